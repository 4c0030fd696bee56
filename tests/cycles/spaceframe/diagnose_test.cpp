// Issue 6's hidden-effect test for the space-frame cycle: a 20 um/m scale error of the X axis,
// hidden in exact simulated data with probe noise, is named with its size within 3 u, the
// location errors come back closer to the truth than the baseline's, and the held-out gain is
// large; clean data (20 seeds, noise 0.5-1.0 um, varied location errors and setup) gives no finding.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "cycles/cycle.hpp"
#include "core/simulation.hpp"
#include "cycles/spaceframe/diagnose.hpp"
#include "core/transforms.hpp"
#include "core/units.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

// The A stroke of ac_trunnion ends short of +45 deg: tilts -90, -45, 0 (27 orientations, 189 centres).
ProbePlan framePlan() { return makePlan("spaceframe", test::acMachine(), {{"phi_list", "-90,-45,0"}}); }

struct Case {
  LocationErrors errors;
  Eigen::Vector3d setup_t_mm, setup_r_rad;
};

// Location errors of Table 4's size and a setup of a few 10 um / mdeg, varied per seed.
Case variedCase(std::uint64_t seed) {
  std::mt19937_64 g(seed * 7919);
  std::normal_distribution<double> n(0.0, 1.0);
  Case c;
  c.errors = test::table4Mean();
  for (int i = 0; i < kNumLocationErrors; ++i) c.errors.values[i] *= 1.0 + 0.5 * n(g);
  c.setup_t_mm = Eigen::Vector3d(n(g), n(g), n(g)) * 0.05;
  c.setup_r_rad = Eigen::Vector3d(n(g), n(g), n(g)) * 1e-3;
  return c;
}

Truth truthOf(const ProbePlan& plan, const Case& c, const Eigen::Vector3d& scale, double noise_um) {
  Truth t = test::truthWith(c.errors);
  t.noise_um = noise_um;
  if (!scale.isZero()) t.linear_axis_error = [scale](const Eigen::Vector3d& p) { return Eigen::Vector3d(scale.cwiseProduct(p)); };
  // The frame's setup as each sphere's true centre: rotation about the frame origin, then shift.
  const SpaceframeLayout l = SpaceframeLayout::fromOptions(plan.options);
  const Eigen::Isometry3d S = Eigen::Translation3d(c.setup_t_mm + l.origin_w_mm) * Da(c.setup_r_rad.x()) *
                              Db(c.setup_r_rad.y()) * Dc(c.setup_r_rad.z()) * Eigen::Translation3d(-l.origin_w_mm);
  for (int s = 1; s <= 7; ++s) {
    const Eigen::Vector3d p = l.origin_w_mm + spaceFrameTable1_mm()[s - 1];
    t.sphere_center_error_w_mm[s] = S * p - p;
  }
  return t;
}

DiagnosisOptions optionsFor(const ProbePlan& plan) {
  DiagnosisOptions o;
  o.prior_sigma_um = plan.machine.probe.repeatability_um;  // 0.7 um
  return o;
}

// Distance of a location-error estimate from the truth, each parameter in units of the extended
// fit's u (one yardstick for both fits: the baseline's own u is inflated by the scale it misses).
double locationMiss(const SpaceframeFit& f, const SpaceframeFit& yardstick, const LocationErrors& truth) {
  double s = 0.0;
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double d = (f.model.errors.values[i] - truth.values[i]) / yardstick.u[i];
    s += d * d;
  }
  return std::sqrt(s);
}

