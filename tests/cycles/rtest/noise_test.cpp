// The R-test's declaration of the readings (rtestDeclaredNoise) against the machines the
// uncertainty budget draws: the structured part, derived to first order, against a Monte Carlo
// of drawRtest through the exact simulator, which the derivation never calls.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "core/machine.hpp"
#include "core/units.hpp"
#include "cycles/rtest/analyze.hpp"
#include "cycles/rtest/budget.hpp"
#include "cycles/rtest/plan.hpp"
#include "rtest_002_scenario.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

ProbePlan plan002() { return test::rtest002Plan(ROTACAL_SOURCE_DIR, 0.2); }
ContributorSet contributors002() { return loadContributors(test::sourcePath("examples/contributors/rtest_002.json")); }

Eigen::VectorXd readingsUm(const RtestCycle& c) {
  Eigen::VectorXd y(3 * static_cast<Eigen::Index>(c.readings.size()));
  for (size_t i = 0; i < c.readings.size(); ++i) y.segment<3>(3 * static_cast<Eigen::Index>(i)) = mmToUm(1.0) * c.readings[i].dq_w_mm;
  return y;
}

// 2000 machines drawn as the budget draws them (drawRtest, applyRtestDraw) around 002-like
// errors, one noise-free cycle each: the readings' covariance about the undrawn machine's
// against the declared structured part, taken about that machine's readings.
TEST(RtestDeclaredNoise, StructuredPartMatchesTheBudgetsDrawMonteCarlo) {
  const ProbePlan plan = plan002();
  const ContributorSet cs = contributors002();
  const Truth truth = test::rtest002Truth(1);
  RtestSimOptions so;
  so.cycles = 1;
  const RtestCycle base = simulateRtest(plan, truth, {}, so).cycles.front();
  const DeclaredNoise noise = rtestDeclaredNoise(plan, &cs, &base);
  ASSERT_EQ(noise.structured_um2.rows(), 3 * static_cast<Eigen::Index>(plan.points.size()));
  EXPECT_FALSE(noise.repeatability_only);
  const Eigen::VectorXd y0 = readingsUm(base);
  constexpr int kDraws = 2000;
  Eigen::MatrixXd X(y0.size(), kDraws);
  for (int r = 0; r < kDraws; ++r) {
    RtestDraw d;
    drawRtest(plan, cs, 2718, r, -1, &d);
    Truth t = truth;
    RtestTruthExtras x;
    applyRtestDraw(plan, d, &t, &x);
    X.col(r) = readingsUm(simulateRtest(plan, t, x, so).cycles.front()) - y0;
  }
  const Eigen::VectorXd mean = X.rowwise().mean();
  X.colwise() -= mean;
  const Eigen::MatrixXd mc = X * X.transpose() / (kDraws - 1);
  const Eigen::MatrixXd& S = noise.structured_um2;
  // Variances: every reading but the reset pose's own (0 by construction in both).
  int compared = 0, beyond = 0;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < S.rows(); ++i) {
    if (S(i, i) < 1e-6 && mc(i, i) < 1e-6) continue;
    ++compared;
    const double ratio = mc(i, i) / S(i, i);
    worst = std::max(worst, std::abs(ratio - 1.0));
    beyond += std::abs(ratio - 1.0) > 0.10;
  }
  const double trace_ratio = mc.trace() / S.trace();
  // The whole matrix: the relative Frobenius distance, which the covariances (the linear axes'
  // shared slopes, the sphere offset read through every pose) dominate.
  const double frob = (mc - S).norm() / S.norm();
  std::printf("rtest structured vs %d draws: %d variances, %d beyond 10 %% (worst %.1f %%), trace ratio %.3f, "
              "relative Frobenius %.3f, declared rms %.2f um per reading\n",
              kDraws, compared, beyond, 100.0 * worst, trace_ratio, frob, std::sqrt(S.diagonal().mean()));
  EXPECT_GE(compared, 60);  // 25 poses x 3, less the reset pose's own
  EXPECT_LE(beyond, compared / 20);
  EXPECT_NEAR(trace_ratio, 1.0, 0.05);
  EXPECT_LT(frob, 0.10);
}

// Without the readings to take it about, the sensors' response moves nothing to first order
// (every reading is 0 on the nominal machine): the gain and cross-talk are then not named.
TEST(RtestDeclaredNoise, GainAndCrossTalkActOnlyAboutReadings) {
  const ProbePlan plan = plan002();
  ContributorSet cs;
  const ContributorSet all = contributors002();
  ASSERT_NE(all.find("rtest_sensor_gain"), nullptr);
  cs.items.push_back(*all.find("rtest_sensor_gain"));
  EXPECT_EQ(rtestDeclaredNoise(plan, &cs).structured_um2.size(), 0);
  RtestSimOptions so;
  so.cycles = 1;
  const RtestCycle c = simulateRtest(plan, test::rtest002Truth(1), {}, so).cycles.front();
  const DeclaredNoise n = rtestDeclaredNoise(plan, &cs, &c);
  ASSERT_GT(n.structured_um2.size(), 0);
  // A gain error g reads g x the reading itself: its variance is u^2 x reading^2, exactly.
  const double u = cs.items.front().u[0];
  for (size_t i = 0; i < c.readings.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double want = std::pow(u * mmToUm(c.readings[i].dq_w_mm[a]), 2);
      EXPECT_NEAR(n.structured_um2(3 * static_cast<Eigen::Index>(i) + a, 3 * static_cast<Eigen::Index>(i) + a), want, 1e-9 + 1e-9 * want);
    }
}

}  // namespace
}  // namespace rotacal
