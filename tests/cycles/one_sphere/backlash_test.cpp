// The rotary axes' lost motion (issue 19 item 2: "backlash of each rotary axis measured by
// approaching each pose from both sides, reported with its uncertainty"), closed on the exact
// simulator, whose rule (actual = commanded - d b / 2, d the way the axis last moved from a start
// at 0 reached in +) the fit never sees: the fit reads the directions from the plan alone and
// carries the first visit's offset as a parameter of its own.
//  - the directions per point against a hand-worked order;
//  - noise-free triggers give back each axis's lost motion and the location errors exactly, and
//    a fit without the term reads the same lost motion as location errors;
//  - with the probe's repeatability, the lost motion lies within k = 2 u of the truth as often
//    as k = 2 claims (200 machines), u from the fit's covariance and the declared noise;
//  - a there-and-back plan's programs pass the program verifier in every dialect.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "controllers/dialect.hpp"
#include "controllers/motion_reader.hpp"
#include "core/rotary_backlash.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/check_rules.hpp"
#include "cycles/one_sphere/analyze.hpp"
#include "cycles/one_sphere/plan.hpp"
#include "postproc/program_check.hpp"
#include "test_util.hpp"
#include "tests/cycles/verify_programs.hpp"

namespace rotacal {
namespace {

MachineModel acMachine() { return loadMachine(test::sourcePath("examples/machines/ac_trunnion.json")); }

Eigen::Index indexOf(const SphereCycleResult& r, const std::string& name) {
  for (size_t i = 0; i < r.names.size(); ++i)
    if (r.names[i].name == name) return static_cast<Eigen::Index>(i);
  ADD_FAILURE() << name << " is not fitted";
  return 0;
}

// 10 arcsec on the tilt axis (a worn worm gear), 5 mdeg on C.
const double kBacklashA_mdeg = 10.0 / 3.6, kBacklashC_mdeg = 5.0;

Truth backlashTruth() {
  Truth t = test::truthWith(test::table4Mean());
  t.rotary_backlash_deg = Eigen::Vector3d(kBacklashA_mdeg, 0.0, kBacklashC_mdeg) * 1e-3;
  return t;
}

TEST(RotaryApproachDirections, ReadFromThePlansOrder) {
  ProbePlan plan;
  // A: 0, -30, -30, 0, 0 ; C: 90, 90, 0, 0, 180 (one touch per pose)
  const double a[] = {0, -30, -30, 0, 0}, c[] = {90, 90, 0, 0, 180};
  for (int k = 0; k < 5; ++k) {
    ProbePoint p;
    p.id = k + 1;
    p.pose = Pose{a[k], 0.0, c[k]};
    plan.points.push_back(p);
  }
  const auto known = rotaryApproachDirections(plan, false);
  const auto from0 = rotaryApproachDirections(plan, true);
  const double wantA[] = {0, -1, -1, 1, 1}, wantC[] = {0, 0, -1, -1, 1};
  const double wantA0[] = {1, -1, -1, 1, 1}, wantC0[] = {1, 1, -1, -1, 1};
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(known[static_cast<size_t>(k)][0], wantA[k]) << k;
    EXPECT_EQ(known[static_cast<size_t>(k)][2], wantC[k]) << k;
    EXPECT_EQ(known[static_cast<size_t>(k)][1], 0.0) << k;  // B never moves, from nowhere known
    EXPECT_EQ(from0[static_cast<size_t>(k)][0], wantA0[k]) << k;
    EXPECT_EQ(from0[static_cast<size_t>(k)][2], wantC0[k]) << k;
    EXPECT_EQ(from0[static_cast<size_t>(k)][1], 1.0) << k;
  }
}

TEST(OneSphereBacklash, ThereAndBackGivesEachAxisLostMotionExactly) {
  const MachineModel m = acMachine();
  const ProbePlan plan = makePlan("one_sphere", m, {{"backlash", "1"}});
  const ProbePlan plain = makePlan("one_sphere", m, {});
  ASSERT_EQ(plan.poses.size(), 2 * plain.poses.size() - 1);
  EXPECT_EQ(plan.poses.back().name, plain.poses.front().name + "R");
  const Truth truth = backlashTruth();
  const SphereCycleResult r = identifySphereCycle(plan, {simulate(plan, truth, {1})});
  ASSERT_TRUE(r.summary.usable()) << r.summary.briefReport();
  EXPECT_LT(r.residual_sd_um, 1e-6);
  EXPECT_NEAR(radToMdeg(r.x[indexOf(r, "backlash_A")]), kBacklashA_mdeg, 1e-6);
  EXPECT_NEAR(radToMdeg(r.x[indexOf(r, "backlash_C")]), kBacklashC_mdeg, 1e-6);
  const LocationErrors want = test::table4Mean();
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const bool len = locationParameters(m.kinematics)[static_cast<size_t>(i)].kind == ParamKind::Length;
    // The papers' parameters are the model's to first order (analyze_test: within 0.01 um /
    // 0.001 mdeg with these errors); the lost motion is the model's own and exact above.
    EXPECT_NEAR(r.location.reportValue(i), want.reportValue(i), len ? 0.01 : 0.001)
        << locationParameters(m.kinematics)[static_cast<size_t>(i)].name;
  }
  // Without the term, the plain plan's triggers read the lost motion as location errors.
  const SphereCycleResult w = identifySphereCycle(plain, {simulate(plain, truth, {1})});
  double worst_mdeg = 0.0, worst_um = 0.0;
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double d = std::abs(w.location.reportValue(i) - want.reportValue(i));
    if (locationParameters(m.kinematics)[static_cast<size_t>(i)].kind == ParamKind::Angle) worst_mdeg = std::max(worst_mdeg, d);
    else worst_um = std::max(worst_um, d);
  }
  EXPECT_TRUE(worst_mdeg > 0.2 || worst_um > 1.0) << worst_mdeg << " mdeg, " << worst_um << " um";
  std::printf("without the term: location errors off by up to %.3f um / %.3f mdeg, residual %.3f um rms\n", worst_um,
              worst_mdeg, w.residual_sd_um);
  EXPECT_GT(w.residual_sd_um, 0.1) << "half a 2.8 mdeg lost motion on a 120 mm radius is 2.4 um";
}

