// R-test machines as their contributors declare them (simulate --contributors): 002's
// contributors (examples/contributors/rtest_002.json: the sensors' gain and cross-talk, the
// sphere's offset, the drift within a cycle, the linear axes of 000 Table 5) drawn into whole
// machines with known location errors. Diagnosed with the same contributors, the judge says
// model_inadequate no more often than its alpha; analyze's U covers the location errors about as
// often as it claims.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fmt/format.h>

#include "core/machine.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/rtest/budget.hpp"
#include "cycles/rtest/diagnose.hpp"
#include "cycles/rtest/plan.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

/// 002's thermal series, shortened to four cycles over an hour (the judge's cost grows with the
/// cube of the readings).
ProbePlan planShort() {
  return makePlan("rtest", loadMachine(test::sourcePath("examples/machines/bc_trunnion.json")),
                  {{"thermal", "1"}, {"interval_min", "20"}, {"duration_h", "1"}, {"sensor_noise_um", "0.2"}});
}

// The eight location errors of the B/C table, um / mdeg (order of locationParameters).
constexpr double kTruth[8] = {6.0, -4.0, 3.0, 2.5, -1.5, 2.0, 3.5, -7.0};

std::string truthText() {
  const auto& info = locationParameters(Kinematics::TableBC);
  std::string e;
  for (int q = 0; q < 8; ++q)
    e += fmt::format("{}\"{}\": {{\"value\": {}, \"unit\": \"{}\"}}", q ? ", " : "", info[static_cast<size_t>(q)].name,
                     kTruth[q], info[static_cast<size_t>(q)].kind == ParamKind::Length ? "um" : "mdeg");
  return "{\"format\": \"rotacal-truth/1\", \"location_errors\": {" + e + "}}";
}

Simulated simulateDrawn(const ProbePlan& plan, const ContributorSet& cs, std::uint64_t machine_seed, std::uint64_t seed) {
  SimulateRequest r;
  r.plan = &plan;
  r.truth = {"truth.json", truthText()};
  r.contributors = &cs;
  r.machine_seed = machine_seed;
  r.seed = seed;
  return cycleByName("rtest").simulate(r);
}

TEST(RtestRealMachine, DrawnMachineIsRecordedInTheTruth) {
  const ProbePlan plan = planShort();
  const ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/rtest_002.json"));
  const Simulated a = simulateDrawn(plan, cs, 7, 1), b = simulateDrawn(plan, cs, 8, 1);
  ASSERT_TRUE(a.truth.contains("drawn"));
  // The declared per reading (sensors 0.2 um, sphere form 0.1 um) is the noise simulated.
  EXPECT_NEAR(a.truth["drawn"]["per_reading_um"].get<double>(), std::sqrt(0.2 * 0.2 + 0.1 * 0.1), 1e-6);
  EXPECT_NEAR(a.truth["noise_um"].get<double>(), a.truth["drawn"]["per_reading_um"].get<double>(), 1e-6);
  EXPECT_TRUE(a.truth["drawn"].contains("linear_axes"));
  EXPECT_NE(a.truth["drawn"]["sphere_offset_um"], b.truth["drawn"]["sphere_offset_um"]);
  EXPECT_NE(a.results_text, b.results_text);
  // The same machine seed, the same machine.
  EXPECT_EQ(simulateDrawn(plan, cs, 7, 1).results_text, a.results_text);
}

