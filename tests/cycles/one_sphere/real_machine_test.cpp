// one_sphere on machines as their own contributors file declares them (the bundled A/C machine
// and examples/contributors/table5.json, 000 Table 5): the probe's pretravel, the linear axes of
// 000 Eqs. (22)-(23), the set-up and the per-touch scatter, drawn by drawMachine around 000
// Table 4's location errors and measured by the exact simulator, whose truth the fit never sees.
// The outlier screen and the judge read the declared covariance of the touches
// (sphereDeclaredNoise): on such machines they must keep their stated rates (alpha = 1 % each),
// still catch a 20 um chip, and no gross error may reach an offsets file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "controllers/dialect.hpp"
#include "core/contributor_draw.hpp"
#include "core/contributors.hpp"
#include "core/errors.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/one_sphere/analyze.hpp"
#include "cycles/one_sphere/diagnose.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

constexpr int kMachines = 20;

struct Bench {
  MachineModel machine = test::acMachine();
  ProbePlan plan = makePlan("one_sphere", machine, {});
  ContributorSet contributors = loadContributors(test::sourcePath("examples/contributors/table5.json"));
  DeclaredNoise noise = sphereDeclaredNoise(plan, &contributors);

  MeasurementRun measure(int m) const {
    Truth t = test::truthWith(test::table4Mean());
    drawMachine(plan, contributors, 6000 + static_cast<std::uint64_t>(m), &t);
    return simulate(plan, t, {static_cast<std::uint64_t>(800 + m)});
  }
  /// The touch of plan point index k moved by `along_mm` along its approach (negative: a chip,
  /// the probe stops early; positive: a late trigger).
  MeasurementRun moved(MeasurementRun run, size_t k, double along_mm) const {
    for (auto& t : run.points)
      if (t.point_id == plan.points[k].id) t.position_m_mm += along_mm * plan.points[k].approach_m;
    return run;
  }
  bool excluded(const OutlierScreen& s, size_t k) const {
    for (const auto& e : s.excluded)
      if (e.point_id == plan.points[k].id) return true;
    return false;
  }
};

DialectIO csvIO() {
  const Dialect& d = dialectByName("csv");
  return {std::string(d.name()),
          [&d](const std::string& text, const std::string& file, const ProbePlan& plan) {
            return d.parseResults(text, file, plan);
          },
          [&d](const ProbePlan& plan, const MeasurementRun& run) { return d.writeResults(plan, run); }};
}

TEST(OneSphereRealMachine, TheScreenAndTheJudgeKeepTheirRatesAndCatchAChip) {
  const Bench b;
  ASSERT_GT(b.noise.structured_um2.size(), 0);
  EXPECT_NEAR(b.noise.white_um2, 0.7 * 0.7 + 1.0 * 1.0, 1e-9);  // table5's repeatability and roughness
  const DeclaredNoise repeatability = repeatabilityOnly(b.machine.probe.repeatability_um, "MACHINE.json");
  const size_t n = b.plan.points.size();
  int screened = 0, too_many = 0, inadequate = 0, caught = 0, old_screened = 0, old_inadequate = 0;
  double chi2_per_dof = 0.0;
  for (int m = 0; m < kMachines; ++m) {
    const MeasurementRun run = b.measure(m);
    const SphereScreen s = screenSphereTouches(b.plan, {run}, b.noise);
    screened += s.screen.excluded.empty() ? 0 : 1;
    {
      const SphereFittedProblem f = sphereFittedProblem(b.noise, s.fit);
      const DeclaredNoiseTest dt = testAgainstDeclared(f.residual_um, f.J, f.covariance_um2);
      chi2_per_dof += dt.chi2 / dt.dof / kMachines;
    }
    too_many += s.screen.too_many ? 1 : 0;
    const SphereScreen old = screenSphereTouches(b.plan, {run}, repeatability);
    old_screened += (old.screen.too_many || !old.screen.excluded.empty()) ? 1 : 0;
    const SphereDiagnosis d = diagnoseSphere(b.plan, {run}, JudgeOptions{}, &b.contributors);
    // Its adequacy test reads its null from draws of the declared machine, as analyze's does.
    EXPECT_EQ(d.summary.baseline.null_draws, kDeclaredNullDraws);
    if (d.summary.verdict == JudgeVerdict::ModelInadequate) {
      ++inadequate;
      std::printf("machine %d: %s\n", m, d.summary.message.c_str());
    }
    old_inadequate += diagnoseSphere(b.plan, {run}, JudgeOptions{}).summary.verdict == JudgeVerdict::ModelInadequate;
    // A 20 um chip at a touch chosen by the machine's index.
    const size_t k = (37 * static_cast<size_t>(m)) % n;
    caught += b.excluded(screenSphereTouches(b.plan, {b.moved(run, k, -0.020)}, b.noise).screen, k) ? 1 : 0;
  }
  std::printf("mean chi2 / dof of the whitened residual: %.3f\n", chi2_per_dof);
  std::printf("%d drawn machines (%zu touches each): screen removed a touch on %d (too many on %d), model_inadequate "
              "on %d, 20 um chip caught on %d; against the repeatability alone: screen flagged %d, model_inadequate %d\n",
              kMachines, n, screened, too_many, inadequate, caught, old_screened, old_inadequate);
  // The declaration is the drawn machines' own: the whitened residual's chi2 / dof averages 1
  // (its sd over 20 machines at 53 dof is sqrt(2 / 53 / 20) = 0.043; 0.15 is over 3 of them).
  EXPECT_NEAR(chi2_per_dof, 1.0, 0.15);
  // alpha = 1 % each: Binomial(20, 0.01) exceeds 2 with probability 0.001.
  EXPECT_LE(screened, 2);
  EXPECT_EQ(too_many, 0);
  EXPECT_LE(inadequate, 2);
  EXPECT_GE(caught, kMachines - 1);
}

