// rtest diagnose through the judge on simulated R-test series whose truth the judge
// never sees: the problem's columns against the exact simulator, 002's drift (11 cycles, -2 um/h
// dy_CB at every tilt, 0.3 um) found jointly and read as the linear axes it equally is, a
// spindle growth named with the closed-form combination it is read as, a 1 um sensor step,
// clean series within alpha. Seed loops of bench size are in bench/cycle_judge_bench.cpp.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <fstream>

#include <fmt/format.h>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/simulation.hpp"
#include "core/statistics.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/rtest/diagnose.hpp"
#include "cycles/rtest/plan.hpp"
#include "rtest_002_scenario.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

ProbePlan plan002(double noise_um) { return test::rtest002Plan(ROTACAL_SOURCE_DIR, noise_um); }
const auto baseTruth = test::rtest002Truth;

std::vector<RtestCycle> series(const ProbePlan& plan, const Truth& truth, const RtestTruthExtras& x, std::uint64_t seed,
                               double noise) {
  RtestSimOptions o;
  o.seed = seed;
  o.noise_um = noise;
  return simulateRtest(plan, truth, x, o).cycles;
}

RtestDiagnosis diagnose(const ProbePlan& plan, const std::vector<RtestCycle>& c, double declared) {
  RtestDiagnosisOptions o;
  o.sensor_sigma_um = declared;
  return diagnoseRtest(plan, c, o);
}

const RtestConfound* confound(const RtestDiagnosis& d, const std::string& cause) {
  for (const auto& c : d.confounds)
    if (c.entry.cause == cause) return &c;
  return nullptr;
}

Truth driftDyCB(int shape, double rate_um_h) {
  Truth t = baseTruth(shape);
  t.drift = [rate_um_h](double s) {
    ErrorVector d = ErrorVector::Zero();
    d[1] = umToMm(rate_um_h * s / 3600.0);
    return d;
  };
  return t;
}

// The judge's columns against the exact simulator (nonlinear, 002 Eq. (1)-(3)) with no noise:
// a static error set, a table drift, a spindle growth and a linear-axis drift each give readings
// equal to their columns times the injected values, to the linearisation (< 1e-4 um here).
TEST(RtestDiagnosis, ColumnsMatchTheExactSimulator) {
  const ProbePlan plan = plan002(0.3);
  const auto clean = series(plan, Truth{}, {}, 1, 0.0);
  const RtestJudgeSetup s = rtestJudgeSetup(plan, clean, 0.3);
  EXPECT_LT(s.problem.y.cwiseAbs().maxCoeff(), 1e-9);
  // Table drift from the reset on (t0: the first cycle's reset reading at B = C = 0, before its
  // first pose): dy_CB -2 um/h and c_BY +0.3 mdeg/h at every tilt.
  const double t0 = rtestReadTimes(plan).front();
  ASSERT_LT(t0, plan.points.front().t_s);
  {
    Truth t;
    t.errors.kinematics = Kinematics::TableBC;
    t.drift = [t0](double sec) {
      ErrorVector d = ErrorVector::Zero();
      d[1] = umToMm(-2.0 * (sec - t0) / 3600.0);
      d[5] = mdegToRad(0.3 * (sec - t0) / 3600.0);
      return d;
    };
    const RtestJudgeSetup g = rtestJudgeSetup(plan, series(plan, t, {}, 1, 0.0), 0.3);
    Eigen::VectorXd slope = Eigen::VectorXd::Zero(g.problem.causes[0].J.cols());
    for (int i = 0; i < 5; ++i) {
      slope[6 * i + 1] = -2.0;
      slope[6 * i + 5] = 0.3;
    }
    EXPECT_LT((g.problem.y - g.problem.causes[0].J * slope).cwiseAbs().maxCoeff(), 1e-4);
  }
  // Spindle growth 1.3 um/h and a linear-axis drift (0.5, -1, 0.8) um/h of the sphere.
  for (const Eigen::Vector3d& v : {Eigen::Vector3d(0, 0, 1.3), Eigen::Vector3d(0.5, -1.0, 0.8)}) {
    RtestTruthExtras x;
    x.sphere_drift_m_mm = [v, t0](double sec) { return Eigen::Vector3d(umToMm(1.0) * v * (sec - t0) / 3600.0); };
    const RtestJudgeSetup g = rtestJudgeSetup(plan, series(plan, Truth{}, x, 1, 0.0), 0.3);
    const Eigen::VectorXd model = v.x() == 0 ? Eigen::VectorXd(g.confounds[0].J * v.z()) : Eigen::VectorXd(g.confounds[1].J * v);
    EXPECT_LT((g.problem.y - model).cwiseAbs().maxCoeff(), 1e-4);
  }
  // The baseline: a static error set of 002's size is J0 times its values (dz, c at B = 0 are
  // not columns: the reset's convention, so the truth holds them at 0 there).
  {
    const Truth t = baseTruth(2);
    const RtestJudgeSetup g = rtestJudgeSetup(plan, series(plan, t, {}, 1, 0.0), 0.3);
    Eigen::VectorXd beta(g.problem.J0.cols());
    int q = 0;
    for (double b : {-60.0, -30.0, 0.0, 30.0, 60.0}) {
      const ErrorVector e = t.pose_dependent(tiltPose(Kinematics::TableBC, b, 0.0));
      for (int p = 0; p < 6; ++p) {
        if (b == 0.0 && (p == 2 || p == 5)) continue;
        beta[q++] = p < 3 ? mmToUm(e[p]) : radToMdeg(e[p]);
      }
    }
    EXPECT_LT((g.problem.y - g.problem.J0 * beta).cwiseAbs().maxCoeff(), 1e-3);
  }
}

