#include "cycles/one_sphere/budget.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>

#include "core/contributor_draw.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/one_sphere/plan.hpp"

namespace rotacal {

UncertaintyBudget sphereBudget(const ProbePlan& plan, const SphereCycleResult& r, const ContributorSet* contributors,
                               const BudgetOptions& options) {
  options.validateOrThrow();
  UncertaintyBudget b;
  std::vector<Eigen::Index> free;
  for (size_t i = 0; i < r.names.size(); ++i)
    if (!r.identifiability.held[i]) free.push_back(static_cast<Eigen::Index>(i));
  const auto n = static_cast<Eigen::Index>(free.size());
  const auto touches = static_cast<Eigen::Index>(r.residuals_um.size());
  Eigen::VectorXd f(n);
  Eigen::MatrixXd Jf(touches, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto& q = r.names[static_cast<size_t>(free[static_cast<size_t>(k)])];
    b.names.push_back(q.name);
    b.units.emplace_back(reportUnit(q.kind));
    f[k] = q.kind == ParamKind::Length ? mmToUm(1.0) : radToMdeg(1.0);
    Jf.col(k) = r.J_r_x.col(free[static_cast<size_t>(k)]);
  }
  // The fit linearised at its solution: a trigger moved by ds_j along its approach u_j changes
  // its residual by (n_j . u_j) ds_j; x moves by -pinv(J) of that, the residual by (I - J pinv(J)).
  const Eigen::MatrixXd pinv = Jf.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::VectorXd nu(touches);
  for (Eigen::Index j = 0; j < touches; ++j)
    nu[j] = r.normals[static_cast<size_t>(j)].dot(
        plan.points[static_cast<size_t>(r.point_index[static_cast<size_t>(j)])].approach_m);
  const Eigen::MatrixXd G = -(f.asDiagonal() * pinv * nu.asDiagonal());
  const Eigen::MatrixXd residual_map = (Eigen::MatrixXd::Identity(touches, touches) - Jf * pinv) * nu.asDiagonal();

  const ContributorSplit split = contributors ? splitContributors(*contributors, isPerTouchContributor, isProbeAxesContributor)
                                              : ContributorSplit{};
  const ContributorSet& type_b = split.type_b;
  // Every trigger of every run moves as its plan point does: the contributors are the machine's.
  // The identified machine: the fitted model's own exact chains (its table chain ends with the
  // sphere's set-up), the same on a tilting table and under a head.
  const KinematicModel& m = r.model;
  const Truth base = truthOfModel(m, r.x.head(m.size()));
  const Eigen::VectorXd ideal = type_b.items.empty() ? Eigen::VectorXd() : triggersAlong(plan, base);
  const auto shift = [&](std::uint64_t seed, int run, int only, ProbeAxesDraw* drawn = nullptr) {
    ProbeAxesDraw d;
    drawProbeAxes(plan, type_b, isProbeAxesContributor, seed, run, only, &d);
    if (drawn) *drawn = d;
    Truth t = base;
    applyProbeAxesDraw(d, &t);
    const Eigen::VectorXd s = triggersAlong(plan, t) - ideal;
    Eigen::VectorXd stacked(touches);
    for (Eigen::Index j = 0; j < touches; ++j) stacked[j] = s[r.point_index[static_cast<size_t>(j)]];
    return stacked;
  };

  const double declared_um2 = contributors ? mmToUm(1.0) * mmToUm(1.0) * split.per_reading_mm2
                                           : std::pow(plan.machine.probe.repeatability_um, 2);
  std::vector<double> sys_um2;
  if (!type_b.items.empty() && r.dof > 0)
    sys_um2 = contributorResidualVariances(200, options.seed, [&](std::uint64_t seed, int k) {
      return mmToUm(1.0) * mmToUm(1.0) * (residual_map * shift(seed, k, -1)).squaredNorm() / r.dof;
    });
  const ReadingScatter scatter = readingScatter(declared_um2, r.residual_sd_um * r.residual_sd_um, r.dof, sys_um2);
  Eigen::MatrixXd cov(n, n);
  for (Eigen::Index a = 0; a < n; ++a)
    for (Eigen::Index c = 0; c < n; ++c) cov(a, c) = r.cov_per_sigma2(free[static_cast<size_t>(a)], free[static_cast<size_t>(c)]);
  b.cov_a = umToMm(1.0) * umToMm(1.0) * scatter.variance_um2 * f.asDiagonal() * cov * f.asDiagonal();
  b.cov_b = Eigen::MatrixXd::Zero(n, n);
  b.type_a_source = fmt::format("the per-touch scatter {:.3f} um ({}; declared: {}) through the one-stage fit of every touch",
                                std::sqrt(scatter.variance_um2), scatter.why,
                                contributors ? "probe repeatability and surface roughness" : "the machine's probe repeatability");
  b.terms.push_back({"data", b.uA()});
  const std::string left_out = leftOutNote("one sphere", split.left_out);
  if (typeBToRun(&b, contributors != nullptr, !type_b.items.empty(), "the one-sphere cycle", left_out)) {
    // A fitted squareness measures the drawn one: its error is what the fit leaves of the draw.
    const Eigen::Index no = -1;
    Eigen::Index s_xy = no, s_xz = no, s_yz = no;
    for (Eigen::Index k = 0; k < n; ++k) {
      const std::string& q = b.names[static_cast<size_t>(k)];
      if (q == "S_xy") s_xy = k;
      if (q == "S_xz") s_xz = k;
      if (q == "S_yz") s_yz = k;
    }
    runTypeB(&b, type_b, options, [&](std::uint64_t seed, int run, int c) -> Eigen::VectorXd {
      ProbeAxesDraw d;
      Eigen::VectorXd dx = G * shift(seed, run, c, &d);
      if (d.linear) {
        if (s_xy != no) dx[s_xy] -= f[s_xy] * d.linear_errors.S_xy;
        if (s_xz != no) dx[s_xz] -= f[s_xz] * d.linear_errors.S_xz;
        if (s_yz != no) dx[s_yz] -= f[s_yz] * d.linear_errors.S_yz;
      }
      return dx;
    });
    b.type_b_source = typeBDrawnSource(type_b.items.size(), *contributors,
                                       "the exact simulator (full HTMs, exact ball-on-sphere contact) around the "
                                       "identified errors, the triggers' deviations run through the fit linearised there",
                                       options, left_out);
  }
  return b;
}

}  // namespace rotacal
