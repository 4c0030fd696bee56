// touch154's diagnosis through the one judge: inject an effect into exact simulated
// data (the simulator's truth, which the judge never sees) and check the verdict, the name and
// the parameters; clean data stays quiet; an effect outside the catalog is model_inadequate;
// confounding follows from the Jacobians. The many-seed figures are in bench/diagnose_bench.cpp.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/touch154/causes.hpp"
#include "cycles/touch154/closed_form.hpp"
#include "cycles/touch154/diagnose.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

constexpr int kRepeats = 4;
constexpr double kNoise = 0.7;   // um, the probe repeatability declared in the machine file
constexpr double kAlpha = 0.01;  // the judge's default family-wise rate

std::vector<MeasurementRun> repeats(const ProbePlan& plan, const Truth& truth, int seed, int n = kRepeats) {
  const double cycle = plan.points.back().t_s + 60.0;
  std::vector<MeasurementRun> runs;
  for (int r = 0; r < n; ++r) {
    Truth t = truth;
    t.start_time_s = r * cycle;
    runs.push_back(simulate(plan, t, {static_cast<std::uint64_t>(1000 * seed + r)}));
  }
  return runs;
}

Touch154DiagnosisOptions options() {
  Touch154DiagnosisOptions o;
  o.judge.alpha = kAlpha;
  o.sigma_um = kNoise;
  return o;
}

Truth clean() {
  Truth t = test::truthWith(test::table4Mean());
  t.noise_um = kNoise;
  return t;
}

TEST(Touch154Diagnose, IssueReproductionXScale60umPerMIsNeverNoSignificantEffect) {
  // issue 16: 4 repeats, X positioning (scale) error 60 um/m, 0.7 um probe noise; the old code
  // said "no significant effect" because its noise was the fit's own sigma.
  const ProbePlan plan = test::touch154Plan();
  Truth t = clean();
  t.linear_axis_error = [](const Eigen::Vector3d& c) { return Eigen::Vector3d(60e-6 * c.x(), 0.0, 0.0); };
  for (int seed : {1, 2}) {
    const Touch154Diagnosis d = diagnoseTouch154(plan, repeats(plan, t, seed), options());
    const std::string text = touch154DiagnosisText(d);
    ASSERT_NE(d.judged.verdict, JudgeVerdict::NoSignificantEffect) << text;
    if (d.judged.verdict == JudgeVerdict::EffectFound)
      EXPECT_NE(d.judged.finding("linear_axis_scale"), nullptr) << text;
    else
      EXPECT_EQ(text.find("explains the data"), std::string::npos) << text;
    EXPECT_FALSE(d.judged.baseline.passes);
  }
}

TEST(Touch154Diagnose, CleanDataRaisesAtMostTheAlphaShareOfAlarms) {
  // 10 seeds at alpha = 1 %: two or more alarms has probability 0.4 % under a correct judge.
  const ProbePlan plan = test::touch154Plan();
  Truth t = clean();
  t.artefact.setup.translation_mm = Eigen::Vector3d(0.4, -0.3, 0.0);
  t.artefact.form[static_cast<size_t>(Face::Top)].tilt_v_rad = 0.002;
  int alarms = 0;
  for (int seed = 100; seed < 110; ++seed) {
    const Touch154Diagnosis d = diagnoseTouch154(plan, repeats(plan, t, seed), options());
    if (d.judged.verdict != JudgeVerdict::NoSignificantEffect) ++alarms;
    else EXPECT_TRUE(d.judged.explainsData());
  }
  EXPECT_LE(alarms, 1);
}

TEST(Touch154Diagnose, HiddenSquarenessIsFoundWithItsParametersWithin3u) {
  // 000 Table 5's size: 3 um / 100 mm (30 um/m) in S_xy and S_yz.
  const ProbePlan plan = test::touch154Plan();
  Truth t = clean();
  t.linear_axis_error = [](const Eigen::Vector3d& c) { return Eigen::Vector3d(30e-6 * c.y(), 30e-6 * c.z(), 0.0); };
  int found = 0;
  constexpr int kSeeds = 6;
  for (int seed = 31; seed < 31 + kSeeds; ++seed) {
    const Touch154Diagnosis d = diagnoseTouch154(plan, repeats(plan, t, seed), options());
    const JudgeFinding* f = d.judged.finding("linear_axis_squareness");
    if (d.judged.verdict != JudgeVerdict::EffectFound || f == nullptr) continue;
    const double truth[3] = {30.0, 0.0, 30.0};
    bool within = true;
    for (int k = 0; k < 3; ++k) within = within && std::abs(f->parameters[static_cast<size_t>(k)].value - truth[k]) < 3.0 * f->parameters[static_cast<size_t>(k)].u;
    found += within;
  }
  EXPECT_GE(found, kSeeds - 1) << "found with parameters within 3 u in " << found << " of " << kSeeds;
}