// Issue 16's reproduction: 002's drift, each dy_CB slope alone weak against 30 Bonferroni'd t
// tests, is found jointly; its slopes within 3 u; the linear-axis drift explains the same signal
// (a uniform dy_CB drift at every B is a Y drift of the sphere), so the finding does not claim
// the rotary table.
TEST(RtestDiagnosis, Reproduction002DriftIsThermalDrift) {
  const ProbePlan plan = plan002(0.3);
  ASSERT_EQ(rtestSchedule(plan).cycles(), 11);
  for (int seed = 1; seed <= 4; ++seed) {
    const RtestDiagnosis d = diagnose(plan, series(plan, driftDyCB(seed, -2.0), {}, static_cast<std::uint64_t>(seed), 0.3), 0.3);
    if (seed == 1) std::printf("%s", rtestDiagnosisText(plan, d).c_str());
    ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << rtestDiagnosisText(plan, d);
    ASSERT_EQ(d.summary.findings.size(), 1u);
    const JudgeFinding& f = d.summary.findings[0];
    EXPECT_EQ(f.cause, "thermal_drift");
    for (double b : {-60, -30, 0, 30, 60}) {
      const JudgeEstimate* e = f.parameter(fmt::format("dy_CB(B={:g})/h", b));
      ASSERT_NE(e, nullptr);
      // 20 slopes over the 4 seeds: 3.8 u keeps the family's chance of a false failure at 0.27 %.
      EXPECT_LE(std::abs(e->value + 2.0), 3.8 * e->u) << b;
    }
    const RtestConfound* lin = confound(d, "linear_axis_drift");
    ASSERT_NE(lin, nullptr);
    EXPECT_TRUE(lin->explains);
    EXPECT_LT(lin->entry.angle_deg, 1e-3);
    const std::string summary = rtestFindingSummary(plan, d, f);
    EXPECT_EQ(summary.find("the rotary table's errors change with time"), std::string::npos) << summary;
    EXPECT_NE(summary.find("linear axes"), std::string::npos) << summary;
    const Json j = rtestDiagnosisJson(plan, d);
    EXPECT_EQ(j["verdict"], "effect_found");
    EXPECT_EQ(j["findings"][0]["cause"], "thermal_drift");
    EXPECT_EQ(j["judge"]["verdict"], "effect_found");
  }
}

