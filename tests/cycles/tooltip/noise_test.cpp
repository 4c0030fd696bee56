// The declaration the tooltip cycle tests its readings against (cycles/tooltip/noise.hpp): the
// white part from the contributors' figures by hand, the structured part against a Monte Carlo
// of the draw its uncertainty budget propagates (drawTooltip through the exact head geometry),
// the judge whitening by it, and analyze holding its values back when the data exceed it.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>

#include "core/contributor_draw.hpp"
#include "core/contributors.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/tooltip/budget.hpp"
#include "cycles/tooltip/diagnose.hpp"
#include "cycles/tooltip/noise.hpp"
#include "cycles/tooltip/plan.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

MachineModel headMachine() { return loadMachine(test::sourcePath("examples/machines/head_ab.json")); }

ProbePlan plan004() {
  return makePlan("tooltip", headMachine(), {{"units", "mm"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}});
}

ContributorSet contributors004() { return loadContributors(test::sourcePath("examples/contributors/tooltip_004.json")); }

/// A head of 004's size: dR = 40 um, e = 3 + 5 A/90 - 2 sin A + 1.5 sin 2A mdeg.
TooltipHead head004(const ProbePlan& plan) {
  TooltipHead h;
  for (const auto& p : plan.points)
    if (h.angles_deg.empty() || std::abs(p.pose.A - h.angles_deg.back()) > 1e-9) h.angles_deg.push_back(p.pose.A);
  for (double a : h.angles_deg) {
    const double r = degToRad(a);
    h.e_mdeg.push_back(3.0 + 5.0 * a / 90.0 - 2.0 * std::sin(r) + 1.5 * std::sin(2 * r));
  }
  h.dR_um = 40.0;
  return h;
}

Eigen::VectorXd values(const TooltipRun& run) {
  Eigen::VectorXd v(2 * static_cast<Eigen::Index>(run.size()));
  for (size_t k = 0; k < run.size(); ++k) {
    v[2 * static_cast<Eigen::Index>(k)] = run[k].t_um;
    v[2 * static_cast<Eigen::Index>(k) + 1] = run[k].z_um;
  }
  return v;
}

TEST(TooltipDeclaredNoise, NothingDeclaredIsThePlansLaserNoiseOnly) {
  const ProbePlan plan = makePlan("tooltip", headMachine(), {{"units", "mm"}, {"laser_noise_um", "0.4"}});
  const DeclaredNoise d = tooltipDeclaredNoise(plan, nullptr);
  EXPECT_DOUBLE_EQ(d.white_um2, 0.16);
  EXPECT_EQ(d.structured_um2.size(), 0);
  // The zero's own scatter is the same laser's: 0.16 um^2 per run, not between runs.
  EXPECT_EQ(d.per_run_um2.rows(), 2 * static_cast<Eigen::Index>(plan.points.size()));
  EXPECT_DOUBLE_EQ(d.per_run_um2.maxCoeff(), 0.16);
  EXPECT_NE(d.declaration.find("only"), std::string::npos) << d.declaration;
  EXPECT_NE(d.declaration.find("laser_noise_um 0.400"), std::string::npos) << d.declaration;
}

// The white part is 004 Sec. VII's per-reading terms in quadrature, typed from the file's
// figures: 0.254, 0.635 and 1.778 um; laser_resolution replaces the plan's laser_noise_um.
TEST(TooltipDeclaredNoise, WhitePartIsThePerReadingContributorsInQuadrature) {
  const ProbePlan plan = plan004();
  const ContributorSet cs = contributors004();
  const DeclaredNoise d = tooltipDeclaredNoise(plan, &cs);
  EXPECT_NEAR(d.white_um2, 0.254 * 0.254 + 0.635 * 0.635 + 1.778 * 1.778, 1e-9);
  EXPECT_FALSE(d.repeatability_only);
  EXPECT_NE(d.declaration.find("E_yy_rand"), std::string::npos) << d.declaration;
  // Without laser_resolution the plan's laser_noise_um is the laser's own part.
  ContributorSet no_res = cs;
  no_res.items.erase(std::remove_if(no_res.items.begin(), no_res.items.end(),
                                    [](const Contributor& c) { return c.info->kind == ContributorKind::LaserResolution; }),
                     no_res.items.end());
  const ProbePlan plan2 = makePlan("tooltip", headMachine(), {{"units", "mm"}, {"laser_noise_um", "0.5"}});
  EXPECT_NEAR(tooltipDeclaredNoise(plan2, &no_res).white_um2, 0.25 + 0.635 * 0.635 + 1.778 * 1.778, 1e-9);
}

