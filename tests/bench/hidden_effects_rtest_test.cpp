// The rtest catalog on R-test machines as their contributors file declares them, not on clean
// ones: each machine drawn by the independent generator (bench/independent_rtest.hpp: 002's B/C
// table, the nest's sensors with their gain and direction errors, the sphere's offset and form,
// the per-cycle drift, the linear axes of 000 Table 5) from examples/contributors/rtest_002.json,
// the effect added through rotacal's R-test simulator (bench/drawn_effects_rtest.hpp), judged as
// `rotacal diagnose` judges it against that declaration. The rates over 200 / 50 machines are in
// docs/diagnosis.md (build/bench/rotacal_diagnose_bench rtest_drawn); the seeds here are not the
// bench's.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bench/drawn_effects_rtest.hpp"
#include "bench/independent_rtest.hpp"
#include "core/contributors.hpp"
#include "core/machine.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/rtest/diagnose.hpp"
#include "cycles/rtest/plan.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

constexpr double kAlpha = 0.01;  // the CLI's default

struct RtestWorld {
  MachineModel machine = loadMachine(test::sourcePath("examples/machines/bc_trunnion.json"));
  ContributorSet declared = loadContributors(test::sourcePath("examples/contributors/rtest_002.json"));
  ProbePlan plan;
  explicit RtestWorld(const CycleOptions& o) : plan(makePlan("rtest", machine, o)) {}

  RtestDiagnosis judge(std::uint64_t seed, const independent::RtestEffect& effect, bool drift = true,
                       independent::RtestMachine* drawn_out = nullptr) const {
    independent::RtestDrawOptions d;
    d.drift = drift;
    const independent::RtestMachine m = independent::drawRtestMachine(declared, plan, d, seed);
    if (drawn_out) *drawn_out = m;
    return independent::diagnoseAsDeclared(plan, declared, independent::measureRtestWithEffect(plan, m, effect).cycles, kAlpha);
  }
  std::string text(const RtestDiagnosis& d) const { return rtestDiagnosisText(plan, d); }
};

const RtestWorld& oneCycle() {
  static const RtestWorld w(CycleOptions{});
  return w;
}
const RtestWorld& thermal() {  // 002's schedule: a cycle every 15 min over 3 h
  static const RtestWorld w(CycleOptions{{"thermal", "1"}});
  return w;
}

void noEffect(Truth*, RtestTruthExtras*) {}

independent::RtestEffect stepX(double at_s, double um) {
  return [at_s, um](Truth*, RtestTruthExtras* x) { x->sensor_steps.push_back({at_s, Eigen::Vector3d(umToMm(um), 0, 0)}); };
}

// The superposition against a closed form: a sensor step of 1 um from a time on is exactly 1 um
// more in x in every reading from then on, and nothing before or in y, z.
TEST(DrawnRtest, SuperposedStepIsTheStepInTheReadings) {
  const RtestWorld& w = thermal();
  const independent::RtestMachine m = independent::drawRtestMachine(w.declared, w.plan, {}, 31000);
  const double at = 6 * rtestSchedule(w.plan).interval_s - 60.0;
  const RtestSeries a = independent::measureRtest(w.plan, m);
  const RtestSeries b = independent::measureRtestWithEffect(w.plan, m, stepX(at, 1.0));
  ASSERT_EQ(a.cycles.size(), b.cycles.size());
  for (size_t c = 0; c < a.cycles.size(); ++c)
    for (size_t i = 0; i < a.cycles[c].readings.size(); ++i) {
      const RtestReading &ra = a.cycles[c].readings[i], &rb = b.cycles[c].readings[i];
      const Eigen::Vector3d d = rb.dq_w_mm - ra.dq_w_mm;
      EXPECT_NEAR(mmToUm(d.x()), ra.t_s >= at ? 1.0 : 0.0, 1e-9);
      EXPECT_NEAR(d.tail<2>().norm(), 0.0, 1e-12);
    }
}

TEST(DrawnRtest, CleanSeedsRaiseNoCauseOnMachinesAsDeclared) {
  // 20 machines on the bundled example's one cycle and 2 on 002's thermal schedule with the drawn
  // drift switched off (the generator's other draws as they were; with it on, the machine drifts
  // as declared: HiddenDriftFoundOverTheThermalSchedule). At alpha 1 % two or more alarms in 22
  // has probability 2.0 % under a correct judge.
  // On the one cycle the linear axes' node spacing is one value, 35 mm (the middle of the file's
  // 20-50 mm), in the draw and in the declaration alike: with the spacing drawn per machine the
  // declaration's node correlation, averaged over the spacing, is the mixture's covariance but
  // not its distribution, and the judge, whitening 0.22 um readings by 5.4 um of shared part,
  // raises 7 in 200 clean machines (docs/diagnosis.md; 2, 0, 0 in 200 at a spacing of 20, 35,
  // 50 mm). That is what this test does not hide: it tests the judge where the declaration is
  // the machine's distribution.
  RtestWorld one{CycleOptions{}};
  one.declared.node_spacing_min_mm = one.declared.node_spacing_max_mm = 35.0;
  int alarms = 0;
  for (std::uint64_t seed = 31100; seed < 31120; ++seed) {
    const RtestDiagnosis d = one.judge(seed, noEffect);
    alarms += d.summary.verdict != JudgeVerdict::NoSignificantEffect;
  }
  for (std::uint64_t seed = 31200; seed < 31202; ++seed) {
    const RtestDiagnosis d = thermal().judge(seed, noEffect, false);
    alarms += d.summary.verdict != JudgeVerdict::NoSignificantEffect;
    EXPECT_TRUE(d.summary.findings.empty()) << thermal().text(d);
  }
  EXPECT_LE(alarms, 1);
}