// A spindle growing 1.3 um/h (the SJTU spindle's first 3 h, 0 -> 3.9 um) on a clean table:
// found as thermal_drift, worded as the spindle. The confounded entry comes from the Jacobians:
// the principal angle between the growth column and the baseline + drift span, computed here by
// QR, is 0; and the combination it names is the closed form: the sphere rising by L reads as
// dz_BY sinking by L at every B (dz_BY is along machine Z at every B: the B axis turns about Y).
TEST(RtestDiagnosis, SpindleGrowthConfoundedWithTableDriftFromTheJacobians) {
  const ProbePlan plan = plan002(0.3);
  RtestTruthExtras x;
  const double t0 = plan.points[static_cast<size_t>(rtestReferencePoint(plan) - 1)].t_s;
  x.sphere_drift_m_mm = [t0](double sec) { return Eigen::Vector3d(0, 0, umToMm(1.3 * (sec - t0) / 3600.0)); };
  const auto cyc = series(plan, baseTruth(1), x, 7, 0.3);
  const RtestDiagnosis d = diagnose(plan, cyc, 0.3);
  ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << rtestDiagnosisText(plan, d);
  EXPECT_EQ(d.summary.findings[0].cause, "thermal_drift");
  const RtestConfound* sp = confound(d, "spindle_growth");
  ASSERT_NE(sp, nullptr);
  EXPECT_TRUE(sp->explains);
  const std::string summary = rtestFindingSummary(plan, d, d.summary.findings[0]);
  EXPECT_NE(summary.find("spindle"), std::string::npos) << summary;
  EXPECT_EQ(summary.find("the rotary table's errors change with time"), std::string::npos) << summary;
  // Independent: QR of [J0 | drift], the growth column's part outside it.
  const RtestJudgeSetup s = rtestJudgeSetup(plan, cyc, 0.3);
  Eigen::MatrixXd M(s.problem.J0.rows(), s.problem.J0.cols() + s.problem.causes[0].J.cols());
  M << s.problem.J0, s.problem.causes[0].J;
  const Eigen::VectorXd g = s.confounds[0].J.col(0);
  const Eigen::VectorXd coef = M.colPivHouseholderQr().solve(g);
  const double sin_angle = (g - M * coef).norm() / g.norm();
  EXPECT_LT(sin_angle, 1e-8);
  EXPECT_NEAR(sp->entry.angle_deg, std::asin(sin_angle) * 180 / 3.14159265358979, 1e-3);
  // Closed form: dZ/h = 1 is read as dz_BY(B=b)/h = -1 at every b, nothing else.
  ASSERT_EQ(sp->entry.with_terms.size(), 5u);
  for (const auto& t : sp->entry.with_terms) {
    EXPECT_EQ(t.name.rfind("dz_BY(B=", 0), 0u) << t.name;
    EXPECT_NEAR(t.coefficient, -1.0, 1e-6) << t.name;
  }
  for (int b = 0; b < 5; ++b) EXPECT_NEAR(coef[s.problem.J0.cols() + 6 * b + 2], -1.0, 1e-6);
}

