// The spaceframe budget (issue 17): the linearised estimator against analyzeSpaceframe run by run;
// a contributor the model fits (a pure linear scale) costs nothing, because the drawn scale is
// the truth of the fitted one; u_A against the scatter of the estimates over repeated noisy
// measurements of one machine; the frame's calibration enters u_B only for a calibrated frame.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/contributors.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/spaceframe/budget.hpp"
#include "contributor_test_util.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

// A small map (two tilts) so that each analysis takes a few tens of ms.
ProbePlan smallPlan(const CycleOptions& extra = {}) {
  CycleOptions o = {{"phi_list", "-90,0"}, {"theta_list", "0,90,180,270"}};
  for (const auto& kv : extra) o[kv.first] = kv.second;
  return makePlan("spaceframe", test::acMachine(), o);
}

Truth someTruth(const ProbePlan& plan) {
  Truth t = test::truthWith(test::table4Mean());
  FrameModel setup;
  setup.setup_translation_mm = Eigen::Vector3d(0.03, -0.02, 0.01);
  setup.setup_rotation_rad = Eigen::Vector3d(mdegToRad(3), mdegToRad(-2), mdegToRad(4));
  const Eigen::Vector3d origin = SpaceframeLayout::fromOptions(plan.options).origin_w_mm;
  for (const auto& p : plan.points)
    t.sphere_center_error_w_mm[p.sphere->id] = setup.placedCentre_w(p.sphere->center_w_mm, p.sphere->id, origin) -
                                               p.sphere->center_w_mm;
  return t;
}

Contributor item(const char* id, double u_internal) { return test::contributorItem(id, u_internal); }

TEST(SpaceframeBudget, LinearisedDeviationMatchesTheExactEstimator) {
  const ProbePlan plan = smallPlan();
  const SpaceframeAnalysis a = analyzeSpaceframe(plan, {simulate(plan, someTruth(plan), {1})});
  const ContributorSet cs = *test::acMachine().contributors;  // 000 Table 5
  const SpaceframeLinearMap lin = linearSpaceframe(plan, a);
  const Truth base = spaceframeIdentifiedTruth(plan, a);
  const Eigen::VectorXd x0 = spaceframeBudgetValues(plan, a);
  double worst = 0.0, size = 0.0;
  for (int run = 0; run < 6; ++run) {
    ProbeAxesDraw d;
    drawProbeAxes(plan, cs, spaceframeTypeB, 7, run, -1, &d);
    Truth t = base;
    applyProbeAxesDraw(d, &t);
    const MeasurementRun sim = simulate(plan, t, {1});
    Eigen::VectorXd ds(static_cast<Eigen::Index>(plan.points.size()));
    for (Eigen::Index i = 0; i < ds.size(); ++i)
      ds[i] = alongApproach(plan.points[static_cast<size_t>(i)], sim.points[static_cast<size_t>(i)]) - lin.ideal_s_mm[i];
    const Eigen::VectorXd exact = spaceframeBudgetValues(plan, analyzeSpaceframe(plan, {sim})) - x0;
    const Eigen::VectorXd linear = lin.G * ds;
    for (Eigen::Index i = 0; i < exact.size(); ++i) {
      // Relative to each parameter's own size of change: um, mdeg and um/m differ by orders.
      worst = std::max(worst, std::abs(exact[i] - linear[i]) / std::max(0.05, std::abs(exact[i])));
      if (i < kNumLocationErrors) size = std::max(size, std::abs(exact[i]));
    }
  }
  EXPECT_GT(size, 0.5);   // the draws move the location errors by um
  EXPECT_LT(worst, 0.02);  // the linearisation agrees to 2 % (or 1 nm / 1 urad-scale floor)
}

TEST(SpaceframeBudget, AScaleTheModelFitsCostsNothing) {
  // A pure linear scale of X is in the model: the estimate follows the truth and nothing else
  // moves. Without the drawn scale counted as the truth, u_B(scale_X) would be the whole u.
  const ProbePlan plan = smallPlan();
  const SpaceframeAnalysis a = analyzeSpaceframe(plan, {simulate(plan, someTruth(plan), {1})});
  ContributorSet cs;
  const double u = 10e-6;  // 10 um/m
  Contributor c = item("E_xx_lin", 0.0);
  c.u = Eigen::Vector3d(u, u, u);
  cs.items = {c};
  SpaceframeBudgetOptions o;
  o.runs = 200;
  o.alone_runs = 0;
  const UncertaintyBudget b = spaceframeBudget(plan, a, {}, &cs, o);
  ASSERT_TRUE(b.type_b_evaluated);
  const Eigen::VectorXd ub = b.uB();
  for (int i = 0; i < b.size(); ++i) EXPECT_LT(ub[i], 0.02) << b.names[static_cast<size_t>(i)];
  // A random error of X (not in the model) is not free.
  Contributor r = item("E_xx_rand", umToMm(2.0));
  cs.items = {r};
  const UncertaintyBudget br = spaceframeBudget(plan, a, {}, &cs, o);
  EXPECT_GT(br.uB()[kNumLocationErrors], 1.0);  // scale_X, um/m
}