TEST(Touch154Diagnose, HiddenLinearDriftIsThermalDriftWithItsRate) {
  // 12 um of dz_AY over the four repeats (000 Table 4 moves dz_AY by 15 um).
  const ProbePlan plan = test::touch154Plan();
  const double span_s = kRepeats * (plan.points.back().t_s + 60.0);
  Truth t = clean();
  t.drift = [span_s](double ts) {
    ErrorVector d = ErrorVector::Zero();
    d[2] = umToMm(12.0) * ts / span_s;
    return d;
  };
  const double rate = 12.0 / span_s * 3600.0;  // um/h
  for (int seed : {5, 6}) {
    const Touch154Diagnosis d = diagnoseTouch154(plan, repeats(plan, t, seed), options());
    ASSERT_EQ(d.judged.verdict, JudgeVerdict::EffectFound) << touch154DiagnosisText(d);
    const JudgeFinding* f = d.judged.finding("thermal_drift");
    ASSERT_NE(f, nullptr) << touch154DiagnosisText(d);
    EXPECT_NEAR(f->parameters[2].value, rate, 3.0 * f->parameters[2].u) << "dz_AY/h";
    EXPECT_NEAR(f->parameters[0].value, 0.0, 3.0 * f->parameters[0].u) << "dx_AY/h";
  }
}

TEST(Touch154Diagnose, StraightnessOutsideTheCatalogIsModelInadequateWithXCarryingIt) {
  // A 4 um bow of Z along X (straightness E_zx), which no catalogued cause models.
  const ProbePlan plan = test::touch154Plan();
  Truth t = clean();
  t.linear_axis_error = [](const Eigen::Vector3d& c) {
    return Eigen::Vector3d(0.0, 0.0, 4e-3 * (c.x() / 250.0) * (c.x() / 250.0));
  };
  for (int seed : {41, 42, 43}) {
    const Touch154Diagnosis d = diagnoseTouch154(plan, repeats(plan, t, seed), options());
    ASSERT_EQ(d.judged.verdict, JudgeVerdict::ModelInadequate) << touch154DiagnosisText(d);
    // Where it sits: X carries a significant part of the misfit (a bow along X).
    const auto x = std::find_if(d.judged.baseline.factors.begin(), d.judged.baseline.factors.end(),
                                [](const JudgeFactorShare& f) { return f.factor == "X"; });
    ASSERT_NE(x, d.judged.baseline.factors.end());
    EXPECT_LT(x->p_value, d.judged.per_test_alpha) << touch154DiagnosisText(d);
  }
}

TEST(Touch154Diagnose, TiltAxisBacklashIsOneFindingWithWhatThePlanCannotTellItFrom) {
  // 10 arcsec of lost motion on A (the simulator turns the table to the angle A really reaches;
  // no Jacobian). 000's plan reaches A = -90 from above only: the data cannot tell backlash from
  // a positioning error at -90 deg, nor either from S_yz, so no single cause may be named: one
  // finding names all three, and reads the signal as its cause (-90 deg stands b = 2.78 mdeg off
  // A = 0: EAA@A-90 or backlash_A of that size, within 3 u).
  const ProbePlan plan = test::touch154Plan();
  Truth t = clean();
  t.rotary_backlash_deg[0] = 10.0 / 3600.0;
  const double b_mdeg = 10.0 / 3.6;
  for (int seed : {51, 52}) {
    const Touch154Diagnosis d = diagnoseTouch154(plan, repeats(plan, t, seed), options());
    const std::string text = touch154DiagnosisText(d);
    ASSERT_EQ(d.judged.findings.size(), 1u) << text;
    const JudgeFinding& f = d.judged.findings[0];
    std::vector<std::string> named = f.confounded_with;
    named.push_back(f.cause);
    for (const char* c : {"tilt_axis_positioning", "tilt_axis_backlash", "linear_axis_squareness"})
      EXPECT_NE(std::find(named.begin(), named.end(), c), named.end()) << c << "\n" << text;
    EXPECT_EQ(d.judged.verdict, d.judged.final_model.passes ? JudgeVerdict::EffectFound : JudgeVerdict::ModelInadequate);
    EXPECT_GT(f.gain, 2.0 * f.gain_se);
    if (const JudgeEstimate* e = f.parameter(f.cause == "tilt_axis_positioning" ? "EAA@A-90" : "backlash_A")) {
      EXPECT_LE(std::abs(std::abs(e->value) - b_mdeg), 3.0 * e->u) << text;
    }
    // Every pair among the three is carried by the finding: no significant signal left unnamed.
    for (const auto& c : d.judged.confounded) EXPECT_FALSE(c.signal) << c.why;
    EXPECT_NE(text.find("the plan cannot tell them apart"), std::string::npos) << text;
  }
}