// A 1 um step of the sensors' x reading (the simulator's sensor_steps, 0.3 um noise), placed
// (a) between cycles 6 and 7: flagged as sensor_step_cycle_7 (from its reset on);
// (b) in cycle 7 after its last pose, before its re-read: sensor_step_in_cycle_7 (from its
//     re-read on: only the re-read tells (a) from (b));
// (c) in the middle of cycle 7 (between poses 12 and 13): a sensor step in cycle 7, either
//     form (each leaves half of the cycle's poses unmodelled, docs/rtest.md).
// dx within 3 u of 1 um (a, b), dy and dz within 3 u of 0; thermal_drift never accepted.
TEST(RtestDiagnosis, SensorStepMidSeriesIsFlagged) {
  const ProbePlan plan = plan002(0.3);
  const double interval = rtestSchedule(plan).interval_s;
  const std::vector<double> reads = rtestReadTimes(plan);
  for (char where : {'a', 'b', 'c'}) {
    RtestTruthExtras x;
    const double at = where == 'a' ? 6 * interval - 60.0
                      : where == 'b' ? 6 * interval + 0.5 * (plan.points.back().t_s + reads.back())
                                     : 6 * interval + 0.5 * (plan.points[11].t_s + plan.points[12].t_s);
    x.sensor_steps.push_back({at, Eigen::Vector3d(umToMm(1.0), 0, 0)});
    for (int seed = 1; seed <= 4; ++seed) {
      const auto cyc = series(plan, baseTruth(seed), x, static_cast<std::uint64_t>(100 + seed), 0.3);
      ASSERT_TRUE(cyc[6].reset && cyc[6].reread);
      // The simulator: the step is in the counts from its time on, reset and re-read included.
      const double seen = mmToUm(cyc[6].reread->dq_w_mm.x() - cyc[6].reset->dq_w_mm.x());
      EXPECT_NEAR(seen, where == 'a' ? 0.0 : 1.0, 5 * std::sqrt(2.0) * 0.3) << seed;
      const RtestDiagnosis d = diagnose(plan, cyc, 0.3);
      ASSERT_GE(d.summary.findings.size(), 1u) << rtestDiagnosisText(plan, d);
      const JudgeFinding& f = d.summary.findings[0];
      const Json j = rtestDiagnosisJson(plan, d);
      EXPECT_EQ(j["findings"][0]["cause"], "sensor_step");
      for (const auto& g : d.summary.findings) EXPECT_NE(g.cause, "thermal_drift");
      if (where == 'c') {
        EXPECT_TRUE(f.cause == "sensor_step_in_cycle_7" || f.cause == "sensor_step_cycle_7") << f.cause;
        continue;
      }
      EXPECT_EQ(f.cause, where == 'b' ? "sensor_step_in_cycle_7" : "sensor_step_cycle_7") << rtestDiagnosisText(plan, d);
      EXPECT_EQ(j["findings"][0]["variant"], where == 'b' ? "during cycle 7" : "from cycle 7");
      EXPECT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << rtestDiagnosisText(plan, d);
      EXPECT_LE(std::abs(f.parameter("dx")->value - 1.0), 3.0 * f.parameter("dx")->u);
      EXPECT_LE(std::abs(f.parameter("dy")->value), 3.0 * f.parameter("dy")->u);
      EXPECT_LE(std::abs(f.parameter("dz")->value), 3.0 * f.parameter("dz")->u);
    }
  }
}

// A linear-axis drift (the sphere -2 um/h in Y: 002's dy_CB drift read as the axes) and a 1 um
// sensor step in x between cycles 6 and 7 in one series: both are found, and the drift's wording
// still names the linear axes. The nested judgements that decide the wording keep the accepted
// step in their model: without it the step's residual is left to the drift families, and the
// table drift passes beyond the linear axes' (on drawn machines, 10 of 10 worded as the table,
// docs/diagnosis.md).
TEST(RtestDiagnosis, DriftWordingKeepsAnAcceptedSensorStepInItsModel) {
  const ProbePlan plan = plan002(0.3);
  const double interval = rtestSchedule(plan).interval_s;
  for (int seed = 1; seed <= 3; ++seed) {
    RtestTruthExtras x;
    x.sphere_drift_m_mm = [](double sec) { return Eigen::Vector3d(0, umToMm(-2.0 * sec / 3600.0), 0); };
    x.sensor_steps.push_back({6 * interval - 60.0, Eigen::Vector3d(umToMm(1.0), 0, 0)});
    const RtestDiagnosis d = diagnose(plan, series(plan, baseTruth(seed), x, static_cast<std::uint64_t>(600 + seed), 0.3), 0.3);
    ASSERT_NE(d.summary.finding("sensor_step_cycle_7"), nullptr) << rtestDiagnosisText(plan, d);
    const JudgeFinding* f = d.summary.finding("thermal_drift");
    ASSERT_NE(f, nullptr) << rtestDiagnosisText(plan, d);
    const RtestConfound* lin = confound(d, "linear_axis_drift");
    ASSERT_NE(lin, nullptr);
    EXPECT_TRUE(lin->explains) << rtestDiagnosisText(plan, d);
    const std::string summary = rtestFindingSummary(plan, d, *f);
    EXPECT_EQ(summary.find("the rotary table's errors change with time"), std::string::npos) << summary;
  }
}

