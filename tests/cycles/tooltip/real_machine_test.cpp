// Tooltip machines as their contributors declare them (simulate --contributors): 004 Sec. VII's
// contributors (examples/contributors/tooltip_004.json) drawn into whole machines. The drawn
// machines' spread against a draw written here (node grid, node values, beam tilts, from the
// contributors' figures, not the product's draw code); on 50 drawn machines the judge's, the
// screen's and the hold-back's rates stay within their alphas and the budget's U covers the truth
// about as often as it claims.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>

#include "core/rng.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/tooltip/noise.hpp"
#include "cycles/tooltip/plan.hpp"
#include "cycles/tooltip/screen.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

ProbePlan plan004() {
  return makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")),
                  {{"units", "mm"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}, {"repeats", "1"}});
}

const char* kTruth = R"({"format": "rotacal-truth/1", "tooltip": {"dR_um": 0.0,
  "angular_error": {"offset_mdeg": 3.0, "slope_mdeg_per_90deg": 5.0, "sin_mdeg": -2.0, "sin2_mdeg": 1.5}}})";

/// The head of the truth file: 004-sized angular errors and the pivot length as programmed, so
/// that 004's model (diagnose's baseline) holds and every alarm on these machines is false.
TooltipTruth truthHead() {
  TooltipTruth t;
  t.dR_um = 0.0;
  t.offset_mdeg = 3.0;
  t.slope_mdeg_per_90deg = 5.0;
  t.sin_mdeg = -2.0;
  t.sin2_mdeg = 1.5;
  return t;
}

Simulated simulateDrawn(const ProbePlan& plan, const ContributorSet& cs, std::uint64_t machine_seed, std::uint64_t seed,
                        std::optional<double> noise_um = std::nullopt) {
  SimulateRequest r;
  r.plan = &plan;
  r.truth = {"truth.json", kTruth};
  r.contributors = &cs;
  r.machine_seed = machine_seed;
  r.seed = seed;
  r.noise_um = noise_um;
  return cycleByName("tooltip").simulate(r);
}

TooltipRun readBack(const ProbePlan& plan, const Simulated& s) {
  const std::vector<TooltipRun> runs = parseTooltipResults(s.results_text, "r.csv", plan);
  EXPECT_EQ(runs.size(), 1u);
  return runs.front();
}

Eigen::VectorXd values(const TooltipRun& run) {
  Eigen::VectorXd v(2 * static_cast<Eigen::Index>(run.size()));
  for (size_t k = 0; k < run.size(); ++k) {
    v[2 * static_cast<Eigen::Index>(k)] = run[k].t_um;
    v[2 * static_cast<Eigen::Index>(k) + 1] = run[k].z_um;
  }
  return v;
}

/// One machine of tooltip_004.json drawn here: per linear axis a node spacing uniform in
/// [20, 50] mm, nodes at its multiples, N(0, 9 um) each in that axis's own direction, linear in
/// between; each beam tilted N(0, 2 mrad) in and out of the read plane. What the readings of the
/// A sweep (transverse = Y) change by against the head alone, um.
Eigen::VectorXd ownDraw(const ProbePlan& plan, const TooltipRun& head, Rng& rng) {
  const std::vector<int> refs = tooltipReferences(plan);
  double spacing[3];
  std::vector<double> node[3];
  for (int a = 0; a < 3; ++a) {
    spacing[a] = 20.0 + 30.0 * rng.uniform();
    node[a].resize(64);
    for (double& v : node[a]) v = 9.0 * rng.normal();
  }
  // Node i sits at (i - 32) x spacing: the plan's pivots lie within +-400 mm.
  auto err = [&](const Eigen::Vector3d& c) {
    Eigen::Vector3d e;
    for (int a = 0; a < 3; ++a) {
      const double f = c[a] / spacing[a] + 32.0;
      const int i = static_cast<int>(std::floor(f));
      e[a] = (1.0 - (f - i)) * node[a][static_cast<size_t>(i)] + (f - i) * node[a][static_cast<size_t>(i + 1)];
    }
    return e;
  };
  const double in_t = 2e-3 * rng.normal(), out_t = 2e-3 * rng.normal(), in_z = 2e-3 * rng.normal(), out_z = 2e-3 * rng.normal();
  const Eigen::Vector3d nt(std::sin(out_t), std::cos(out_t) * std::cos(in_t), std::cos(out_t) * std::sin(in_t));
  const Eigen::Vector3d nz(std::sin(out_z), std::cos(out_z) * std::sin(in_z), std::cos(out_z) * std::cos(in_z));
  Eigen::VectorXd d = Eigen::VectorXd::Zero(2 * static_cast<Eigen::Index>(plan.points.size()));
  for (size_t k = 0; k < plan.points.size(); ++k) {
    if (refs[k] == static_cast<int>(k)) continue;
    // The head's own deviation (X: none in an A sweep) plus the axes' error less the zero pose's.
    const Eigen::Vector3d rel = Eigen::Vector3d(0.0, head[k].t_um, head[k].z_um) + err(plan.points[k].trigger_m_mm) -
                                err(plan.points[static_cast<size_t>(refs[k])].trigger_m_mm);
    d[2 * static_cast<Eigen::Index>(k)] = nt.dot(rel) - head[k].t_um;
    d[2 * static_cast<Eigen::Index>(k) + 1] = nz.dot(rel) - head[k].z_um;
  }
  return d;
}

