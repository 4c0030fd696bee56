#include "cycles/touch154/declared.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "cycles/touch154/uncertainty.hpp"

namespace rotacal {

Touch154Noise touch154DeclaredNoise(const ProbePlan& plan, const ContributorSet* declared) {
  Touch154Noise out;
  out.noise = perTouchDeclaration(declared, plan.machine.probe.repeatability_um);
  for (size_t i = 0; i < plan.points.size(); ++i) out.index_of_id[plan.points[i].id] = static_cast<int>(i);
  LinearChain chain;
  try {
    chain = lineariseChain(plan, LocationErrors{});
  } catch (const std::invalid_argument&) {
    return out;  // no least squares on this plan: the screen falls back to the per-touch scatter
  }
  out.basis = chain.range_lp;
  if (!declared) return out;
  ContributorSet systematic = *declared;
  systematic.items.clear();
  std::string ids;
  for (const Contributor& c : declared->items) {
    if (isPerTouchContributor(*c.info) || c.u.cwiseAbs().maxCoeff() <= 0) continue;
    systematic.items.push_back(c);
    ids += fmt::format("{}{}", ids.empty() ? "" : ", ", c.info->id);
  }
  if (systematic.items.empty()) return out;
  out.noise.structured_um2 = 1e6 * triggerCovariance(chain, systematic);
  out.noise.repeatability_only = false;
  // The same contributors drawn as the budget draws them, for the whole-residual test's null.
  const DrawModel model = drawModel(systematic);
  out.noise.structured_draws_um.resize(chain.points, kTouch154NullDraws);
  RunDraw draw;
  for (int d = 0; d < kTouch154NullDraws; ++d) {
    drawRun(model, chain, kTouch154NullSeed, d, &draw);
    out.noise.structured_draws_um.col(d) = 1e3 * linearisedTriggerChange(chain, draw);
  }
  // What the shared part leaves in the per-point model's residual, per degree of freedom: the
  // set-up's 120 um and the faces' offsets are absorbed, and would read as noise otherwise.
  const Eigen::MatrixXd& Q = out.basis;
  const double dof = static_cast<double>(Q.rows() - Q.cols());
  const double left = dof > 0 ? std::sqrt(std::max(0.0, out.noise.structured_um2.trace() -
                                                           (Q.transpose() * out.noise.structured_um2 * Q).trace()) / dof)
                              : 0.0;
  out.noise.declaration += fmt::format("; shared between touches, to first order: {} (leaving {:.2f} um rms in the "
                                       "residual)", ids, left);
  return out;
}

std::vector<std::pair<int, int>> fittedReadings(const Touch154Noise& n, const std::vector<PointResidual>& residuals) {
  std::vector<std::pair<int, int>> kept;
  for (const auto& p : residuals) {
    if (p.held_out) continue;
    const auto it = n.index_of_id.find(p.point_id);
    if (it == n.index_of_id.end()) throw std::logic_error(fmt::format("declared noise: point {} not in the plan", p.point_id));
    kept.emplace_back(p.run, it->second);
  }
  return kept;
}

FittedReadings fittedProblem(const Touch154Noise& n, const std::vector<PointResidual>& residuals) {
  if (n.basis.size() == 0) throw std::logic_error("declared noise: no model span on this plan");
  const auto kept = fittedReadings(n, residuals);
  FittedReadings f;
  f.residual_um.resize(static_cast<Eigen::Index>(kept.size()));
  f.J.resize(f.residual_um.size(), n.basis.cols());
  Eigen::Index k = 0;
  for (const auto& p : residuals) {
    if (p.held_out) continue;
    f.residual_um[k] = p.residual_um;
    f.J.row(k) = n.basis.row(kept[static_cast<size_t>(k)].second);
    ++k;
  }
  f.covariance_um2 = n.noise.covariance(kept);
  f.null_draws_um = n.noise.nullDraws(kept, kTouch154NullSeed);
  return f;
}

Eigen::VectorXd touch154OutlierStatistic(const Touch154Noise& n, const ScreenedFit& fit) {
  const FittedReadings f = fittedProblem(n, fit.residuals);
  return deletionStatistics(f.residual_um, f.J, f.covariance_um2);
}

}  // namespace rotacal