// 30 machines drawn from 002's contributors, four cycles each with the declared noise, diagnosed
// and analyzed with the same contributors (the screen whitening by the structured part too). At the judge's alpha (1 %) model_inadequate may come
// out on at most 2 (binomial: P(X >= 3) = 0.33 %); U (95.45 %) covers the location errors' truth
// on at least 85 % of the 240 (correlated within a machine: a loose bound). The same machines
// judged and screened against the white part alone (what diagnose read before) beside.
TEST(RtestRealMachine, JudgeAndBudgetKeepTheirRatesOnDrawnMachines) {
  const ProbePlan plan = planShort();
  const ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/rtest_002.json"));
  const auto& info = locationParameters(Kinematics::TableBC);
  const int machines = 30;
  int inadequate = 0, effect = 0, white_inadequate = 0, in = 0, all = 0, screened = 0, white_screened = 0;
  for (int m = 1; m <= machines; ++m) {
    const Simulated s = simulateDrawn(plan, cs, static_cast<std::uint64_t>(m), static_cast<std::uint64_t>(500 + m));
    DiagnoseRequest dr;
    dr.plan = &plan;
    dr.results = {{"r.csv", s.results_text}};
    dr.contributors = &cs;
    const CycleDocuments dg = cycleByName("rtest").diagnose(dr);
    const std::string verdict = dg.doc["verdict"].get<std::string>();
    inadequate += verdict == "model_inadequate" ? 1 : 0;
    effect += verdict == "effect_found" ? 1 : 0;
    {
      const std::vector<RtestCycle> cycles = parseRtestResults(s.results_text, "r.csv", plan).cycles;
      const DeclaredNoise white = rtestDeclaredNoise(plan, &cs);
      RtestDiagnosisOptions o;
      o.sensor_sigma_um = 0.2;
      o.reading_sigma_um = std::sqrt(white.white_um2);
      o.declaration = white.declaration;
      white_inadequate += diagnoseRtest(plan, cycles, o).summary.verdict == JudgeVerdict::ModelInadequate ? 1 : 0;
    }
    // analyze's location errors and their budget (what REPORT.json's location_errors sign), as
    // the cycle computes them; the per-tilt budget it also runs is not needed here.
    const std::vector<RtestCycle> cycles = parseRtestResults(s.results_text, "r.csv", plan).cycles;
    const DeclaredNoise noise = rtestDeclaredNoise(plan, &cs, &cycles.front());
    RtestFitOptions fo;
    fo.sensor_sigma_um = 0.2;
    fo.reading_sigma_um = std::sqrt(noise.white_um2);
    fo.declaration = noise.declaration;
    fo.structured_um2 = noise.structured_um2;
    fo.structured_draws_um = noise.structured_draws_um;
    const RtestAnalysis a = analyzeRtest(plan, cycles, fo);
    ASSERT_TRUE(a.location.identifiable);
    RtestBudgetOptions bo;
    bo.runs = 300;
    bo.seed = static_cast<std::uint64_t>(m);
    const UncertaintyBudget b = rtestBudget(plan, cycles.front(), a.location, 0.2, &cs, bo);
    const Eigen::VectorXd U = b.expanded();
    for (int q = 0; q < 8; ++q) {
      const bool length = info[static_cast<size_t>(q)].kind == ParamKind::Length;
      const double value = length ? mmToUm(a.location.value[q]) : radToMdeg(a.location.value[q]);
      ++all;
      in += std::abs(value - kTruth[q]) <= U[q] ? 1 : 0;
    }
    screened += a.screen.screen.excluded.empty() && !a.screen.screen.too_many ? 0 : 1;
    {
      RtestFitOptions wo = fo;
      wo.structured_um2.resize(0, 0);
      const RtestScreen w = analyzeRtest(plan, cycles, wo).screen;
      white_screened += w.screen.excluded.empty() && !w.screen.too_many ? 0 : 1;
    }
  }
  std::printf("rtest on %d drawn machines: model_inadequate %d, effect_found %d (the drawn drift); against the white part "
              "alone: model_inadequate %d; U covers the location errors %d of %d; the screen lost a value on %d (against the white "
              "part alone: %d)\n",
              machines, inadequate, effect, white_inadequate, in, all, screened, white_screened);
  EXPECT_LE(inadequate, 2);
  EXPECT_GE(in, static_cast<int>(0.85 * all));
  EXPECT_GT(white_inadequate, machines / 2);  // the test can fail: the white part alone misdeclares these machines
  // The screen: a drawn machine's nodes sit at ONE spacing, a scale mixture over machines with a
  // heavier tail than the covariance's Gaussian; its threshold reads that tail from draws of the
  // declared machine (without them 3 of these 30 lost a value). At its 1 %, at most 2 of 30
  // (Binomial(30, 0.01) reaches 3 with probability 0.3 %). Against the white part alone most
  // series lose a value: the declaration is what the screen reads.
  EXPECT_LE(screened, 2);
  EXPECT_GT(white_screened, machines / 2);
}

}  // namespace
}  // namespace rotacal
