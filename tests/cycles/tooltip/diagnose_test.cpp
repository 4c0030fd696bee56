// tooltip diagnose through the judge on the exact simulator (cycles/tooltip/plan.hpp),
// whose truth the judge never sees: the cause columns against the simulator, the case that failed once
// reproduction (an isotropic 30 um/m scale, no pivot error, one tool: a confounded pair, never
// pivot_length found) with the closed-form combination dR = 1 um <-> s = -1000 / R um/m, the
// confounding gone with two tool lengths on the real plans, hidden causes found, clean data.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include <fmt/format.h>

#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/tooltip/diagnose.hpp"
#include "cycles/tooltip/plan.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

constexpr double kNoise = 0.254;  // the declared default (004 Sec. VII), also drawn

ProbePlan planR(double radius_mm, CycleOptions extra = {}) {
  CycleOptions o{{"units", "mm"}, {"radius_mm", fmt::format("{:g}", radius_mm)}, {"step_deg", "5"}, {"end_deg", "90"}};
  for (const auto& [k, v] : extra) o[k] = v;
  return makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")), o);
}

TooltipTruth truthOf(int shape, double noise = kNoise) {
  TooltipTruth t;
  t.offset_mdeg = 1.0 + 0.3 * shape;
  t.slope_mdeg_per_90deg = 2.0 - 0.5 * (shape % 3);
  t.sin_mdeg = -1.5 + 0.2 * (shape % 5);
  t.sin2_mdeg = 0.8;
  t.noise_um = noise;
  return t;
}

TooltipDiagnosis run(const std::vector<const ProbePlan*>& plans, const TooltipTruth& t, std::uint64_t seed, int repeats = 1) {
  std::vector<TooltipSet> sets;
  for (const ProbePlan* p : plans) {
    TooltipSet s{p, {}};
    for (int r = 0; r < repeats; ++r) s.runs.push_back(simulateTooltip(*p, t, seed * 100 + sets.size() * 10 + r));
    sets.push_back(s);
  }
  return diagnoseTooltip(sets, {});
}