// Clean series (static errors only, noise as declared): any verdict but no_significant_effect is
// a false alarm. 12 seeds at alpha 0.01: 3 or more has binomial probability 2.0e-4 (the
// benchmark runs 200).
TEST(RtestDiagnosis, CleanSeriesFalseAlarmsWithinAlpha) {
  const ProbePlan plan = plan002(0.3);
  int alarms = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const RtestDiagnosis d = diagnose(plan, series(plan, baseTruth(static_cast<int>(seed)), {}, 500 + seed, 0.3), 0.3);
    alarms += d.summary.verdict != JudgeVerdict::NoSignificantEffect;
    if (d.summary.verdict == JudgeVerdict::NoSignificantEffect) {
      EXPECT_TRUE(d.summary.explainsData());
    }
    EXPECT_NE(d.summary.message.find("within the declared noise"), std::string::npos);
  }
  std::printf("rtest clean: %d false alarms in 12 seeds\n", alarms);
  EXPECT_LE(alarms, 2);
}

// 002's drifts at a realistic size (the truth file examples/truth/rtest_002.json: -0.667 / -2 /
// -0.667 um/h in dx_BY / dy_CB / dz_BY and 0.3 mdeg/h in c_BY, every tilt), half of it, 0.2 um
// declared and drawn: found in at least 90 % of 10 seeds with the family within its 3-sigma
// ellipsoid: (b - b_true)^T C^-1 (b - b_true) below the chi2(30) quantile at 0.27 %, C computed
// here from the columns (the drift's whitened columns with the baseline projected out).
TEST(RtestDiagnosis, HiddenDriftFoundWithParametersWithin3u) {
  const ProbePlan plan = plan002(0.2);
  const Eigen::VectorXd truth_rate = [] {
    Eigen::VectorXd r = Eigen::VectorXd::Zero(30);
    for (int i = 0; i < 5; ++i) {
      r[6 * i + 0] = -0.333;
      r[6 * i + 1] = -1.0;
      r[6 * i + 2] = -0.333;
      r[6 * i + 5] = 0.15;
    }
    return r;
  }();
  const double q = chiSquareUpperQuantile(0.0027, 30);
  int found = 0;
  for (int seed = 1; seed <= 10; ++seed) {
    Truth t = baseTruth(seed);
    t.drift = [&truth_rate](double sec) {
      ErrorVector d = ErrorVector::Zero();
      d[0] = umToMm(truth_rate[0] * sec / 3600.0);
      d[1] = umToMm(truth_rate[1] * sec / 3600.0);
      d[2] = umToMm(truth_rate[2] * sec / 3600.0);
      d[5] = mdegToRad(truth_rate[5] * sec / 3600.0);
      return d;
    };
    const auto cyc = series(plan, t, {}, static_cast<std::uint64_t>(seed), 0.2);
    const RtestDiagnosis d = diagnose(plan, cyc, 0.2);
    if (d.summary.verdict != JudgeVerdict::EffectFound || d.summary.findings[0].cause != "thermal_drift") continue;
    const RtestJudgeSetup s = rtestJudgeSetup(plan, cyc, 0.2);
    const Eigen::MatrixXd W = s.problem.J0 / 0.2, D = s.problem.causes[0].J / 0.2;
    const Eigen::MatrixXd B = D - W * W.colPivHouseholderQr().solve(D);
    Eigen::VectorXd est(30);
    for (int k = 0; k < 30; ++k) est[k] = d.summary.findings[0].parameters[static_cast<size_t>(k)].value;
    const Eigen::VectorXd e = est - truth_rate;
    const double d2 = e.dot((B.transpose() * B) * e);
    found += d2 < q;
  }
  std::printf("rtest hidden drift (half 002): %d / 10 found within the 3-sigma ellipsoid\n", found);
  EXPECT_GE(found, 9);
}


