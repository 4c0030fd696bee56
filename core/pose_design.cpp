#include "core/pose_design.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "core/require_valid.hpp"

namespace rotacal {

bool PoseDesignOptions::validate(std::string* why) const {
  if (poses < 1) return invalidBecause(why, "poses must be >= 1");
  if (exchange_passes < 0) return invalidBecause(why, "exchange_passes must be >= 0");
  if (!(centre_sd_mm.minCoeff() > 0)) return invalidBecause(why, "centre_sd_mm must be > 0 in X, Y and Z");
  return true;
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

// The subset's candidates' rows, stacked in the subset's order.
Eigen::MatrixXd stackRows(const std::vector<Eigen::MatrixXd>& rows, const std::vector<int>& subset, Eigen::Index columns) {
  Eigen::Index total = 0;
  for (int k : subset) total += rows.at(static_cast<size_t>(k)).rows();
  Eigen::MatrixXd J(total, columns);
  Eigen::Index at = 0;
  for (int k : subset) {
    const Eigen::MatrixXd& R = rows[static_cast<size_t>(k)];
    J.middleRows(at, R.rows()) = R;
    at += R.rows();
  }
  return J;
}

std::vector<int> everyCandidate(size_t n) {
  std::vector<int> all(n);
  for (size_t k = 0; k < n; ++k) all[k] = static_cast<int>(k);
  return all;
}

// Fedorov exchange passes: for every chosen pose c and every candidate k not chosen,
// try_swap(c, k) says whether swapping them gains (and then keeps its own state for the swap);
// the passes end when one gains nothing or after `passes`.
template <class TrySwap>
void exchangePasses(int candidates, int passes, std::vector<int>* chosen, TrySwap try_swap) {
  std::vector<bool> in(static_cast<size_t>(candidates), false);
  for (int k : *chosen) in[static_cast<size_t>(k)] = true;
  for (int pass = 0; pass < passes; ++pass) {
    bool improved = false;
    for (size_t c = 0; c < chosen->size(); ++c)
      for (int k = 0; k < candidates; ++k) {
        if (in[static_cast<size_t>(k)] || !try_swap(c, k)) continue;
        in[static_cast<size_t>((*chosen)[c])] = false;
        in[static_cast<size_t>(k)] = true;
        (*chosen)[c] = k;
        improved = true;
      }
    if (!improved) break;
  }
}

// What no candidate set separates is held, as every fit of the model holds it; the others are
// the free columns, each with its norm over all candidates (its scale: mm and rad weigh alike).
struct FreeColumns {
  Identifiability all;
  std::vector<Eigen::Index> index;
  Eigen::VectorXd scale;
};

FreeColumns freeColumns(const Eigen::MatrixXd& Jall, const std::vector<IdentifiabilityParameter>& names,
                        const std::vector<int>& hold_first) {
  FreeColumns f;
  f.all = identifiability(Jall, names, hold_first);
  for (Eigen::Index i = 0; i < Jall.cols(); ++i)
    if (!f.all.held[static_cast<size_t>(i)]) f.index.push_back(i);
  f.scale.resize(static_cast<Eigen::Index>(f.index.size()));
  for (Eigen::Index k = 0; k < f.scale.size(); ++k) {
    const double n = Jall.col(f.index[static_cast<size_t>(k)]).norm();
    f.scale[k] = n > 0 ? n : 1.0;
  }
  return f;
}

Prepared prepare(const std::vector<Eigen::MatrixXd>& rows, const std::vector<IdentifiabilityParameter>& names,
                 const PoseDesignOptions& o) {
  requireValid(o, "pose design");
  checkRows(rows, names);
  Prepared p;
  const FreeColumns f = freeColumns(stackRows(rows, everyCandidate(rows.size()), static_cast<Eigen::Index>(names.size())),
                                    names, o.hold_first);
  p.all = f.all;
  p.nf = f.scale.size();
  for (const auto& R : rows) {
    Eigen::MatrixXd Rf(R.rows(), p.nf);
    for (Eigen::Index k = 0; k < p.nf; ++k) Rf.col(k) = R.col(f.index[static_cast<size_t>(k)]) / f.scale[k];
    p.info.push_back(Rf.transpose() * Rf);
  }
  return p;
}

// A centre reading per pose: J_X_p whitened by the declared centre noise.
std::vector<Eigen::MatrixXd> centreRows(const KinematicModel& m, const std::vector<Pose>& candidates,
                                        const PoseDesignOptions& o) {
  requireValid(o, "pose design");
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
  exchangePasses(nc, o.exchange_passes, &d.chosen, [&](size_t c, int k) {
    const Eigen::MatrixXd trial = M - info[static_cast<size_t>(d.chosen[c])] + info[static_cast<size_t>(k)];
    const double v = logDet(trial);
    if (!(v > current + 1e-12 * std::max(1.0, std::abs(current)))) return false;
    M = trial;
    current = v;
    return true;
  });
  d.log_det = current;
  const Eigen::MatrixXd Jc = stackRows(candidate_rows, d.chosen, static_cast<Eigen::Index>(names.size()));
  d.identifiability = identifiability(Jc, names, o.hold_first);
  return d;
}

PoseDesign designPoses(const KinematicModel& m, const std::vector<Pose>& candidates, const PoseDesignOptions& o) {
  return designPoses(centreRows(m, candidates, o), modelNames(m), o);
}

bool PoseBudgetOptions::validate(Eigen::Index parameters, std::string* why) const {
  if (exchange_passes < 0) return invalidBecause(why, "exchange_passes must be >= 0");
  if (weight.size() != parameters)
    return invalidBecause(why, fmt::format("weight has {} entries for {} parameters", weight.size(), parameters));
  if (!(weight.minCoeff() >= 0) || !(weight.maxCoeff() > 0))
    return invalidBecause(why, "weight must be >= 0 and count some parameter");
  return true;
}

namespace {

// The candidates stacked once: the free columns, scaled (freeColumns), and each candidate's first
// row and count of rows.
struct BudgetProblem {
  Eigen::MatrixXd J;  // every candidate's rows, free columns, scaled
  Eigen::VectorXd scale;
  std::vector<Eigen::Index> free;
  std::vector<Eigen::Index> first, count;
  Eigen::Index np = 0;
};

BudgetProblem prepareBudget(const std::vector<Eigen::MatrixXd>& rows, const std::vector<IdentifiabilityParameter>& names,
                            const Eigen::MatrixXd& covariance, const PoseBudgetOptions& o) {
  BudgetProblem b;
  b.np = static_cast<Eigen::Index>(names.size());
  if (std::string bad; !o.validate(b.np, &bad)) throw std::invalid_argument("pose design: " + bad);
  checkRows(rows, names);
  Eigen::Index total = 0;
  for (const auto& R : rows) b.first.push_back(total), b.count.push_back(R.rows()), total += R.rows();
  if (covariance.rows() != total || covariance.cols() != total)
    throw std::invalid_argument(fmt::format("pose design: a {} x {} covariance for {} touches", covariance.rows(),
                                            covariance.cols(), total));
  const Eigen::MatrixXd Jall = stackRows(rows, everyCandidate(rows.size()), b.np);
  FreeColumns f = freeColumns(Jall, names, o.hold_first);
  b.free = std::move(f.index);
  b.scale = std::move(f.scale);
  b.J.resize(total, b.scale.size());
  for (Eigen::Index k = 0; k < b.scale.size(); ++k) b.J.col(k) = Jall.col(b.free[static_cast<size_t>(k)]) / b.scale[k];
  return b;
}

// The free parameters' covariance (scaled units) at the subset; false when it does not fix them.
bool subsetCovariance(const BudgetProblem& b, const Eigen::MatrixXd& C, const std::vector<int>& subset,
                      Eigen::MatrixXd* out) {
  std::vector<Eigen::Index> idx;
  for (int k : subset)
    for (Eigen::Index r = 0; r < b.count.at(static_cast<size_t>(k)); ++r) idx.push_back(b.first[static_cast<size_t>(k)] + r);
  const auto m = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd J(m, b.J.cols()), Cs(m, m);
  for (Eigen::Index r = 0; r < m; ++r) {
    J.row(r) = b.J.row(idx[static_cast<size_t>(r)]);
    for (Eigen::Index q = 0; q < m; ++q) Cs(r, q) = C(idx[static_cast<size_t>(r)], idx[static_cast<size_t>(q)]);
  }
  const Eigen::MatrixXd M = J.transpose() * J;
  const Eigen::LLT<Eigen::MatrixXd> llt(M);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::VectorXd d = llt.matrixL().toDenseMatrix().diagonal();
  if (d.minCoeff() <= 1e-6 * d.maxCoeff()) return false;
  const Eigen::MatrixXd A = llt.solve(J.transpose());  // (J^T J)^-1 J^T
  *out = A * Cs * A.transpose();
  return true;
}

double budgetOf(const BudgetProblem& b, const Eigen::MatrixXd& cov_scaled, const Eigen::VectorXd& weight) {
  double f = 0.0;
  for (Eigen::Index k = 0; k < b.scale.size(); ++k)
    f += weight[b.free[static_cast<size_t>(k)]] * cov_scaled(k, k) / (b.scale[k] * b.scale[k]);
  return f;
}

}  // namespace

Eigen::MatrixXd poseSetCovariance(const std::vector<Eigen::MatrixXd>& rows, const std::vector<IdentifiabilityParameter>& names,
                                  const Eigen::MatrixXd& covariance, const std::vector<int>& subset,
                                  const PoseBudgetOptions& o) {
  const BudgetProblem b = prepareBudget(rows, names, covariance, o);
  Eigen::MatrixXd cov;
  if (!subsetCovariance(b, covariance, subset, &cov))
    throw std::invalid_argument("pose design: the subset does not fix the parameters the candidates separate");
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(b.np, b.np);
  for (Eigen::Index i = 0; i < b.scale.size(); ++i)
    for (Eigen::Index j = 0; j < b.scale.size(); ++j)
      out(b.free[static_cast<size_t>(i)], b.free[static_cast<size_t>(j)]) = cov(i, j) / (b.scale[i] * b.scale[j]);
  return out;
}

double poseSetBudget(const std::vector<Eigen::MatrixXd>& rows, const std::vector<IdentifiabilityParameter>& names,
                     const Eigen::MatrixXd& covariance, const std::vector<int>& subset, const PoseBudgetOptions& o) {
  const BudgetProblem b = prepareBudget(rows, names, covariance, o);
  Eigen::MatrixXd cov;
  if (!subsetCovariance(b, covariance, subset, &cov)) return std::numeric_limits<double>::infinity();
  return budgetOf(b, cov, o.weight);
}

PoseDesign refinePosesForBudget(const std::vector<Eigen::MatrixXd>& rows, const std::vector<IdentifiabilityParameter>& names,
                                const Eigen::MatrixXd& covariance, const std::vector<int>& start,
                                const PoseBudgetOptions& o) {
  const BudgetProblem b = prepareBudget(rows, names, covariance, o);
  const int nc = static_cast<int>(rows.size());
  std::vector<bool> seen(static_cast<size_t>(nc), false);
  for (int k : start) {
    if (k < 0 || k >= nc || seen[static_cast<size_t>(k)])
      throw std::invalid_argument(fmt::format("pose design: start pose {} is not a distinct candidate of {}", k, nc));
    seen[static_cast<size_t>(k)] = true;
  }
  auto value = [&](const std::vector<int>& S) {
    Eigen::MatrixXd cov;
    return subsetCovariance(b, covariance, S, &cov) ? budgetOf(b, cov, o.weight) : std::numeric_limits<double>::infinity();
  };
  PoseDesign d;
  d.chosen = start;
  double current = value(d.chosen);
  if (!std::isfinite(current))
    throw std::invalid_argument("pose design: the start poses do not fix the parameters the candidates separate");
  exchangePasses(nc, o.exchange_passes, &d.chosen, [&](size_t c, int k) {
    std::vector<int> trial = d.chosen;
    trial[c] = k;
    const double v = value(trial);
    if (!(v < current * (1.0 - 1e-12))) return false;
    current = v;
    return true;
  });
  d.budget = current;
  const Eigen::MatrixXd Jc = stackRows(rows, d.chosen, b.np);
  d.identifiability = identifiability(Jc, names, o.hold_first);
  return d;
}

}  // namespace rotacal
