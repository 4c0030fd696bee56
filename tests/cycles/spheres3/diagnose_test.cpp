// Issue 16 for the three-sphere cycle: the diagnosis through the one judge. Every check compares
// with the simulation's truth, which the judge never sees. Sizes (stated once here and in
// docs/diagnosis.md): 001's C axis shows volumetric errors up to 11.97 um from its component
// errors (2.31 um after compensation), so a 3 um second-order radial error motion (issue 6's
// oval bearing) is a realistic hidden cause; squareness 30 um/m is 000 Table 5's size.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "cycles/cycle.hpp"
#include "cycles/spheres3/diagnose.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

ProbePlan spheresPlan() { return makePlan("spheres3", test::acMachine(), {}); }

// Location errors of 001's size (Oxc -1.9 um, Syc 2.2 arcsec), varied per seed.
Eigen::Vector4d variedLocation(std::uint64_t seed) {
  std::mt19937_64 g(seed * 7919);
  std::normal_distribution<double> n(0.0, 1.0);
  return {umToMm(-2.0 + 5.0 * n(g)), umToMm(3.0 * n(g)), mdegToRad(0.6 * n(g)), mdegToRad(0.6 + 0.6 * n(g))};
}

// The truth as the spheres3 model's own exact transform (T_L T_E(C) Dc(-C)), with a component
// error function of C and a drift of the table's position (mm/s).
Truth truthWith(const Eigen::Vector4d& L, std::function<ComponentVector(double)> E, double noise_um,
                Eigen::Vector3d drift_mm_per_s = Eigen::Vector3d::Zero()) {
  Truth t = test::truthWith(test::table4Mean());
  t.noise_um = noise_um;
  t.table_transform = [L, E, drift_mm_per_s](const Pose& p, double ts) {
    const double c = degToRad(p.C);
    Eigen::Isometry3d T = spheres3Table_m_w(L, E ? E(c) : ComponentVector::Zero(), c);
    T.pretranslate(drift_mm_per_s * ts);
    return T;
  };
  return t;
}

const Spheres3DiagnosisOptions& opts() {
  static const Spheres3DiagnosisOptions o = [] {
    Spheres3DiagnosisOptions x;
    x.sigma_um = 0.7;
    return x;
  }();
  return o;
}

