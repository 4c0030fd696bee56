#include "core/pose_design.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rotacal {

std::string PoseDesignOptions::validate() const {
  if (poses < 1) return "poses must be >= 1";
  if (exchange_passes < 0) return "exchange_passes must be >= 0";
  if (!(centre_sd_mm.minCoeff() > 0)) return "centre_sd_mm must be > 0 in X, Y and Z";
  return {};
}

namespace {

// The whitened, scaled rows of one pose over the free parameters.
Eigen::MatrixXd poseRows(const KinematicModel& m, const Pose& pose, const std::vector<int>& free,
                         const Eigen::Vector3d& sd_mm, const Eigen::VectorXd& scale) {
  const auto J = J_X_p(m, Eigen::VectorXd::Zero(m.size()), pose);
  Eigen::MatrixXd rows(3, static_cast<Eigen::Index>(free.size()));
  for (size_t k = 0; k < free.size(); ++k)
    rows.col(static_cast<Eigen::Index>(k)) = J.col(free[k]).cwiseQuotient(sd_mm) / scale[free[k]];
  return rows;
}

double logDet(const Eigen::MatrixXd& M) {
  const Eigen::LLT<Eigen::MatrixXd> llt(M);
  if (llt.info() != Eigen::Success) return -std::numeric_limits<double>::infinity();
  const Eigen::VectorXd d = llt.matrixL().toDenseMatrix().diagonal();
  if (d.minCoeff() <= 1e-12 * d.maxCoeff()) return -std::numeric_limits<double>::infinity();
  return 2.0 * d.array().log().sum();
}

// The candidates' information per pose over the parameters they can separate.
struct Prepared {
  std::vector<IdentifiabilityParameter> names;
  Identifiability all;
  Eigen::Index nf = 0;
  std::vector<Eigen::MatrixXd> info;
};

Prepared prepare(const KinematicModel& m, const std::vector<Pose>& candidates, const PoseDesignOptions& o) {
  if (const std::string bad = o.validate(); !bad.empty()) throw std::invalid_argument("pose design: " + bad);
  Prepared p;
  const auto nc = static_cast<Eigen::Index>(candidates.size());
  for (const auto& q : m.parameters) p.names.push_back({q.name, q.kind});
  Eigen::MatrixXd Jall(3 * nc, m.size());
  for (Eigen::Index k = 0; k < nc; ++k)
    Jall.middleRows(3 * k, 3) = J_X_p(m, Eigen::VectorXd::Zero(m.size()), candidates[static_cast<size_t>(k)]);
  // What no candidate set separates is held, as every fit of the model holds it.
  p.all = identifiability(Jall, p.names, o.hold_first);
  Eigen::VectorXd scale(m.size());
  for (int i = 0; i < m.size(); ++i) scale[i] = Jall.col(i).norm() > 0 ? Jall.col(i).norm() : 1.0;
  std::vector<int> free;
  for (int i = 0; i < m.size(); ++i)
    if (!p.all.held[static_cast<size_t>(i)]) free.push_back(i);
  p.nf = static_cast<Eigen::Index>(free.size());
  for (const auto& pose : candidates) {
    const Eigen::MatrixXd R = poseRows(m, pose, free, o.centre_sd_mm, scale);
    p.info.push_back(R.transpose() * R);
  }
  return p;
}

}  // namespace

double poseSetLogDet(const KinematicModel& m, const std::vector<Pose>& candidates, const std::vector<int>& subset,
                     const PoseDesignOptions& o) {
  const Prepared p = prepare(m, candidates, o);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(p.nf, p.nf);
  for (int k : subset) M += p.info.at(static_cast<size_t>(k));
  return logDet(M);
}

PoseDesign designPoses(const KinematicModel& m, const std::vector<Pose>& candidates, const PoseDesignOptions& o) {
  const int nc = static_cast<int>(candidates.size());
  if (nc < o.poses)
    throw std::invalid_argument(fmt::format("pose design: {} poses asked from {} candidates", o.poses, nc));
  const Prepared p = prepare(m, candidates, o);
  const Eigen::Index nf = p.nf;
  const std::vector<Eigen::MatrixXd>& info = p.info;
  // Greedy forward selection on the information regularised until it is of full rank, then
  // exchange passes on the true log det: swap a chosen pose for another while it gains.
  const double ridge = 1e-6 * static_cast<double>(nc);
  PoseDesign d;
  std::vector<bool> in(static_cast<size_t>(nc), false);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(nf, nf);
  for (int s = 0; s < o.poses; ++s) {
    int best = -1;
    double best_v = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < nc; ++k) {
      if (in[static_cast<size_t>(k)]) continue;
      const double v = logDet(M + info[static_cast<size_t>(k)] + ridge * Eigen::MatrixXd::Identity(nf, nf));
      if (v > best_v) best_v = v, best = k;
    }
    in[static_cast<size_t>(best)] = true;
    d.chosen.push_back(best);
    M += info[static_cast<size_t>(best)];
  }
  double current = logDet(M);
  for (int pass = 0; pass < o.exchange_passes; ++pass) {
    bool improved = false;
    for (size_t c = 0; c < d.chosen.size(); ++c)
      for (int k = 0; k < nc; ++k) {
        if (in[static_cast<size_t>(k)]) continue;
        const Eigen::MatrixXd trial = M - info[static_cast<size_t>(d.chosen[c])] + info[static_cast<size_t>(k)];
        const double v = logDet(trial);
        if (v > current + 1e-12 * std::max(1.0, std::abs(current))) {
          in[static_cast<size_t>(d.chosen[c])] = false;
          in[static_cast<size_t>(k)] = true;
          d.chosen[c] = k;
          M = trial;
          current = v;
          improved = true;
        }
      }
    if (!improved) break;
  }
  d.log_det = current;
  Eigen::MatrixXd Jc(3 * static_cast<Eigen::Index>(d.chosen.size()), m.size());
  for (size_t k = 0; k < d.chosen.size(); ++k) {
    const Eigen::Matrix<double, 3, Eigen::Dynamic> J = J_X_p(m, Eigen::VectorXd::Zero(m.size()), candidates[static_cast<size_t>(d.chosen[k])]);
    Jc.middleRows(3 * static_cast<Eigen::Index>(k), 3) = o.centre_sd_mm.cwiseInverse().asDiagonal() * J;
  }
  d.identifiability = identifiability(Jc, p.names, o.hold_first);
  return d;
}

}  // namespace rotacal