TEST(OneSphereRealMachine, NoGrossErrorReachesTheOffsets) {
  // Through the cycle's analyze, as `rotacal analyze --offsets` calls it: a 1 mm chip on every
  // machine, and on the first a 5 mm chip and a 1.9 mm late trigger. Each is either refused by
  // the results reader, or excluded by name with offsets equal to those of the same machine's
  // clean touches less that one (to 1e-6 um / mdeg: the screen left out the chip and nothing
  // else), or no offsets at all.
  const Bench b;
  const Cycle& cycle = cycleByName("one_sphere");
  const DialectIO io = csvIO();
  const auto analyze = [&](const MeasurementRun& run) {
    AnalyzeRequest a;
    a.plan = &b.plan;
    a.dialect = &io;
    a.contributors = &b.contributors;
    a.mc_runs = 200;
    a.results = {{"results.csv", io.write_results(b.plan, run)}};
    return cycle.analyze(a);
  };
  const size_t n = b.plan.points.size();
  int caught = 0, cases = 0;
  double worst_unscreened_mdeg = 0.0;
  const int a_AY = parameterIndex(Kinematics::TableAC, "a_AY");
  for (int m = 0; m < kMachines; ++m) {
    const MeasurementRun run = b.measure(m);
    const CycleDocuments clean = analyze(run);
    ASSERT_TRUE(clean.offsets.has_value());
    const size_t k = (53 * static_cast<size_t>(m) + 11) % n;
    std::vector<std::pair<std::string, double>> errors = {{"1 mm chip", -1.0}};
    if (m == 0) errors.insert(errors.end(), {{"5 mm chip", -5.0}, {"1.9 mm late trigger", 1.9}});
    for (const auto& [what, along] : errors) {
      const MeasurementRun bad = b.moved(run, k, along);
      ++cases;
      CycleDocuments rep;
      try {
        rep = analyze(bad);
      } catch (const InputError& e) {
        std::printf("machine %d, %s at point %d: refused by the reader (%s)\n", m, what.c_str(), b.plan.points[k].id, e.what());
        ++caught;
        continue;
      }
      // Without the screen: what the offsets would have been.
      const SphereCycleResult unscreened = identifySphereCycle(b.plan, {bad});
      worst_unscreened_mdeg = std::max(worst_unscreened_mdeg, std::abs(unscreened.location.reportValue(a_AY) -
                                                                        clean.offsets->identified.reportValue(a_AY)));
      bool named = false;
      for (const auto& e : rep.doc["outliers"]["excluded"]) named = named || e["point"].get<int>() == b.plan.points[k].id;
      caught += named ? 1 : 0;
      EXPECT_TRUE(named) << "machine " << m << ", " << what << ": " << rep.doc["outliers"]["summary"].get<std::string>();
      if (named && along == -1.0) {
        // The report's figure against A shows the chip where the simulator put it: among the
        // touches left out, at its pose's A, about 1000 um outward (the chip stops the ball early,
        // away from the sphere; the linear axes' declared errors move it by a few um).
        const Json& figs = rep.doc["figures"];
        ASSERT_GE(figs.size(), 3u);
        EXPECT_EQ(figs[0]["id"], "one_sphere_residual_a");
        ASSERT_EQ(figs[0]["series"].size(), 2u);
        EXPECT_EQ(figs[0]["series"][0]["x"].size(), n - rep.doc["outliers"]["excluded"].size());
        const Json& left = figs[0]["series"][1];
        bool shown = false;
        for (size_t i = 0; i < left["x"].size(); ++i)
          shown = shown || (std::abs(left["x"][i].get<double>() - b.plan.points[k].pose.A) < 1e-6 &&
                            std::abs(left["y"][i].get<double>() - 1000.0) < 10.0);
        EXPECT_TRUE(shown) << "machine " << m << ": " << left.dump();
      }
      if (!rep.offsets_refused.empty() || !rep.offsets) continue;
      // The clean measurement of the same machine with that touch held out: what the offsets
      // must be when the screen left out the chipped touch and nothing else.
      const int id = b.plan.points[k].id;
      const SphereCycleResult without =
          identifySphereCycle(b.plan, {run}, {[id](int, const ProbePoint& p) { return p.id == id; }});
      EXPECT_FALSE(rep.warnings.empty()) << "an excluded touch is named on stderr";
      for (int i = 0; i < kNumLocationErrors; ++i) {
        const auto& q = locationParameters(Kinematics::TableAC)[static_cast<size_t>(i)];
        const double got = rep.offsets->identified.reportValue(i), want = without.location.reportValue(i);
        EXPECT_NEAR(got, want, 1e-6) << "machine " << m << ", " << what << ", " << q.name;
      }
    }
  }
  std::printf("%d gross errors: %d caught; unscreened they would move a_AY by up to %.1f mdeg\n", cases, caught,
              worst_unscreened_mdeg);
  EXPECT_EQ(caught, cases);
  // The screen matters: the same errors left in move a_AY far beyond its u_c (tenths of a mdeg).
  EXPECT_GT(worst_unscreened_mdeg, 1.0);
}

}  // namespace
}  // namespace rotacal