TEST(DrawnRtest, HiddenDriftFoundOverTheThermalSchedule) {
  // The machine as declared carries 002's drift over its schedule: rtest_cycle_drift's 0.05, 0.1,
  // 0.05 um per 155 s cycle held over 3 h is 1.2, 2.3, 1.2 um/h at 1 sigma, a drift of the sphere
  // against the table. It is named thermal_drift, the linear axes' drift explains it (the judge's
  // nested tests, from the plan's Jacobians), and the table's dy_CB slope is the drawn sphere's Y
  // rate with its sign turned (a sphere moving by v reads as the table moving by -v), within 3 u.
  const RtestWorld& w = thermal();
  for (std::uint64_t seed = 31300; seed < 31302; ++seed) {
    independent::RtestMachine m;
    const RtestDiagnosis d = w.judge(seed, noEffect, true, &m);
    const JudgeFinding* f = d.summary.finding("thermal_drift");
    ASSERT_NE(f, nullptr) << w.text(d);
    bool linear_explains = false;
    for (const RtestConfound& c : d.confounds) linear_explains = linear_explains || (c.entry.cause == "linear_axis_drift" && c.explains);
    EXPECT_TRUE(linear_explains) << w.text(d);
    const JudgeEstimate* e = f->parameter("dy_CB(B=30)/h");
    ASSERT_NE(e, nullptr);
    EXPECT_NEAR(e->value, -independent::drawnSphereDriftUmPerH(m).y(), 3.0 * e->u) << w.text(d);
  }
}

TEST(DrawnRtest, HiddenDriftFoundInTheTableBeyondTheDeclaration) {
  // 002 Sec. 4.4's c_BY drift, 0.3 mdeg/h at every B, on top of the machine as declared: a
  // rotation of the table, which no drift of the sphere (all the declaration makes) reads as:
  // worded as the table's errors, the slope within 3 u.
  const RtestWorld& w = thermal();
  for (std::uint64_t seed = 31400; seed < 31402; ++seed) {
    const RtestDiagnosis d = w.judge(seed, [](Truth* t, RtestTruthExtras*) {
      t->drift = [](double s) {
        ErrorVector v = ErrorVector::Zero();
        v[5] = mdegToRad(0.3 * s / 3600.0);
        return v;
      };
    });
    ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << w.text(d);
    const JudgeFinding* f = d.summary.finding("thermal_drift");
    ASSERT_NE(f, nullptr) << w.text(d);
    EXPECT_NE(rtestFindingSummary(w.plan, d, *f).find("the rotary table's errors change"), std::string::npos) << w.text(d);
    const JudgeEstimate* e = f->parameter("c_BY(B=30)/h");
    ASSERT_NE(e, nullptr);
    EXPECT_NEAR(e->value, 0.3, 3.0 * e->u) << w.text(d);
  }
}

TEST(DrawnRtest, HiddenGlitchFoundAsASensorStep) {
  // 1 um along x (the clean-world tests' step, 4.5 times the declared 0.224 um of a reading):
  // between cycles 6 and 7, and in cycle 7 after its last pose (before its re-read), each named
  // as that candidate beside the drawn drift, dx within 3 u of 1 um.
  const RtestWorld& w = thermal();
  const double interval = rtestSchedule(w.plan).interval_s;
  const std::vector<double> reads = rtestReadTimes(w.plan);
  struct Case {
    double at_s;
    const char* cause;
  };
  for (const Case& c : {Case{6 * interval - 60.0, "sensor_step_cycle_7"},
                        Case{6 * interval + 0.5 * (w.plan.points.back().t_s + reads.back()), "sensor_step_in_cycle_7"}})
    for (std::uint64_t seed = 31500; seed < 31501; ++seed) {
      const RtestDiagnosis d = w.judge(seed, stepX(c.at_s, 1.0));
      ASSERT_EQ(d.summary.verdict, JudgeVerdict::EffectFound) << w.text(d);
      const JudgeFinding* f = d.summary.finding(c.cause);
      ASSERT_NE(f, nullptr) << c.cause << "\n" << w.text(d);
      EXPECT_NEAR(f->parameter("dx")->value, 1.0, 3.0 * f->parameter("dx")->u) << w.text(d);
      // The drawn drift beside it is still the linear axes' (the nested judgements keep the step).
      bool linear_explains = false;
      for (const RtestConfound& k : d.confounds) linear_explains = linear_explains || (k.entry.cause == "linear_axis_drift" && k.explains);
      EXPECT_TRUE(linear_explains) << w.text(d);
    }
  // The bundled example's one cycle: the same step before its re-read is analyze's re-read check's
  // (the reset against its re-read, beside the judge): with one cycle the judge's leave-one-cycle-
  // out has no second fold, so no held-out gain names a cause there (docs/diagnosis.md). The
  // bench flags it on 35 of 50 machines (70 %): at that rate at least 1 of 3 with probability 97 %.
  const RtestWorld& o = oneCycle();
  const std::vector<double> r1 = rtestReadTimes(o.plan);
  int flagged = 0;
  for (std::uint64_t seed = 31600; seed < 31603; ++seed) {
    const RtestDiagnosis d = o.judge(seed, stepX(0.5 * (o.plan.points.back().t_s + r1.back()), 1.0));
    ASSERT_EQ(d.analysis.cycles.size(), 1u);
    flagged += d.analysis.cycles[0].sensor_step;
  }
  EXPECT_GE(flagged, 1);
}

}  // namespace
}  // namespace rotacal