// The structured part against the budget's own draw: drawTooltip (the linear axes carrying the
// pivot, the beams' alignment) through simulateTooltipHead on a head of 004's size, 4000 draws.
// The readings are linear in the axes' errors and, to first order, in the tilts: the sample
// covariance must match within its sampling error (diagonal: 4 x sqrt(2 / N) relative; the
// correlations: 5 / sqrt(N)); the zero readings' rows are zero in both.
TEST(TooltipDeclaredNoise, StructuredPartMatchesAMonteCarloOfTheBudgetsDraw) {
  const ProbePlan plan = plan004();
  const ContributorSet cs = contributors004();
  const ContributorSplit split = splitContributors(cs, tooltipTypeA, tooltipTypeB);
  const TooltipHead head = head004(plan);
  const TooltipRun about = simulateTooltipHead(plan, head, TooltipDraw{}, true, 0.0, nullptr);
  const DeclaredNoise d = tooltipDeclaredNoise(plan, &cs, &about);
  const Eigen::MatrixXd& C = d.structured_um2;
  ASSERT_EQ(C.rows(), 2 * static_cast<Eigen::Index>(plan.points.size()));
  const Eigen::VectorXd v0 = values(about);
  const int N = 4000;
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(C.rows(), C.cols());
  for (int run = 0; run < N; ++run) {
    TooltipDraw draw;
    drawTooltip(plan, split.type_b, 11, run, -1, &draw);
    const Eigen::VectorXd dv = values(simulateTooltipHead(plan, head, draw, true, 0.0, nullptr)) - v0;
    S += dv * dv.transpose();
  }
  S /= N;
  const std::vector<int> refs = tooltipReferences(plan);
  double worst_diag = 0.0, worst_corr = 0.0;
  for (Eigen::Index i = 0; i < C.rows(); ++i) {
    if (refs[static_cast<size_t>(i / 2)] == static_cast<int>(i / 2)) {
      EXPECT_EQ(C(i, i), 0.0);
      EXPECT_LT(S(i, i), 1e-12);
      continue;
    }
    worst_diag = std::max(worst_diag, std::abs(S(i, i) / C(i, i) - 1.0));
    for (Eigen::Index j = 0; j < C.cols(); ++j) {
      if (refs[static_cast<size_t>(j / 2)] == static_cast<int>(j / 2)) continue;
      const double s = std::sqrt(C(i, i) * C(j, j));
      worst_corr = std::max(worst_corr, std::abs(S(i, j) - C(i, j)) / s);
    }
  }
  std::printf("tooltip declared noise: %.2f um rms per reading structured; Monte Carlo (%d draws): worst diagonal %.3f "
              "relative, worst correlation %.3f\n",
              std::sqrt(C.diagonal().sum() / (C.rows() - 2)), N, worst_diag, worst_corr);
  EXPECT_LT(worst_diag, 4.0 * std::sqrt(2.0 / N));
  EXPECT_LT(worst_corr, 5.0 / std::sqrt(static_cast<double>(N)));
}

// The judge is handed the declaration: its covariance is the white part on the diagonal and the
// structured part between the values (one machine in every repeat), in the problem's order.
TEST(TooltipDeclaredNoise, TheJudgeWhitensByTheDeclaration) {
  const ProbePlan plan = plan004();
  const ContributorSet cs = contributors004();
  TooltipTruth t;
  t.dR_um = 10.0;
  t.noise_um = 1.0;
  const std::vector<TooltipRun> runs = {simulateTooltip(plan, t, 3), simulateTooltip(plan, t, 4)};
  const TooltipJudgeSetup s = tooltipJudgeSetup({{&plan, runs}}, 0.254, &cs);
  const DeclaredNoise d = tooltipDeclaredNoise(plan, &cs, &runs.front());
  const Eigen::MatrixXd want = d.covariance(tooltipReadValues(plan, runs));
  ASSERT_EQ(s.problem.covariance.rows(), want.rows());
  EXPECT_LT((s.problem.covariance - want).cwiseAbs().maxCoeff(), 1e-9 * want.cwiseAbs().maxCoeff());
  EXPECT_EQ(s.problem.declaration, d.declaration);
  // Without contributors: the laser noise alone, each reading's own and its zero's, written out
  // here by sweep and direction: 0.254^2 on the diagonal, and again between two values of one
  // run that read one direction against one zero.
  const TooltipJudgeSetup w = tooltipJudgeSetup({{&plan, runs}}, 0.254);
  const std::vector<std::pair<int, int>> kept = tooltipReadValues(plan, runs);
  const std::vector<int> refs = tooltipReferences(plan);
  ASSERT_EQ(w.problem.covariance.rows(), static_cast<Eigen::Index>(kept.size()));
  const double v = 0.254 * 0.254;
  for (size_t a = 0; a < kept.size(); ++a)
    for (size_t b = 0; b < kept.size(); ++b) {
      const bool one_zero = kept[a].first == kept[b].first && kept[a].second % 2 == kept[b].second % 2 &&
                            refs[static_cast<size_t>(kept[a].second / 2)] == refs[static_cast<size_t>(kept[b].second / 2)];
      const double want_ab = (a == b ? v : 0.0) + (one_zero ? v : 0.0);
      EXPECT_NEAR(w.problem.covariance(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)), want_ab, 1e-12) << a << " " << b;
    }
  EXPECT_NE(w.problem.declaration.find("only"), std::string::npos);
}

