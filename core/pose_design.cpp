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

double logDet(const Eigen::MatrixXd& M) {
  const Eigen::LLT<Eigen::MatrixXd> llt(M);
  if (llt.info() != Eigen::Success) return -std::numeric_limits<double>::infinity();
  const Eigen::VectorXd d = llt.matrixL().toDenseMatrix().diagonal();
  if (d.minCoeff() <= 1e-12 * d.maxCoeff()) return -std::numeric_limits<double>::infinity();
  return 2.0 * d.array().log().sum();
}

// The candidates' information per pose over the parameters they can separate, columns scaled by
// their norms over all candidates.
struct Prepared {
  Identifiability all;
  Eigen::Index nf = 0;
  std::vector<Eigen::MatrixXd> info;
};

void checkRows(const std::vector<Eigen::MatrixXd>& rows, const std::vector<IdentifiabilityParameter>& names) {
  for (const auto& R : rows)
    if (R.cols() != static_cast<Eigen::Index>(names.size()))
      throw std::invalid_argument(fmt::format("pose design: a candidate has {} columns for {} parameters", R.cols(), names.size()));
}

Prepared prepare(const std::vector<Eigen::MatrixXd>& rows, const std::vector<IdentifiabilityParameter>& names,
                 const PoseDesignOptions& o) {
  if (const std::string bad = o.validate(); !bad.empty()) throw std::invalid_argument("pose design: " + bad);
  checkRows(rows, names);
  Prepared p;
  const auto np = static_cast<Eigen::Index>(names.size());
  Eigen::Index total = 0;
  for (const auto& R : rows) total += R.rows();
  Eigen::MatrixXd Jall(total, np);
  Eigen::Index at = 0;
  for (const auto& R : rows) Jall.middleRows(at, R.rows()) = R, at += R.rows();
  // What no candidate set separates is held, as every fit of the model holds it.
  p.all = identifiability(Jall, names, o.hold_first);
  Eigen::VectorXd scale(np);
  for (Eigen::Index i = 0; i < np; ++i) scale[i] = Jall.col(i).norm() > 0 ? Jall.col(i).norm() : 1.0;
  std::vector<Eigen::Index> free;
  for (Eigen::Index i = 0; i < np; ++i)
    if (!p.all.held[static_cast<size_t>(i)]) free.push_back(i);
  p.nf = static_cast<Eigen::Index>(free.size());
  for (const auto& R : rows) {
    Eigen::MatrixXd Rf(R.rows(), p.nf);
    for (Eigen::Index k = 0; k < p.nf; ++k) Rf.col(k) = R.col(free[static_cast<size_t>(k)]) / scale[free[static_cast<size_t>(k)]];
    p.info.push_back(Rf.transpose() * Rf);
  }
  return p;
}

// A centre reading per pose: J_X_p whitened by the declared centre noise.
std::vector<Eigen::MatrixXd> centreRows(const KinematicModel& m, const std::vector<Pose>& candidates,
                                        const PoseDesignOptions& o) {
  if (const std::string bad = o.validate(); !bad.empty()) throw std::invalid_argument("pose design: " + bad);
  std::vector<Eigen::MatrixXd> rows;
  for (const auto& pose : candidates)
    rows.emplace_back(o.centre_sd_mm.cwiseInverse().asDiagonal() * J_X_p(m, Eigen::VectorXd::Zero(m.size()), pose));
  return rows;
}

std::vector<IdentifiabilityParameter> modelNames(const KinematicModel& m) {
  std::vector<IdentifiabilityParameter> names;
  for (const auto& q : m.parameters) names.push_back({q.name, q.kind});
  return names;
}

}  // namespace

double poseSetLogDet(const std::vector<Eigen::MatrixXd>& candidate_rows, const std::vector<IdentifiabilityParameter>& names,
                     const std::vector<int>& subset, const PoseDesignOptions& o) {
  const Prepared p = prepare(candidate_rows, names, o);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(p.nf, p.nf);
  for (int k : subset) M += p.info.at(static_cast<size_t>(k));
  return logDet(M);
}

double poseSetLogDet(const KinematicModel& m, const std::vector<Pose>& candidates, const std::vector<int>& subset,
                     const PoseDesignOptions& o) {
  return poseSetLogDet(centreRows(m, candidates, o), modelNames(m), subset, o);
}

PoseDesign designPoses(const std::vector<Eigen::MatrixXd>& candidate_rows, const std::vector<IdentifiabilityParameter>& names,
                       const PoseDesignOptions& o) {
  const int nc = static_cast<int>(candidate_rows.size());
  if (nc < o.poses)
    throw std::invalid_argument(fmt::format("pose design: {} poses asked from {} candidates", o.poses, nc));
  const Prepared p = prepare(candidate_rows, names, o);
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
  Eigen::Index total = 0;
  for (int k : d.chosen) total += candidate_rows[static_cast<size_t>(k)].rows();
  Eigen::MatrixXd Jc(total, static_cast<Eigen::Index>(names.size()));
  Eigen::Index at = 0;
  for (int k : d.chosen) {
    const Eigen::MatrixXd& R = candidate_rows[static_cast<size_t>(k)];
    Jc.middleRows(at, R.rows()) = R;
    at += R.rows();
  }
  d.identifiability = identifiability(Jc, names, o.hold_first);
  return d;
}

PoseDesign designPoses(const KinematicModel& m, const std::vector<Pose>& candidates, const PoseDesignOptions& o) {
  return designPoses(centreRows(m, candidates, o), modelNames(m), o);
}

}  // namespace rotacal