TEST(SpaceframeDiagnosis, HiddenXScaleIsFoundWithItsSize) {
  const ProbePlan plan = framePlan();
  const Case c = variedCase(101);
  const double s_x = 20e-6;  // 20 um/m: 2 um over 100 mm, a typical uncompensated ball screw
  const auto t0 = std::chrono::steady_clock::now();
  const SpaceframeDiagnosis d =
      diagnoseSpaceframe(plan, {simulate(plan, truthOf(plan, c, Eigen::Vector3d(s_x, 0, 0), 0.7), {3})}, optionsFor(plan));
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(d.baseline.converged);
  ASSERT_TRUE(d.candidate.converged);
  // The linearised steps are exact to far below the noise (um, whitened).
  EXPECT_LT(d.candidate.linearisation_um, 1e-3);
  EXPECT_TRUE(d.found) << spaceframeDiagnosisText(d);
  EXPECT_LT(d.baseline_p_value, 1e-3);
  const Eigen::Vector3d s = d.candidate.model.scale, u = d.candidate.u.segment<3>(kNumLocationErrors);
  EXPECT_NEAR(s.x(), s_x, 3 * u.x());
  EXPECT_NEAR(s.y(), 0.0, 3 * u.y());
  EXPECT_NEAR(s.z(), 0.0, 3 * u.z());
  EXPECT_LT(u.x(), 0.25 * s_x);  // the size is really measured, not just within a wide band
  // The baseline absorbs the scale into the location errors; the extended model does not.
  const double miss_b = locationMiss(d.baseline, d.candidate, c.errors), miss_e = locationMiss(d.candidate, d.candidate, c.errors);
  EXPECT_LT(miss_e, miss_b);
  EXPECT_LT(miss_e, 3.0 * std::sqrt(static_cast<double>(kNumLocationErrors)));  // about sqrt(8) u expected
  // The held-out orientations are predicted at least 25 % better (the touch noise alone leaves
  // about 0.5 um per coordinate, the scale error about 1 um more in the baseline).
  EXPECT_GT(d.gain_pct, 25.0);
  std::printf("%s  location miss (in u, 8 parameters): baseline %.1f, extended %.1f; %.1f s\n",
              spaceframeDiagnosisText(d).c_str(), miss_b, miss_e, secs);
  // DIAGNOSIS.json: the finding with the scale and both estimates side by side.
  const Json j = spaceframeDiagnosisJson(d, plan);
  EXPECT_EQ(j["verdict"], "effect_found");
  ASSERT_EQ(j["findings"].size(), 1u);
  EXPECT_EQ(j["findings"][0]["cause"], "linear_axis_scale");
  EXPECT_NEAR(j["findings"][0]["linear_axis_scale"]["X"]["value"].get<double>(), s.x() * 1e6, 1e-5);
  EXPECT_NEAR(j["findings"][0]["parameters"]["scale_X"]["value"].get<double>(), s.x() * 1e6, 1e-5);
  EXPECT_NEAR(j["findings"][0]["location_errors"]["dx_AY"]["value"].get<double>(), mmToUm(d.candidate.model.errors.values[0]), 1e-6);
  EXPECT_TRUE(j["baseline"].contains("location_errors"));
  EXPECT_FALSE(j["baseline"].contains("linear_axis_scale"));
}

TEST(SpaceframeDiagnosis, NoFalseAlarmOnCleanData) {
  const ProbePlan plan = framePlan();
  int alarms = 0, baseline_failed = 0;
  double worst_gain = -1e9;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const double noise = 0.5 + 0.5 * static_cast<double>(seed - 1) / 19.0;  // 0.5 .. 1.0 um
    const SpaceframeDiagnosis d =
        diagnoseSpaceframe(plan, {simulate(plan, truthOf(plan, variedCase(seed), Eigen::Vector3d::Zero(), noise), {seed})},
                           optionsFor(plan));
    alarms += d.found ? 1 : 0;
    baseline_failed += d.baseline_p_value < 1e-3 ? 1 : 0;
    worst_gain = std::max(worst_gain, d.gain_pct);
    EXPECT_FALSE(d.found) << "seed " << seed << ": " << spaceframeDiagnosisText(d);
    // Test (a) alone is calibrated where the noise is within the probe's stated repeatability
    // (0.7 um); beyond it the fits' pooled noise (about 190 dof, +-5 %) only partly catches up
    // and test (b), the held-out gain, is what keeps the verdict clean.
    if (noise <= plan.machine.probe.repeatability_um) {
      EXPECT_GE(d.baseline_p_value, 1e-3) << "seed " << seed;
    }
    EXPECT_LT(d.gain_pct, 100 * d.needed_gain) << "seed " << seed;
  }
  std::printf("20 clean seeds: %d alarms, baseline chi-square failed %d times, largest held-out gain %.1f %%\n", alarms,
              baseline_failed, worst_gain);
}

}  // namespace
}  // namespace rotacal