// The laser is zeroed on a noisy reading: 4000 runs of the simulator (noise 0.5 um, two sweeps at
// B = 0 and 30 deg, so two zeros) against the declaration's white and per-run parts, entry by
// entry within 5 sampling sd: between two values of one sweep and direction the zero's variance,
// elsewhere nothing; each value's variance twice the reading's.
TEST(TooltipDeclaredNoise, ZeroReadingMonteCarloMatchesThePerRunPart) {
  const ProbePlan plan = makePlan("tooltip", headMachine(),
                                  {{"units", "mm"}, {"radius_mm", "381"}, {"step_deg", "30"}, {"end_deg", "90"},
                                   {"other_deg", "0,30"}, {"laser_noise_um", "0.5"}});
  const DeclaredNoise d = tooltipDeclaredNoise(plan, nullptr);
  TooltipTruth t;
  t.dR_um = 15.0;
  t.noise_um = 0.5;
  TooltipTruth noiseless = t;
  noiseless.noise_um = 0.0;
  const Eigen::VectorXd clean = values(simulateTooltip(plan, noiseless, 1));
  const int runs = 4000;
  const std::vector<int> refs = tooltipReferences(plan);
  const std::vector<std::pair<int, int>> kept = tooltipReadValues(plan, {simulateTooltip(plan, t, 1)});
  const auto n = static_cast<Eigen::Index>(kept.size());
  ASSERT_GT(n, 8);
  Eigen::MatrixXd sample = Eigen::MatrixXd::Zero(n, n);
  for (int r = 0; r < runs; ++r) {
    const Eigen::VectorXd all = values(simulateTooltip(plan, t, static_cast<std::uint64_t>(100 + r))) - clean;
    Eigen::VectorXd x(n);
    for (Eigen::Index a = 0; a < n; ++a) x[a] = all[kept[static_cast<size_t>(a)].second];
    sample += x * x.transpose() / runs;
  }
  const Eigen::MatrixXd C = d.covariance(kept);
  double worst = 0.0;
  int shared = 0;
  for (Eigen::Index a = 0; a < n; ++a)
    for (Eigen::Index b = 0; b < n; ++b) {
      worst = std::max(worst, std::abs(sample(a, b) - C(a, b)) / std::sqrt((C(a, a) * C(b, b) + C(a, b) * C(a, b)) / runs));
      shared += a != b && C(a, b) > 0 ? 1 : 0;
    }
  std::printf("tooltip zero reading: worst entry %.2f sampling sd off the declaration (%d shared pairs)\n", worst, shared);
  EXPECT_LT(worst, 5.0);
  EXPECT_GT(shared, 0);
  for (Eigen::Index a = 0; a < n; ++a) EXPECT_NEAR(C(a, a), 2.0 * 0.25, 1e-12);
  // Two sweeps, two zeros: a value of B0 shares nothing with one of B30.
  for (size_t a = 0; a < kept.size(); ++a)
    for (size_t b = 0; b < kept.size(); ++b) {
      if (refs[static_cast<size_t>(kept[a].second / 2)] != refs[static_cast<size_t>(kept[b].second / 2)]) {
        EXPECT_EQ(C(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)), 0.0);
      }
    }
}

CycleDocuments analyzeThrough(const ProbePlan& plan, const TooltipRun& run, const ContributorSet* cs) {
  AnalyzeRequest r;
  r.plan = &plan;
  r.results = {{"r.csv", tooltipResultsText(plan, run)}};
  r.contributors = cs;
  r.mc_runs = 200;
  return cycleByName("tooltip").analyze(r);
}

// Readings that scatter 4 x the declared laser noise: the data exceed the declaration, and the
// values are held back (REPORT.json, the warnings, the reason --offsets gives); at the declared
// noise they are not.
TEST(TooltipDeclaredNoise, AnalyzeHoldsTheValuesBackWhenTheDataExceedTheDeclaration) {
  const ProbePlan plan = plan004();
  TooltipTruth t;
  t.dR_um = 20.0;
  t.offset_mdeg = 2.0;
  t.noise_um = 4.0 * 0.254;
  const CycleDocuments bad = analyzeThrough(plan, simulateTooltip(plan, t, 5), nullptr);
  ASSERT_TRUE(bad.doc.contains("declared_noise"));
  EXPECT_LT(bad.doc["declared_noise"]["p_value"].get<double>(), 1e-3);
  EXPECT_NEAR(bad.doc["declared_noise"]["ratio"].get<double>(), 4.0, 1.5);
  ASSERT_TRUE(bad.doc.contains("corrections_held_back"));
  EXPECT_FALSE(bad.offsets_refused.empty());
  t.noise_um = 0.254;
  const CycleDocuments good = analyzeThrough(plan, simulateTooltip(plan, t, 5), nullptr);
  EXPECT_FALSE(good.doc.contains("corrections_held_back")) << good.doc["declared_noise"].dump();
  EXPECT_TRUE(good.offsets_refused.empty());
}

}  // namespace
}  // namespace rotacal