// 002's example as a user runs it: the truth file examples/truth/rtest_002.json (002's drifts
// at every tilt), the readings scattered as the contributors declare one reading
// (examples/contributors/rtest_002.json: the sensors' 0.2 um and the sphere form's 0.1 um, 0.224
// um in quadrature, the per-reading part the uncertainty budget reads), judged against that same
// declaration. The judge used to whiten by the sensors alone: 1.25 times the chi2 per dof on 833
// dof is model_inadequate in 18 of 20 seeds. Named thermal_drift in every seed, never a sensor
// step; the clean counterpart (the same truth without its drift, the same noise) names nothing.
struct Example002 {
  ProbePlan plan = plan002(0.2);
  ContributorSet contributors = loadContributors(test::sourcePath("examples/contributors/rtest_002.json"));
  DeclaredNoise noise = rtestDeclaredNoise(plan, &contributors);
  Truth truth;
  RtestTruthExtras extras;
  Example002() {
    const JsonDoc doc = parseJsonText(readTextFile(test::sourcePath("examples/truth/rtest_002.json")), "rtest_002.json");
    truth = truthFromJson(doc, plan.machine.kinematics);
    rtestTruthFromJson(doc, plan.machine.kinematics, truth, extras);
  }
  RtestDiagnosis diagnose(const Truth& t, std::uint64_t seed) const {
    RtestDiagnosisOptions o;
    o.sensor_sigma_um = 0.2;
    o.reading_sigma_um = std::sqrt(noise.white_um2);
    const std::vector<RtestCycle> c = series(plan, t, extras, seed, std::sqrt(noise.white_um2));
    // As the CLI does: the structured part too, taken about the first cycle's readings.
    const DeclaredNoise as_read = rtestDeclaredNoise(plan, &contributors, &c.front());
    o.declaration = as_read.declaration;
    o.structured_um2 = as_read.structured_um2;
    return diagnoseRtest(plan, c, o);
  }
};

TEST(RtestDiagnosis, Example002HiddenDriftFoundUnderTheContributorsNoise) {
  const Example002 ex;
  ASSERT_EQ(rtestSchedule(ex.plan).cycles(), 11);
  ASSERT_TRUE(static_cast<bool>(ex.truth.drift));
  // The declaration is the budget's per-reading part, computed here from the file's two figures.
  ASSERT_NEAR(ex.noise.white_um2, 0.2 * 0.2 + 0.1 * 0.1, 1e-12);
  // 4 seeds: each diagnosis whitens 891 readings by the full declared covariance (8 of 8 found on
  // 8 seeds, docs/rtest.md).
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const RtestDiagnosis d = ex.diagnose(ex.truth, seed);
    ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << rtestDiagnosisText(ex.plan, d);
    EXPECT_NE(d.summary.finding("thermal_drift"), nullptr) << seed;
    for (const auto& f : d.summary.findings) EXPECT_EQ(f.cause, "thermal_drift") << seed;
    // dy_CB's -2 um/h at every tilt is 002's dominant drift (every cycle's own reset does not
    // touch it: it is a change along Y at every B alike).
    const JudgeEstimate* e = d.summary.finding("thermal_drift")->parameter("dy_CB(B=30)/h");
    ASSERT_NE(e, nullptr);
    EXPECT_LE(std::abs(e->value + 2.0), 4.0 * e->u) << seed;
  }
}