// 400 machines drawn by `simulate --contributors` (no reading noise) against 4000 drawn here:
// every value's variance within 4.5 sampling sd of the ratio (sqrt(2 / 400)), the mean change
// within 4.5 standard errors of 0; the per-reading noise is the three per-reading terms in
// quadrature, typed from the file.
TEST(TooltipRealMachine, DrawnMachinesHaveTheStatedSpread) {
  const ProbePlan plan = plan004();
  const ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/tooltip_004.json"));
  const TooltipRun head = simulateTooltip(plan, truthHead(), 1);
  const Eigen::VectorXd v0 = values(head);
  const Eigen::Index n = v0.size();
  const int M = 400, M2 = 4000;
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(n), ss = Eigen::VectorXd::Zero(n), ss2 = Eigen::VectorXd::Zero(n);
  for (int m = 1; m <= M; ++m) {
    const Eigen::VectorXd d = values(readBack(plan, simulateDrawn(plan, cs, static_cast<std::uint64_t>(m), 1, 0.0))) - v0;
    sum += d;
    ss += d.cwiseAbs2();
  }
  Rng rng(2026, 5);
  for (int m = 0; m < M2; ++m) ss2 += ownDraw(plan, head, rng).cwiseAbs2();
  const std::vector<int> refs = tooltipReferences(plan);
  double worst_ratio = 0.0, worst_mean = 0.0, pooled_p = 0.0, pooled_o = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (refs[static_cast<size_t>(i / 2)] == static_cast<int>(i / 2)) continue;
    const double vp = ss[i] / M, vo = ss2[i] / M2;
    pooled_p += vp;
    pooled_o += vo;
    worst_ratio = std::max(worst_ratio, std::abs(vp / vo - 1.0));
    worst_mean = std::max(worst_mean, std::abs(sum[i] / M) / std::sqrt(vo / M));
  }
  std::printf("tooltip drawn machines: %.2f um rms per value (simulate) vs %.2f um (drawn here); worst variance ratio "
              "off by %.3f, worst mean %.2f SE\n",
              std::sqrt(pooled_p / (n - 2)), std::sqrt(pooled_o / (n - 2)), worst_ratio, worst_mean);
  EXPECT_LT(worst_ratio, 4.5 * std::sqrt(2.0 / M));
  EXPECT_LT(worst_mean, 4.5);
  const Simulated s = simulateDrawn(plan, cs, 7, 1);
  EXPECT_NEAR(s.truth["drawn"]["per_reading_um"].get<double>(), std::sqrt(0.254 * 0.254 + 0.635 * 0.635 + 1.778 * 1.778),
              1e-6);
  EXPECT_NEAR(s.truth["noise_um"].get<double>(), s.truth["drawn"]["per_reading_um"].get<double>(), 1e-6);
}