TEST(OneSphereBacklash, LostMotionIsWithinTwoUncertaintiesAsOftenAsClaimed) {
  const MachineModel m = acMachine();
  const ProbePlan plan = makePlan("one_sphere", m, {{"backlash", "1"}});
  Truth truth = backlashTruth();
  const double sigma_um = m.probe.repeatability_um;
  truth.noise_um = sigma_um;
  const int machines = 200;
  int inside_A = 0, inside_C = 0;
  double u_A = 0, u_C = 0;
  for (int s = 0; s < machines; ++s) {
    const SphereCycleResult r = identifySphereCycle(plan, {simulate(plan, truth, {static_cast<std::uint64_t>(500 + s)})});
    const Eigen::Index a = indexOf(r, "backlash_A"), c = indexOf(r, "backlash_C");
    // u from the fit's covariance and the declared noise (what the budget's Type A is here).
    u_A = radToMdeg(umToMm(sigma_um) * std::sqrt(r.cov_per_sigma2(a, a)));
    u_C = radToMdeg(umToMm(sigma_um) * std::sqrt(r.cov_per_sigma2(c, c)));
    inside_A += std::abs(radToMdeg(r.x[a]) - kBacklashA_mdeg) <= 2 * u_A;
    inside_C += std::abs(radToMdeg(r.x[c]) - kBacklashC_mdeg) <= 2 * u_C;
  }
  // 95.4 % claimed; the binomial sd over 200 is 1.5 %: 4 sd either side.
  EXPECT_NEAR(inside_A / static_cast<double>(machines), 0.954, 0.06) << "u = " << u_A << " mdeg";
  EXPECT_NEAR(inside_C / static_cast<double>(machines), 0.954, 0.06) << "u = " << u_C << " mdeg";
  RecordProperty("u_backlash_A_mdeg", std::to_string(u_A));
  RecordProperty("u_backlash_C_mdeg", std::to_string(u_C));
  std::printf("lost motion: u(A) %.4f mdeg, u(C) %.4f mdeg; within 2u: A %d, C %d of %d\n", u_A, u_C, inside_A, inside_C,
              machines);
}

TEST(OneSphereBacklash, ThereAndBackProgramsPassTheVerifier) {
  const MachineModel m = acMachine();
  EXPECT_EQ(test::expectEveryDialectProgramPasses(makePlan("one_sphere", m, {{"backlash", "1"}})), 6);
  EXPECT_THROW(makePlan("one_sphere", m, {{"backlash", "1"}, {"pose_list", "0/0"}}), std::invalid_argument);
  EXPECT_THROW(makePlan("one_sphere", m, {{"backlash", "2"}}), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