TEST(RtestDiagnosis, Example002CleanSeedsRaiseNothingUnderTheContributorsNoise) {
  const Example002 ex;
  Truth still = ex.truth;
  still.drift = nullptr;
  int named = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {  // 8 of 8 quiet on 8 seeds (docs/rtest.md)
    const RtestDiagnosis d = ex.diagnose(still, seed);
    named += d.summary.findings.empty() ? 0 : 1;
    EXPECT_EQ(d.summary.verdict, JudgeVerdict::NoSignificantEffect) << rtestDiagnosisText(ex.plan, d);
  }
  EXPECT_EQ(named, 0);
}

std::vector<double> sjtuDriftUm() {
  std::vector<double> v;
  for (const char* rel : {"../shared/data", "../../shared/data"}) {
    std::ifstream in(test::sourcePath(std::string(rel) + "/sjtu-spindle-thermal/thermal_expansion_error_original.csv"));
    if (!in) continue;
    std::string line;
    std::getline(in, line);  // header (with a byte-order mark)
    while (std::getline(in, line)) v.push_back(std::stod(line.substr(0, line.find(','))));
    break;
  }
  return v;
}

// Real data (shared/data/sjtu-spindle-thermal): the first 3 h of the SJTU spindle's axial growth
// (1-min samples, 0 -> 3.9 um, quantised in 0.265 um steps) as the sphere's Z drift on 002's
// series. Found as thermal_drift and worded as the spindle; the judge's dz_BY slopes against the
// injected curve's least-squares slope at the cycles' mean times (computed here), within 3 u
// plus the curve's bend (its residual about the line, taken as a bound).
TEST(RtestDiagnosis, RealSpindleHeatingIsWordedAsTheSpindle) {
  const std::vector<double> dl = sjtuDriftUm();
  if (dl.size() < 1000) GTEST_SKIP() << "shared/data/sjtu-spindle-thermal not found beside the project";
  const ProbePlan plan = plan002(0.3);
  RtestTruthExtras x;
  x.sphere_drift_m_mm = [dl](double t_s) {
    const double m = t_s / 60.0;
    const size_t i = std::min(dl.size() - 2, static_cast<size_t>(m));
    const double w = std::min(1.0, m - std::floor(m));
    return Eigen::Vector3d(0, 0, umToMm((1 - w) * dl[i] + w * dl[i + 1] - dl[0]));
  };
  const auto cyc = series(plan, baseTruth(1), x, 5, 0.3);
  const RtestDiagnosis d = diagnose(plan, cyc, 0.3);
  std::printf("%s", rtestDiagnosisText(plan, d).c_str());
  ASSERT_FALSE(d.summary.findings.empty()) << rtestDiagnosisText(plan, d);
  const JudgeFinding& f = d.summary.findings[0];
  ASSERT_EQ(f.cause, "thermal_drift");
  const std::string summary = rtestFindingSummary(plan, d, f);
  EXPECT_NE(summary.find("spindle"), std::string::npos) << summary;
  double st = 0, sy = 0, stt = 0, sty = 0;
  std::vector<double> ts, ys;
  for (const auto& c : cyc) {
    const double t = c.t_s() / 3600.0, y = -mmToUm(x.sphere_drift_m_mm(c.t_s()).z());
    ts.push_back(t), ys.push_back(y);
    st += t, sy += y, stt += t * t, sty += t * y;
  }
  const double n = static_cast<double>(cyc.size());
  const double slope = (n * sty - st * sy) / (n * stt - st * st), b0 = (sy - slope * st) / n;
  double bend = 0;
  for (size_t k = 0; k < ts.size(); ++k) bend = std::max(bend, std::abs(ys[k] - b0 - slope * ts[k]));
  const double bend_rate = bend / 3.0;  // the largest departure from the line over the 3 h, per hour
  std::printf("SJTU first 3 h: injected slope %.3f um/h, bend %.3f um\n", slope, bend);
  for (double b : {-60, -30, 0, 30, 60}) {
    const JudgeEstimate* e = f.parameter(fmt::format("dz_BY(B={:g})/h", b));
    ASSERT_NE(e, nullptr);
    EXPECT_LE(std::abs(e->value - slope), 3.0 * e->u + bend_rate) << b;
  }
}

}  // namespace
}  // namespace rotacal