TEST(Touch154Diagnose, SyzAndTheTiltAxisAngleAtMinus90AreOneSignalOnThe000Plan) {
  // Two exact simulations that share no code path: A stopping b short at -90 deg (the table
  // turned, full HTMs) and the Y axis out of square with Z by S_yz = -b (rad) (the linear-axis
  // error at the read position). The judge's confounded entry says these move the data alike;
  // here the baseline's residuals of the two simulated data sets must agree.
  const ProbePlan plan = test::touch154Plan();
  const double b_rad = mdegToRad(2.0);
  Truth tilt = test::truthWith(test::table4Mean());
  // Lost motion b: A = 0 is reached in + (stands -b/2 off), -90 deg from above (+b/2 off), so
  // -90 deg stands b off A = 0; the common -b/2 is A's zero, a_AY.
  tilt.rotary_backlash_deg[0] = radToDeg(b_rad);
  Truth sq = test::truthWith(test::table4Mean());
  sq.linear_axis_error = [b_rad](const Eigen::Vector3d& c) { return Eigen::Vector3d(0.0, -b_rad * c.z(), 0.0); };
  IdentificationOptions io;
  const Linearisation a = lineariseAtBaseline(plan, repeats(plan, tilt, 1, 1), io, {tiltAxisPositioning(plan)});
  const Linearisation s = lineariseAtBaseline(plan, repeats(plan, sq, 1, 1), io, {linearAxisSquareness()});
  ASSERT_TRUE(a.ok && s.ok);
  ASSERT_GT(a.residual_um.norm(), 5.0);  // um: the misfit is real, not rounding
  EXPECT_LT((a.residual_um - s.residual_um).norm(), 0.02 * a.residual_um.norm());
  // And the extension's own column reproduces the simulator's backlash: EAA@A-90 = b.
  const Eigen::VectorXd v = a.extension_J[0] * Eigen::VectorXd::Constant(1, radToMdeg(b_rad));
  const Eigen::VectorXd predicted = v - a.J0 * a.J0.completeOrthogonalDecomposition().solve(v);
  EXPECT_LT((a.residual_um - predicted).norm(), 0.02 * predicted.norm());
}

TEST(Touch154Diagnose, LobingThatReversesWithTheApproachIsReadAsDxAYAndTheJudgeSaysSo) {
  // +X late and -X early by 2 um: on 000's plan each point is probed from one side, so the data
  // cannot show it (the fit is exact) while dx_AY takes it in full. The simulator says how much;
  // the judge, from the Jacobians alone, must name dx_AY among what pretravel is read as.
  const ProbePlan plan = test::touch154Plan();
  Truth t = test::truthWith(test::table4Mean());
  t.pretravel_by_direction_um = [](const Eigen::Vector3d& u) { return std::abs(u.x()) > 0.9 ? 2.0 * u.x() : 0.0; };
  const auto runs = repeats(plan, t, 1, 1);
  IdentificationOptions io;
  io.method = Method::LeastSquaresPerPoint;
  const IdentificationResult r = identifyTouch154(plan, runs, io);
  EXPECT_LT(r.summary.sigma_um, 1e-3);  // invisible: the model fits exactly
  EXPECT_NEAR(r.estimate.reportValue(0) - test::table4Mean().reportValue(0), 2.0, 1e-3);  // dx_AY, um
  Touch154DiagnosisOptions o = options();
  o.candidates = {probePretravel()};
  const Touch154Diagnosis d = diagnoseTouch154(plan, runs, o);
  bool names_dx = false;
  for (const auto& c : d.judged.confounded)
    if (c.cause == "probe_pretravel") names_dx = std::find(c.with.begin(), c.with.end(), "dx_AY") != c.with.end();
  EXPECT_TRUE(names_dx) << touch154DiagnosisText(d);
}