/// Raw readings (transverse, Z interleaved) in the judge's order: non-zero readings of each run.
Eigen::VectorXd raw(const ProbePlan& plan, const TooltipRun& run) {
  const std::vector<int> refs = tooltipReferences(plan);
  std::vector<double> v;
  for (size_t k = 0; k < run.size(); ++k)
    if (refs[k] != static_cast<int>(k)) {
      v.push_back(run[k].t_um);
      v.push_back(run[k].z_um);
    }
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

const JudgeConfounded* pairEntry(const JudgeSummary& s) {
  for (const auto& c : s.confounded)
    if (!c.with_model && ((c.cause == "pivot_length" && c.with[0] == "linear_axis_scale") ||
                          (c.cause == "linear_axis_scale" && c.with[0] == "pivot_length")))
      return &c;
  return nullptr;
}

// The cause columns against the exact simulator: readings with only a pivot error, only a scale
// error, only a drift (dynamic test: angles read at several times) are the columns times the
// injected values, to the linearisation (dR = 5 um at R = 200 mm: (5e-3)^2 / 200 mm ~ 1e-4 um).
TEST(TooltipDiagnosis, CauseColumnsMatchTheExactSimulator) {
  const ProbePlan plan = planR(200, {{"sweeps", "1"}});
  TooltipTruth zero;
  const TooltipJudgeSetup s = tooltipJudgeSetup({{&plan, {simulateTooltip(plan, zero, 1)}}}, kNoise);
  ASSERT_EQ(s.problem.causes.size(), 3u);  // a dynamic test reads each angle more than once: drift
  TooltipTruth t = zero;
  t.dR_um = 5.0;
  EXPECT_LT((raw(plan, simulateTooltip(plan, t, 1)) - s.problem.causes[0].J.col(0) * 5.0).cwiseAbs().maxCoeff(), 1e-3);
  t = zero;
  t.scale_t_um_m = 30.0;
  t.scale_z_um_m = -20.0;
  EXPECT_LT((raw(plan, simulateTooltip(plan, t, 1)) - s.problem.causes[1].J * Eigen::Vector2d(30, -20)).cwiseAbs().maxCoeff(),
            1e-6);
  t = zero;
  t.drift_t_um_h = 4.0;
  t.drift_z_um_h = -3.0;
  EXPECT_LT((raw(plan, simulateTooltip(plan, t, 1)) - s.problem.causes[2].J * Eigen::Vector2d(4, -3)).cwiseAbs().maxCoeff(),
            1e-9);
}

// Issue 16's reproduction: an isotropic 30 um/m scale of Y and Z, no pivot error, one tool.
// Never "effect found: pivot_length" alone: the judge finds the pair exactly confounded from the
// columns, with the closed form dR = 1 um moves the tip as s_Y = s_Z = -1000 / R um/m, and the
// signal is one finding that names both, read as whichever predicts held-out data better.
TEST(TooltipDiagnosis, Reproduction30umPerMScaleIsConfoundedWithPivotLength) {
  for (double R : {381.0, 150.0}) {
    const ProbePlan plan = planR(R);
    for (int seed = 1; seed <= 3; ++seed) {
      TooltipTruth t = truthOf(seed);
      t.scale_t_um_m = t.scale_z_um_m = 30.0;
      const TooltipDiagnosis d = run({&plan}, t, static_cast<std::uint64_t>(seed));
      if (seed == 1 && R == 381.0) std::printf("%s", tooltipDiagnosisText(d).c_str());
      ASSERT_EQ(d.summary.findings.size(), 1u) << tooltipDiagnosisText(d);
      const JudgeFinding& f = d.summary.findings[0];
      EXPECT_EQ(f.confounded_with.size(), 1u);
      EXPECT_TRUE(f.label() == "pivot_length or linear_axis_scale" || f.label() == "linear_axis_scale or pivot_length")
          << f.label();
      const JudgeConfounded* c = pairEntry(d.summary);
      ASSERT_NE(c, nullptr) << tooltipDiagnosisText(d);
      EXPECT_EQ(c->finding, f.cause);
      EXPECT_LT(c->angle_deg, 1e-4);
      const auto& pivot_terms = c->cause == "pivot_length" ? c->cause_terms : c->with_terms;
      const auto& scale_terms = c->cause == "pivot_length" ? c->with_terms : c->cause_terms;
      ASSERT_EQ(pivot_terms.size(), 1u);
      ASSERT_EQ(scale_terms.size(), 2u);
      for (const auto& st : scale_terms)
        EXPECT_NEAR(st.coefficient / pivot_terms[0].coefficient, -1000.0 / R, 1e-6 * 1000.0 / R) << st.name;
      // The estimate is the truth read in the finding's cause: s, or dR = -s R / 1000.
      for (const auto& p : f.parameters)
        EXPECT_LE(std::abs(p.value - (f.cause == "pivot_length" ? -30.0 * R / 1000.0 : 30.0)), 3.0 * p.u) << p.name;
      const Json j = tooltipDiagnosisJson(d);
      if (d.summary.final_model.passes) {
        EXPECT_EQ(j["verdict"], "effect_found");
      }
      EXPECT_EQ(j["findings"][0]["confounded_with"].size(), 1u);
      EXPECT_FALSE(j["findings"][0]["separate_with"].get<std::string>().empty());
      EXPECT_FALSE(j["confounded"][0]["separate_with"].get<std::string>().empty());
    }
  }
}

// A pivot-length error on one tool (dR = 10 um, 004's R = 381 mm; truth drawn by the simulator,
// noise as declared, the laser zero's included: it about doubles dR's u on one run, so 10 um is the
// multiple of u that 5 um was when the zero was taken as exact): the signal the plan cannot attribute is one finding naming pivot_length
// and the linear-axis scale, with how to separate them, its held-out gain > 0 and the truth
// within 3 u read in the finding's cause (dR, or s = -dR 1000 / R um/m). Before, the verdict was
// model_inadequate with no cause named.
TEST(TooltipDiagnosis, PivotLengthOnOneToolIsOneFindingWithTheScale) {
  const double R = 381.0;
  const ProbePlan plan = planR(R);
  int effect_found = 0, within_3u = 0;
  for (int seed = 1; seed <= 5; ++seed) {
    TooltipTruth t = truthOf(seed);
    t.dR_um = 10.0;
    const TooltipDiagnosis d = run({&plan}, t, static_cast<std::uint64_t>(40 + seed));
    const std::string text = tooltipDiagnosisText(d);
    if (seed == 1) std::printf("%s", text.c_str());
    ASSERT_EQ(d.summary.findings.size(), 1u) << text;
    // effect_found unless the model with the finding still misfits the declared noise (seed 2:
    // chi2 41.5 on 16 dof, then model_inadequate naming the same finding; the rate is below).
    EXPECT_EQ(d.summary.verdict, d.summary.final_model.passes ? JudgeVerdict::EffectFound : JudgeVerdict::ModelInadequate);
    effect_found += d.summary.verdict == JudgeVerdict::EffectFound;
    const JudgeFinding& f = d.summary.findings[0];
    EXPECT_EQ(f.confounded_with.size(), 1u);
    EXPECT_GT(f.gain, 0.0);
    EXPECT_GT(f.gain, 2.0 * f.gain_se);
    EXPECT_LT(f.holdout_rms_cause, f.holdout_rms_model);
    bool within = true;
    for (const auto& p : f.parameters)
      within = within && std::abs(p.value - (f.cause == "pivot_length" ? 10.0 : -10.0 * 1000.0 / R)) <= 3.0 * p.u;
    within_3u += within ? 1 : 0;
    // Read as either of the pair (the one the judge tried first leads, as the values above).
    EXPECT_TRUE(text.find("pivot_length or linear-axis scale: the plan cannot tell them apart; a second tool length") !=
                    std::string::npos ||
                text.find("linear-axis scale or pivot_length: the plan cannot tell them apart; a second tool length") !=
                    std::string::npos)
        << text;
    const Json j = tooltipDiagnosisJson(d);
    EXPECT_GT(j["findings"][0]["gain_pct"].get<double>(), 0.0);
    EXPECT_NE(j["findings"][0]["separate_with"].get<std::string>().find("second tool length"), std::string::npos);
  }
  EXPECT_GE(effect_found, 4);
  // The truth within 3 u in the finding's terms on at least 4 of 5: a seed outside has probability
  // about 0.5 % (two parameters at 0.27 %), two of five 2.5e-4 (one of these five lands at 3.5 u of dR: its
  // noise draw, the same whatever dR's size).
  EXPECT_GE(within_3u, 4);
}

// Power and false alarms of that finding over many seeds: dR = 5 um on one tool, 50 seeds, named
// (pivot_length with linear_axis_scale, effect_found) with the truth within 3 u in at least 45;
// clean data (the angular errors only, noise as declared), 200 seeds: any alarm, and a confounded
// finding in particular, no more often than alpha = 0.01 allows (more than 6 of 200 has binomial
// probability 4.3e-3 at that rate).
TEST(TooltipDiagnosis, PivotLengthOnOneToolIsFoundWithItsParametersWithin3u) {
  const double R = 381.0;
  const ProbePlan plan = planR(R);
  for (double dR : {5.0}) {
    int named = 0;
    for (int seed = 1; seed <= 50; ++seed) {
      TooltipTruth t = truthOf(seed);
      t.dR_um = dR;
      const TooltipDiagnosis d = run({&plan}, t, static_cast<std::uint64_t>(1000 + seed));
      if (d.summary.verdict != JudgeVerdict::EffectFound || d.summary.findings.size() != 1) continue;
      const JudgeFinding& f = d.summary.findings[0];
      if (f.confounded_with.size() != 1 || f.gain <= 0) continue;
      bool within = true;
      for (const auto& p : f.parameters)
        within = within && std::abs(p.value - (f.cause == "pivot_length" ? dR : -dR * 1000.0 / R)) <= 3.0 * p.u;
      named += within;
    }
    std::printf("tooltip dR = %g um on one tool: named with the scale, within 3 u, %d / 50\n", dR, named);
    EXPECT_GE(named, 45);
  }
}

TEST(TooltipDiagnosis, CleanOneToolConfoundedFindingFalseAlarmsWithinAlpha) {
  const ProbePlan plan = planR(381);
  int alarms = 0, confounded = 0;
  for (int seed = 1; seed <= 200; ++seed) {
    const TooltipDiagnosis d = run({&plan}, truthOf(seed), static_cast<std::uint64_t>(5000 + seed));
    alarms += d.summary.verdict != JudgeVerdict::NoSignificantEffect;
    for (const auto& f : d.summary.findings) confounded += !f.confounded_with.empty();
  }
  std::printf("tooltip clean, one tool: %d alarms, %d confounded findings in 200 seeds\n", alarms, confounded);
  EXPECT_LE(alarms, 6);
  EXPECT_LE(confounded, 6);
}

// The same scale with two tool lengths on the real plans (R = 381 and 200 mm, the same angles):
// a scale moves the tip in proportion to R, a pivot error does not; the principal angle between
// the two causes opens, the confounded pair disappears and the scale is found within 3 u. A
// 5 um pivot error alone is found as pivot_length within 3 u.
TEST(TooltipDiagnosis, TwoToolLengthsSeparatePivotFromScale) {
  const ProbePlan a = planR(381), b = planR(200);
  for (int seed = 1; seed <= 3; ++seed) {
    TooltipTruth t = truthOf(seed);
    t.scale_t_um_m = t.scale_z_um_m = 30.0;
    const TooltipDiagnosis d = run({&a, &b}, t, static_cast<std::uint64_t>(seed));
    if (seed == 1) std::printf("%s", tooltipDiagnosisText(d).c_str());
    EXPECT_EQ(pairEntry(d.summary), nullptr) << tooltipDiagnosisText(d);
    ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << tooltipDiagnosisText(d);
    ASSERT_EQ(d.summary.findings.size(), 1u);
    const JudgeFinding& f = d.summary.findings[0];
    EXPECT_EQ(f.cause, "linear_axis_scale");
    for (const auto& p : f.parameters) EXPECT_LE(std::abs(p.value - 30.0), 3.0 * p.u) << p.name;
    TooltipTruth tp = truthOf(seed);
    tp.dR_um = 5.0;
    const TooltipDiagnosis dp = run({&a, &b}, tp, static_cast<std::uint64_t>(seed + 10));
    ASSERT_EQ(dp.summary.verdict, JudgeVerdict::EffectFound) << tooltipDiagnosisText(dp);
    EXPECT_EQ(dp.summary.findings[0].cause, "pivot_length");
    EXPECT_LE(std::abs(dp.summary.findings[0].parameters[0].value - 5.0), 3.0 * dp.summary.findings[0].parameters[0].u);
  }
}

// Two tool lengths where the screen of gross readings left one reading of the first tool out
// (both components NaN, as withoutScreened does): its angle has no value in the first set's fit
// (the linearisation point), and the judge still reads the second set's reading of that angle
// (once a non-finite y, a throw). A 5 um pivot error is found within 3 u of the simulator's truth.
TEST(TooltipDiagnosis, TwoToolLengthsWithAReadingLeftOutOfTheFirst) {
  const ProbePlan a = planR(381), b = planR(200);
  for (int seed = 1; seed <= 3; ++seed) {
    TooltipTruth t = truthOf(seed);
    t.dR_um = 5.0;
    TooltipRun first = simulateTooltip(a, t, static_cast<std::uint64_t>(60 + seed));
    for (auto& r : first)
      if (std::abs(r.angle_deg - 45.0) < 1e-9) r.t_um = r.z_um = std::numeric_limits<double>::quiet_NaN();
    const TooltipDiagnosis d = diagnoseTooltip({{&a, {first}}, {&b, {simulateTooltip(b, t, static_cast<std::uint64_t>(70 + seed))}}}, {});
    ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << tooltipDiagnosisText(d);
    EXPECT_EQ(d.summary.findings[0].cause, "pivot_length");
    EXPECT_LE(std::abs(d.summary.findings[0].parameters[0].value - 5.0), 3.0 * d.summary.findings[0].parameters[0].u);
  }
}

// A tip drift of 6 um/h (dY) in the dynamic test of 004 Sec. VI (2 sweeps 0 -> 90 -> -90 -> 0,
// each angle read at several times): found as thermal_drift within 3 u. A static test with
// repeats does not offer the drift (each angle at the same time since its zero).
TEST(TooltipDiagnosis, DriftInTheDynamicTestIsFound) {
  const ProbePlan plan = planR(381, {{"sweeps", "2"}});
  for (int seed = 1; seed <= 3; ++seed) {
    TooltipTruth t = truthOf(seed);
    t.drift_t_um_h = 6.0;
    const TooltipDiagnosis d = run({&plan}, t, static_cast<std::uint64_t>(seed));
    if (seed == 1) std::printf("%s", tooltipDiagnosisText(d).c_str());
    ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << tooltipDiagnosisText(d);
    const JudgeFinding& f = d.summary.findings[0];
    EXPECT_EQ(f.cause, "thermal_drift");
    EXPECT_LE(std::abs(f.parameters[0].value - 6.0), 3.0 * f.parameters[0].u);
    EXPECT_LE(std::abs(f.parameters[1].value), 3.0 * f.parameters[1].u);
  }
  const ProbePlan fixed = planR(381);
  EXPECT_EQ(run({&fixed}, truthOf(1), 1, 3).setup.problem.causes.size(), 2u);
}

// Clean data (angular errors only, noise as declared): at alpha 0.01, 3 or more alarms in 12
// seeds has binomial probability 2.0e-4 (the benchmark runs 200).
TEST(TooltipDiagnosis, CleanFalseAlarmsWithinAlpha) {
  const ProbePlan plan = planR(381);
  int alarms = 0;
  for (int seed = 1; seed <= 12; ++seed) {
    const TooltipDiagnosis d = run({&plan}, truthOf(seed), static_cast<std::uint64_t>(300 + seed));
    alarms += d.summary.verdict != JudgeVerdict::NoSignificantEffect;
    if (d.summary.verdict == JudgeVerdict::NoSignificantEffect) {
      EXPECT_NE(d.summary.message.find("within the declared noise"), std::string::npos);
    }
  }
  std::printf("tooltip clean: %d false alarms in 12 seeds\n", alarms);
  EXPECT_LE(alarms, 2);
}

}  // namespace
}  // namespace rotacal