const JudgeEstimate& param(const JudgeFinding& f, const std::string& name) {
  for (const auto& p : f.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

TEST(Spheres3Diagnosis, CleanSeedsRaiseAtMostOneAlarmInTen) {
  // alpha = 0.01 per data set: 2 or more alarms in 10 has probability < 0.5 %.
  const ProbePlan plan = spheresPlan();
  int alarms = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const Truth t = truthWith(variedLocation(seed), nullptr, 0.7);
    const Spheres3Diagnosis d = diagnoseSpheres3(plan, {simulate(plan, t, {seed})}, opts());
    if (d.judged.verdict != JudgeVerdict::NoSignificantEffect) ++alarms;
    else EXPECT_TRUE(d.judged.explainsData());
  }
  EXPECT_LE(alarms, 1);
}

TEST(Spheres3Diagnosis, FindsAHidden3umSecondOrderRadialErrorMotion) {
  const ProbePlan plan = spheresPlan();
  const double cases[3][2] = {{3.0, 0.0}, {0.0, 3.0}, {2.5, -2.0}};
  for (int k = 0; k < 3; ++k) {
    const double ax = cases[k][0], ay = cases[k][1];
    const std::uint64_t seed = 100 + static_cast<std::uint64_t>(k);
    const Truth t = truthWith(variedLocation(seed), [ax, ay](double c) {
      ComponentVector e = ComponentVector::Zero();
      e[0] = umToMm(ax) * std::cos(2 * c);
      e[1] = umToMm(ay) * std::cos(2 * c);
      return e;
    }, 0.7);
    const Spheres3Diagnosis d = diagnoseSpheres3(plan, {simulate(plan, t, {seed})}, opts());
    ASSERT_EQ(d.judged.verdict, JudgeVerdict::EffectFound) << judgeText(d.judged);
    const JudgeFinding& f = d.judged.findings.front();
    EXPECT_EQ(f.cause, kSpheres3Radial);
    for (const auto& [name, want] : {std::pair<std::string, double>{"EXC_cos2C", ax}, {"EYC_cos2C", ay},
                                     {"EXC_sin2C", 0.0}, {"EYC_sin2C", 0.0}}) {
      const JudgeEstimate& e = param(f, name);
      EXPECT_LT(std::abs(e.value - want), 3.0 * e.u) << name << " case " << k;
    }
    EXPECT_TRUE(d.judged.explainsData());
  }
}

TEST(Spheres3Diagnosis, FindsASquarenessErrorOfTable5Size) {
  const ProbePlan plan = spheresPlan();
  for (std::uint64_t seed : {201u, 202u}) {
    Truth t = truthWith(variedLocation(seed), nullptr, 0.7);
    const double sxy = 30e-6;  // 30 um/m
    t.linear_axis_error = [sxy](const Eigen::Vector3d& c) { return Eigen::Vector3d(sxy * c.y(), 0.0, 0.0); };
    const Spheres3Diagnosis d = diagnoseSpheres3(plan, {simulate(plan, t, {seed})}, opts());
    ASSERT_EQ(d.judged.verdict, JudgeVerdict::EffectFound) << judgeText(d.judged);
    const JudgeFinding& f = d.judged.findings.front();
    ASSERT_EQ(f.cause, kSpheres3Squareness) << judgeText(d.judged);
    const JudgeEstimate& e = param(f, "S_xy");
    EXPECT_LT(std::abs(e.value - 30.0), 3.0 * e.u);
  }
}

TEST(Spheres3Diagnosis, FindsThermalDriftOverFourRepeats) {
  const ProbePlan plan = spheresPlan();
  // 3 um/h in X, repeats every 30 min: 001 averages five consecutive runs, 000 Table 4 sees
  // location errors move by 15 um while warming up.
  const double rate_um_h = 3.0;
  Truth t = truthWith(variedLocation(300), nullptr, 0.7, Eigen::Vector3d(umToMm(rate_um_h) / 3600.0, 0, 0));
  std::vector<MeasurementRun> runs;
  for (int r = 0; r < 4; ++r) {
    t.start_time_s = 1800.0 * r;
    runs.push_back(simulate(plan, t, {300u + static_cast<std::uint64_t>(r)}));
  }
  const Spheres3Diagnosis d = diagnoseSpheres3(plan, runs, opts());
  ASSERT_EQ(d.judged.verdict, JudgeVerdict::EffectFound) << judgeText(d.judged);
  const JudgeFinding& f = d.judged.findings.front();
  ASSERT_EQ(f.cause, kSpheres3Drift);
  const JudgeEstimate& e = param(f, "X/h");
  EXPECT_LT(std::abs(e.value - rate_um_h), 3.0 * e.u);
}

TEST(Spheres3Diagnosis, AFifthOrderRadialErrorMotionIsOutsideTheCatalog) {
  // The catalog's harmonics stop at 3C; a 3 um 5C radial waviness must read model_inadequate.
  const ProbePlan plan = spheresPlan();
  for (std::uint64_t seed : {401u, 402u}) {
    const Truth t = truthWith(variedLocation(seed), [](double c) {
      ComponentVector e = ComponentVector::Zero();
      e[0] = umToMm(3.0) * std::cos(5 * c);
      return e;
    }, 0.7);
    const Spheres3Diagnosis d = diagnoseSpheres3(plan, {simulate(plan, t, {seed})}, opts());
    EXPECT_EQ(d.judged.verdict, JudgeVerdict::ModelInadequate) << judgeText(d.judged);
    EXPECT_FALSE(d.judged.explainsData());
  }
}

TEST(Spheres3Diagnosis, ZScaleIsConfoundedWithTheSpherePositionsFromTheJacobians) {
  // With the tilt axis at 0 every sphere keeps its height: a Z scale s moves sphere i by the
  // constant -s z_i, which is exactly a sphere position. Closed form (never seen by the judge):
  // the Z-scale column equals sum_i (-1e-3 z_i) * (sphere i's z column).
  const ProbePlan plan = spheresPlan();
  const Truth t = truthWith(variedLocation(500), nullptr, 0.7);
  const std::vector<MeasurementRun> runs{simulate(plan, t, {500u})};
  const Spheres3Diagnosis d = diagnoseSpheres3(plan, runs, opts());
  const JudgeCause* scale = nullptr;
  for (const auto& c : d.problem.causes)
    if (c.name == kSpheres3Scale) scale = &c;
  ASSERT_NE(scale, nullptr);
  Eigen::VectorXd closed = Eigen::VectorXd::Zero(d.problem.y.size());
  for (int i = 0; i < 3; ++i) closed += -1e-3 * d.baseline.sphere_w_mm[static_cast<size_t>(i)].z() * d.problem.J0.col(4 + 3 * i + 2);
  // Equal to the tilt of the axis (Sxc, Syc ~ 1e-5 rad: a sphere's height varies by ~r 1e-5
  // over the turn), hence 1e-4 relative.
  EXPECT_LT((scale->J.col(2) - closed).norm(), 1e-4 * closed.norm());
  // The judge finds it from the columns alone: a confounded entry for the scale, with the model.
  bool named = false;
  for (const auto& c : d.judged.confounded)
    if (c.cause == kSpheres3Scale && c.with_model) named = true;
  EXPECT_TRUE(named) << judgeText(d.judged);
  // Without the Z column (and the isotropic XY part the sphere radii absorb the same way) the
  // rest of the scale, X - Y, is a separable 2C pattern: no confounded entry for it.
  JudgeProblem p = d.problem;
  for (auto& c : p.causes)
    if (c.name == kSpheres3Scale) {
      c.J = (scale->J.col(0) - scale->J.col(1)).eval();
      c.parameters = {{"X_minus_Y_scale", "um/m"}};
    }
  const JudgeSummary s = judge(p, opts().judge);
  for (const auto& c : s.confounded) EXPECT_NE(c.cause, kSpheres3Scale) << judgeText(s);
}

}  // namespace
}  // namespace rotacal