TEST(Touch154Diagnose, CauseColumnsMatchTheExactSimulator) {
  // Noise-free data with a small squareness: the baseline's residual is (I - P_J0) J_c gamma to
  // first order; the simulator computes the truth without any Jacobian.
  const ProbePlan plan = test::touch154Plan();
  Truth t = test::truthWith(test::table4Mean());
  const double s_xy = 10e-6, s_yz = -8e-6;  // mm/mm
  t.linear_axis_error = [&](const Eigen::Vector3d& c) { return Eigen::Vector3d(s_xy * c.y(), s_yz * c.z(), 0.0); };
  IdentificationOptions io;
  const Linearisation lin = lineariseAtBaseline(plan, repeats(plan, t, 1, 1), io, {linearAxisSquareness()});
  ASSERT_TRUE(lin.ok);
  const Eigen::VectorXd gamma = Eigen::Vector3d(s_xy * 1e6, 0.0, s_yz * 1e6);  // um/m
  const Eigen::VectorXd v = lin.extension_J[0] * gamma;
  const Eigen::VectorXd predicted = v - lin.J0 * lin.J0.completeOrthogonalDecomposition().solve(v);
  ASSERT_GT(predicted.norm(), 1.0);  // um: a signal well above rounding
  EXPECT_LT((lin.residual_um - predicted).norm(), 0.02 * predicted.norm());
}

TEST(Touch154Diagnose, ConfoundingComesFromTheJacobians) {
  const ProbePlan plan = test::touch154Plan();
  const auto runs = repeats(plan, clean(), 3);
  Touch154DiagnosisOptions o = options();
  o.candidates = {probeLength(), linearAxisSquareness()};
  const Touch154Diagnosis d = diagnoseTouch154(plan, runs, o);
  auto confoundedWith = [](const JudgeSummary& s, const std::string& cause, const std::string& with) {
    for (const auto& c : s.confounded)
      if (c.cause == cause && std::find(c.with.begin(), c.with.end(), with) != c.with.end()) return true;
    return false;
  };
  // A probe-length error moves the ball centre down: the table-probing plan reads it as dz_AY.
  EXPECT_TRUE(confoundedWith(d.judged, "probe_length", "dz_AY")) << touch154DiagnosisText(d);
  EXPECT_FALSE(confoundedWith(d.judged, "linear_axis_squareness", "dz_AY"));
  // The same problem without dz_AY's column in the baseline: the entry goes with the column.
  JudgeProblem p = touch154JudgeProblem(plan, d.lin, d.candidates, kNoise);
  const auto it = std::find(d.lin.J0_names.begin(), d.lin.J0_names.end(), "dz_AY");
  ASSERT_NE(it, d.lin.J0_names.end());
  const Eigen::Index col = it - d.lin.J0_names.begin();
  p.J0.col(col).setZero();
  const JudgeSummary without = judge(p, o.judge);
  EXPECT_FALSE(confoundedWith(without, "probe_length", "dz_AY")) << judgeText(without);
}

TEST(Touch154Diagnose, JsonKeepsTheContractFieldsAndTheJudgeVerdict) {
  const ProbePlan plan = test::touch154Plan();
  Truth t = clean();
  t.drift = [](double ts) {
    ErrorVector d = ErrorVector::Zero();
    d[2] = umToMm(12.0) * ts / 3000.0;
    return d;
  };
  const Touch154Diagnosis d = diagnoseTouch154(plan, repeats(plan, t, 5), options());
  const Json j = touch154DiagnosisJson(d, plan);
  EXPECT_EQ(j["format"], "rotacal-diagnosis/1");
  EXPECT_EQ(j["verdict"], "effect_found");
  EXPECT_TRUE(j["baseline"].contains("holdout_rms_um"));
  EXPECT_TRUE(j["baseline"].contains("residual_rms_um"));
  const Json& f = j["findings"][0];
  EXPECT_EQ(f["cause"], "thermal_drift");
  EXPECT_EQ(f["parameters"]["dz_AY/h"]["unit"], "um/h");
  EXPECT_TRUE(f["location_errors"].contains("dz_AY"));
  EXPECT_GT(f["gain_pct"].get<double>(), 0.0);
  ASSERT_FALSE(j["confounded"].empty());  // probe_length with dz_AY, at least
  for (const auto& c : j["confounded"]) {
    EXPECT_FALSE(c["causes"].empty());
    EXPECT_FALSE(c["separate_with"].get<std::string>().empty());
  }
}

}  // namespace
}  // namespace rotacal