// 50 machines drawn from 004's contributors, each read once with its declared noise, analyzed and
// diagnosed with the same contributors. At the judge's alpha (1 %) model_inadequate may come out
// on at most 3 (binomial: P(X >= 4) = 0.16 %), the screen may lose a reading on at most 3 (its
// 1 %), the values may be held back on at most 1 (its 0.1 %: P(X >= 2) = 0.12 %); U (95.45 %)
// covers dR's truth on at least 44 (P(X <= 43) = 0.7 %) and the angular errors' on at least 90 %
// of the 950 (correlated within a machine: a loose bound).
TEST(TooltipRealMachine, JudgeScreenAndBudgetKeepTheirRatesOnDrawnMachines) {
  const ProbePlan plan = plan004();
  const ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/tooltip_004.json"));
  const TooltipTruth t = truthHead();
  const int machines = 50;
  int inadequate = 0, effect = 0, screened = 0, held = 0, dr_in = 0, e_in = 0, e_all = 0;
  int laser_only_inadequate = 0, laser_only_screened = 0;
  for (int m = 1; m <= machines; ++m) {
    const Simulated s = simulateDrawn(plan, cs, static_cast<std::uint64_t>(m), static_cast<std::uint64_t>(1000 + m));
    DiagnoseRequest dr;
    dr.plan = &plan;
    dr.results = {{"r.csv", s.results_text}};
    dr.contributors = &cs;
    const CycleDocuments dg = cycleByName("tooltip").diagnose(dr);
    const std::string verdict = dg.doc["verdict"].get<std::string>();
    inadequate += verdict == "model_inadequate" ? 1 : 0;
    effect += verdict == "effect_found" ? 1 : 0;
    // The same machine judged against the laser's noise alone (what diagnose did before the
    // contributors were declared to it), and screened against it.
    dr.contributors = nullptr;
    laser_only_inadequate += cycleByName("tooltip").diagnose(dr).doc["verdict"] == "model_inadequate" ? 1 : 0;
    const TooltipScreen lo = screenTooltipReadings(plan, {readBack(plan, s)}, tooltipDeclaredNoise(plan, nullptr));
    laser_only_screened += lo.screen.excluded.empty() && !lo.screen.too_many ? 0 : 1;
    AnalyzeRequest ar;
    ar.plan = &plan;
    ar.results = dr.results;
    ar.contributors = &cs;
    ar.mc_runs = 400;
    ar.mc_seed = static_cast<std::uint64_t>(m);
    const CycleDocuments a = cycleByName("tooltip").analyze(ar);
    screened += a.doc["outliers"]["excluded"].empty() ? 0 : 1;
    held += a.doc.contains("corrections_held_back") ? 1 : 0;
    const Json& dR = a.doc["location_errors"]["dR"];
    dr_in += std::abs(dR["value"].get<double>() - t.dR_um) <= dR["U"].get<double>() ? 1 : 0;
    for (const auto& e : a.doc["angular_error"]) {
      if (!e.contains("U") || e["value"].is_null()) continue;
      ++e_all;
      e_in += std::abs(e["value"].get<double>() - t.angularErrorMdeg(e["angle_deg"].get<double>())) <= e["U"].get<double>()
                  ? 1
                  : 0;
    }
  }
  std::printf("tooltip on %d drawn machines: model_inadequate %d, effect_found %d, screen lost a reading %d, held back %d; "
              "U covers dR %d, the angular errors %d of %d; against the laser's noise alone: model_inadequate %d, "
              "screen alarms %d\n",
              machines, inadequate, effect, screened, held, dr_in, e_in, e_all, laser_only_inadequate, laser_only_screened);
  EXPECT_LE(inadequate + effect, 3);
  EXPECT_GT(laser_only_inadequate, machines / 2);  // the test can fail: the laser alone misdeclares these machines
  EXPECT_LE(screened, 3);
  EXPECT_LE(held, 1);
  EXPECT_GE(dr_in, 44);
  EXPECT_GE(e_in, static_cast<int>(0.90 * e_all));
}

// Gross readings on drawn machines, screened against 004's declaration: a 1 mm glitch in a random
// value of a random reading is caught on at least 19 of 20 machines (a glitch along its reading's
// tangent, Z at 90 deg, is that angle's own error to the data). A 20 um glitch is within what the
// declared machine positioning (12.7 um per move, shared between readings) lets one reading move:
// its rate is printed, not claimed.
TEST(TooltipRealMachine, HiddenGlitchFoundOnDrawnMachines) {
  const ProbePlan plan = plan004();
  const ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/tooltip_004.json"));
  const DeclaredNoise noise = tooltipDeclaredNoise(plan, &cs);
  const std::vector<int> refs = tooltipReferences(plan);
  int caught[2] = {0, 0};
  const int machines = 20;
  for (int g = 0; g < 2; ++g)
    for (int m = 1; m <= machines; ++m) {
      TooltipRun run = readBack(plan, simulateDrawn(plan, cs, static_cast<std::uint64_t>(100 + m), static_cast<std::uint64_t>(m)));
      Rng rng(static_cast<std::uint64_t>(m), 17);
      int k = 0;
      do k = static_cast<int>(rng.uniform() * static_cast<double>(run.size()));
      while (refs[static_cast<size_t>(k)] == k);
      const double glitch = (g == 0 ? 20.0 : 1000.0) * (rng.uniform() < 0.5 ? -1.0 : 1.0);
      (rng.uniform() < 0.5 ? run[static_cast<size_t>(k)].t_um : run[static_cast<size_t>(k)].z_um) += glitch;
      const auto ex = screenTooltipReadings(plan, {run}, noise).excludedReadings();
      caught[g] += std::find(ex.begin(), ex.end(), std::make_pair(0, k)) != ex.end() ? 1 : 0;
    }
  std::printf("tooltip screen on drawn machines (004's declaration): 20 um caught %d / %d, 1 mm caught %d / %d\n",
              caught[0], machines, caught[1], machines);
  EXPECT_GE(caught[1], machines - 1);
}

}  // namespace
}  // namespace rotacal