TEST(SpaceframeBudget, TypeAMatchesTheScatterOfRepeatedMeasurements) {
  // One machine measured 40 times with 1 um of noise per touch: the estimates' scatter is what
  // u_A claims (declared repeatability 1 um, nothing else).
  const ProbePlan plan = smallPlan();
  Truth t = someTruth(plan);
  t.noise_um = 1.0;
  ContributorSet cs;
  cs.items = {item("probe_repeatability", umToMm(1.0))};
  std::vector<Eigen::VectorXd> est;
  UncertaintyBudget b;
  for (int k = 0; k < 40; ++k) {
    const SpaceframeAnalysis a = analyzeSpaceframe(plan, {simulate(plan, t, {static_cast<std::uint64_t>(k) + 11})});
    est.push_back(spaceframeBudgetValues(plan, a));
    if (k == 0) {
      SpaceframeBudgetOptions o;
      o.runs = 100;
      b = spaceframeBudget(plan, a, {}, &cs, o);
    }
  }
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(est.front().size());
  for (const auto& e : est) mean += e / 40.0;
  Eigen::VectorXd var = Eigen::VectorXd::Zero(mean.size());
  for (const auto& e : est) var += (e - mean).cwiseAbs2() / 39.0;
  const Eigen::VectorXd ua = b.uA();
  for (int i = 0; i < b.size(); ++i) {
    const double ratio = std::sqrt(var[i]) / ua[i];
    // 39 dof: the sample sd is within +-25 % of the truth with about 99 % probability per parameter.
    EXPECT_GT(ratio, 0.7) << b.names[static_cast<size_t>(i)];
    EXPECT_LT(ratio, 1.3) << b.names[static_cast<size_t>(i)];
  }
  EXPECT_LT(b.uB().maxCoeff(), 1e-12);  // nothing Type B was declared
}

TEST(SpaceframeBudget, TheFrameCalibrationMatchesTheExactSensitivityAndCountsOnlyForACalibratedFrame) {
  // The frame's spheres each sit N(0, u^2) per coordinate off their calibration. Another route to
  // the same u_B: move each of the 21 coordinates by 1 um, re-measure and re-analyze exactly, and
  // sum the squared changes (the estimator is linear at um scale).
  const double u_um = 2.0;
  const ProbePlan calibrated = smallPlan({{"frame_u_um", fmt::format("{:g}", u_um)}});
  const Truth truth = someTruth(calibrated);
  const SpaceframeAnalysis a = analyzeSpaceframe(calibrated, {simulate(calibrated, truth, {1})});
  const Eigen::VectorXd x0 = spaceframeBudgetValues(calibrated, a);
  Eigen::VectorXd var = Eigen::VectorXd::Zero(x0.size());
  for (int s = 1; s <= 7; ++s)
    for (int k = 0; k < 3; ++k) {
      Truth t = truth;
      t.sphere_center_error_w_mm[s][k] += umToMm(1.0);
      const Eigen::VectorXd dx = spaceframeBudgetValues(calibrated, analyzeSpaceframe(calibrated, {simulate(calibrated, t, {1})})) - x0;
      var += (u_um * dx).cwiseAbs2();
    }
  ContributorSet none;
  SpaceframeBudgetOptions o;
  o.runs = 4000;
  o.alone_runs = 100;
  const UncertaintyBudget b = spaceframeBudget(calibrated, a, {}, &none, o);
  ASSERT_TRUE(b.type_b_evaluated);
  bool named = false;
  for (const auto& term : b.terms) named |= term.contributor == kFrameCalibrationContributor;
  EXPECT_TRUE(named);
  const Eigen::VectorXd ub = b.uB();
  int compared = 0;
  for (int i = 0; i < b.size(); ++i) {
    const double exact = std::sqrt(var[i]);
    if (exact < 1e-3) continue;
    // 4000 runs: the Monte Carlo's sd is within about 3.5 % (3 sigma) of the truth.
    EXPECT_NEAR(ub[i], exact, 0.05 * exact) << b.names[static_cast<size_t>(i)];
    ++compared;
  }
  EXPECT_GE(compared, kNumLocationErrors);
  // The frame's own u is 0: nothing acts.
  const ProbePlan exact_frame = smallPlan();
  const UncertaintyBudget b0 = spaceframeBudget(
      exact_frame, analyzeSpaceframe(exact_frame, {simulate(exact_frame, someTruth(exact_frame), {1})}), {}, &none, o);
  EXPECT_LT(b0.uB().maxCoeff(), 1e-12);
}

}  // namespace
}  // namespace rotacal
