// The declaration the space-frame cycle tests its centres against (cycles/spaceframe/noise.hpp):
// with nothing declared, each centre's covariance is the probe's repeatability squared times its
// sphere fit's own (J^T J)^-1; the white part from the contributors' figures by hand; the
// structured part, carried to the centres, against a Monte Carlo of the product's own draw
// (drawProbeAxes through the exact simulator and the sphere fits); the judge reading it; analyze
// holding the identification back when the data exceed it.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>

#include "bench.hpp"
#include "core/contributor_draw.hpp"
#include "core/sphere_centre_fit.hpp"
#include "core/units.hpp"
#include "cycles/spaceframe/diagnose.hpp"
#include "cycles/spaceframe/noise.hpp"

namespace rotacal {
namespace {

using namespace spaceframe_test;

TEST(SpaceframeDeclaredNoise, NothingDeclaredIsTheSphereFitsOwnCovarianceTimesTheRepeatability) {
  const ProbePlan plan = reducedPlan();
  const SpaceframeNoise noise = spaceframeDeclaredNoise(plan, nullptr);
  EXPECT_DOUBLE_EQ(noise.touch.white_um2, 0.49);
  EXPECT_EQ(noise.touch.structured_um2.size(), 0);
  EXPECT_NE(noise.touch.declaration.find("repeatability only"), std::string::npos) << noise.touch.declaration;
  const std::vector<FramePoint> pts = framePoints(plan);
  for (int runs : {1, 3}) {
    const Eigen::MatrixXd S = spaceframeCentreCovariance(plan, pts, noise, runs);
    ASSERT_EQ(S.rows(), 3 * static_cast<Eigen::Index>(pts.size()));
    for (size_t i = 0; i < pts.size(); ++i) {
      // The fit's own covariance per unit noise, from its Gauss-Newton at the nominal triggers.
      std::vector<Eigen::Vector3d> t;
      for (int id : pts[i].point_ids) t.push_back(plan.findPoint(id)->trigger_m_mm);
      SphereFitOptions fo;
      fo.rho_mm = 19.05 / 2 + plan.machine.probe.ball_radius_mm();
      const SphereFit f = fitSphereCentre(t, pts[i].nominal_m_mm, fo);
      const Eigen::Matrix3d want = 0.49 / runs * f.cov_centre_per_sigma2;
      const auto r = 3 * static_cast<Eigen::Index>(i);
      EXPECT_LT((S.block<3, 3>(r, r) - want).cwiseAbs().maxCoeff(), 1e-9) << "point " << i;
      // Different touches, independent: nothing between two centres.
      const Eigen::Index other = (r + 3) % S.rows();
      EXPECT_EQ((S.block<3, 3>(r, other).cwiseAbs().maxCoeff()), 0.0);
    }
  }
}

// 000 Table 5 declares 0.7 um of repeatability and 1.0 um of roughness per touch: 1.49 um^2; the
// declaration names the file and what it shares between touches. A repeatability that contradicts
// MACHINE.json's is refused.
TEST(SpaceframeDeclaredNoise, WhitePartIsThePerTouchContributorsInQuadrature) {
  const ProbePlan plan = reducedPlan();
  const ContributorSet cs = table5();
  const SpaceframeNoise noise = spaceframeDeclaredNoise(plan, &cs);
  EXPECT_NEAR(noise.touch.white_um2, 0.7 * 0.7 + 1.0 * 1.0, 1e-12);
  EXPECT_FALSE(noise.touch.repeatability_only);
  EXPECT_EQ(noise.touch.structured_um2.rows(), static_cast<Eigen::Index>(plan.points.size()));
  EXPECT_NE(noise.touch.declaration.find("table5.json"), std::string::npos) << noise.touch.declaration;
  EXPECT_NE(noise.touch.declaration.find("S_xy"), std::string::npos) << noise.touch.declaration;
  ProbePlan other = plan;
  other.machine.probe.repeatability_um = 1.5;
  EXPECT_THROW(spaceframeDeclaredNoise(other, &cs), std::invalid_argument);
}

// The centres' structured covariance against the product's own draw: drawProbeAxes (the linear
// axes of 000 Table 5 and the pretravel) applied to a perfect machine, every trigger simulated
// exactly (no touch noise), every sphere fitted; 3000 draws. The draw is linear in what it draws,
// so the sample covariance must match within its sampling error: each variance within 4 x
// sqrt(2 / N) relative, each covariance within 7 / sqrt(N) of sqrt(C_ii C_jj) (the largest of
// some 30000 correlated entries, each with sd up to sqrt(2 / N)).
TEST(SpaceframeDeclaredNoise, StructuredPartMatchesAMonteCarloOfTheProductsDraw) {
  const ProbePlan plan = reducedPlan();
  const ContributorSet cs = table5();
  SpaceframeNoise noise = spaceframeDeclaredNoise(plan, &cs);
  noise.touch.white_um2 = 0.0;  // the structured part alone
  const std::vector<FramePoint> pts = framePoints(plan);
  const Eigen::MatrixXd C = spaceframeCentreCovariance(plan, pts, noise, 1);
  Truth perfect;
  perfect.noise_um = 0.0;
  const auto centres = [&](const Truth& t) {
    const MeasurementRun run = simulate(plan, t, {1});
    std::map<int, Eigen::Vector3d> at;
    for (const auto& p : run.points) at[p.point_id] = p.position_m_mm;
    Eigen::VectorXd c(3 * static_cast<Eigen::Index>(pts.size()));
    for (size_t i = 0; i < pts.size(); ++i) {
      std::vector<Eigen::Vector3d> tr;
      for (int id : pts[i].point_ids) tr.push_back(at.at(id));
      SphereFitOptions fo;
      fo.rho_mm = 19.05 / 2 + plan.machine.probe.ball_radius_mm();
      c.segment<3>(3 * static_cast<Eigen::Index>(i)) = mmToUm(1.0) * fitSphereCentre(tr, pts[i].nominal_m_mm, fo).centre_mm;
    }
    return c;
  };
  const Eigen::VectorXd c0 = centres(perfect);
  const int N = 3000;
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(C.rows(), C.cols());
  for (int run = 0; run < N; ++run) {
    ProbeAxesDraw draw;
    drawProbeAxes(plan, cs, isProbeAxesContributor, 41, run, -1, &draw);
    Truth t = perfect;
    applyProbeAxesDraw(draw, &t);
    const Eigen::VectorXd d = centres(t) - c0;
    S.selfadjointView<Eigen::Lower>().rankUpdate(d);
  }
  S = S.selfadjointView<Eigen::Lower>();
  S /= N;
  double worst_diag = 0.0, worst_cov = 0.0;
  for (Eigen::Index i = 0; i < C.rows(); ++i) {
    worst_diag = std::max(worst_diag, std::abs(S(i, i) / C(i, i) - 1.0));
    for (Eigen::Index j = 0; j < i; ++j) worst_cov = std::max(worst_cov, std::abs(S(i, j) - C(i, j)) / std::sqrt(C(i, i) * C(j, j)));
  }
  std::printf("spaceframe declared noise: %.2f um rms per centre coordinate structured (%zu centres); Monte Carlo (%d "
              "draws): worst variance %.3f relative, worst covariance %.3f of sqrt(C_ii C_jj)\n",
              std::sqrt(C.diagonal().mean()), pts.size(), N, worst_diag, worst_cov);
  EXPECT_LT(worst_diag, 4.0 * std::sqrt(2.0 / N));
  EXPECT_LT(worst_cov, 7.0 / std::sqrt(static_cast<double>(N)));
}

// The tests' null draws of the centres (spaceframeCentreNullDraws) against their declared
// covariance (spaceframeCentreCovariance, M C M^T written out): the whole declaration with one
// repeat and with two (the draws' sample covariance; 2000 draws of a scale mixture), and the white
// part alone, where the repeats' mean halves the variance: a draw not averaged over the repeats
// reads twice the covariance.
TEST(SpaceframeDeclaredNoise, CentreNullDrawsHaveTheCentresDeclaredCovariance) {
  const ProbePlan plan = reducedPlan();
  const ContributorSet cs = table5();
  const SpaceframeNoise whole = spaceframeDeclaredNoise(plan, &cs);
  SpaceframeNoise white = whole;
  white.touch.structured_um2.setZero();
  white.touch.structured_draws_um.setZero();
  const std::vector<FramePoint> pts = framePoints(plan);
  for (const SpaceframeNoise* noise : std::vector<const SpaceframeNoise*>{&whole, &white})
    for (int runs : {1, 2}) {
      const Eigen::MatrixXd C = spaceframeCentreCovariance(plan, pts, *noise, runs);
      const Eigen::MatrixXd D = spaceframeCentreNullDraws(plan, pts, *noise, runs, 17);
      ASSERT_EQ(D.rows(), C.rows());
      ASSERT_EQ(D.cols(), kDeclaredNullDraws);
      const auto N = static_cast<double>(D.cols());
      const Eigen::MatrixXd S = D * D.transpose() / N;  // the draws have mean zero by construction
      double worst_diag = 0.0, worst_cov = 0.0;
      for (Eigen::Index i = 0; i < C.rows(); ++i) {
        worst_diag = std::max(worst_diag, std::abs(S(i, i) / C(i, i) - 1.0));
        for (Eigen::Index j = 0; j < i; ++j)
          worst_cov = std::max(worst_cov, std::abs(S(i, j) - C(i, j)) / std::sqrt(C(i, i) * C(j, j)));
      }
      const char* which = noise == &whole ? "whole" : "white only";
      std::printf("spaceframe centre null draws (%s, %d repeats): worst variance %.3f relative, worst covariance %.3f\n",
                  which, runs, worst_diag, worst_cov);
      EXPECT_LT(worst_diag, 5.0 * std::sqrt(2.0 / N)) << which << ", " << runs << " repeats";
      EXPECT_LT(worst_cov, 7.0 / std::sqrt(N)) << which << ", " << runs << " repeats";
    }
}

// The judge is handed the declaration: the covariance of the centres it judges, in their order,
// and the declaration's words.
TEST(SpaceframeDeclaredNoise, TheJudgeReadsTheCentresDeclaredCovariance) {
  const ProbePlan plan = reducedPlan();
  const ContributorSet cs = table5();
  const SpaceframeNoise noise = spaceframeDeclaredNoise(plan, &cs);
  Truth t = test::truthWith(test::table4Mean());
  t.noise_um = 1.2;
  const std::vector<MeasurementRun> runs = {simulate(plan, t, {3}), simulate(plan, t, {4})};
  SpaceframeDiagnosisOptions o;
  o.noise = &noise;
  const SpaceframeDiagnosis d = diagnoseSpaceframe(plan, runs, o);
  const Eigen::MatrixXd want = spaceframeCentreCovariance(plan, framePoints(plan), noise, 2);
  ASSERT_EQ(d.problem.covariance.rows(), want.rows());
  EXPECT_LT((d.problem.covariance - want).cwiseAbs().maxCoeff(), 1e-12 * want.cwiseAbs().maxCoeff());
  EXPECT_EQ(d.problem.sigma.size(), 0);
  EXPECT_EQ(d.problem.declaration, noise.touch.declaration);
  EXPECT_EQ(d.judged.declaration, noise.touch.declaration);
  // Its adequacy test reads its null from draws of the declared machine, not chi2(dof).
  EXPECT_EQ(d.problem.null_draws.rows(), want.rows());
  EXPECT_EQ(d.judged.baseline.null_draws, kDeclaredNullDraws);
}

// Centres that scatter 4 x what the declared repeatability gives: the data exceed the
// declaration, and the identification is held back (REPORT.json, the warnings, the reason
// --offsets gives); at the declared noise it is not (p < 0.001 by chance once in a thousand).
TEST(SpaceframeDeclaredNoise, AnalyzeHoldsTheIdentificationBackWhenTheDataExceedTheDeclaration) {
  const ProbePlan plan = reducedPlan();
  Truth t = test::truthWith(test::table4Mean());
  t.noise_um = 4.0 * 0.7;
  const CycleDocuments bad = analyzeThrough(plan, {simulate(plan, t, {5})}, nullptr);
  ASSERT_TRUE(bad.doc.contains("declared_noise"));
  EXPECT_EQ(bad.doc["declared_noise"]["level"], "centres");
  EXPECT_LT(bad.doc["declared_noise"]["p_value"].get<double>(), 1e-3);
  EXPECT_NEAR(bad.doc["declared_noise"]["ratio"].get<double>(), 4.0, 1.0);
  ASSERT_TRUE(bad.doc.contains("corrections_held_back"));
  EXPECT_FALSE(bad.offsets_refused.empty());
  EXPECT_NE(bad.text.find("held back"), std::string::npos);
  t.noise_um = 0.7;
  const CycleDocuments good = analyzeThrough(plan, {simulate(plan, t, {5})}, nullptr);
  EXPECT_FALSE(good.doc.contains("corrections_held_back")) << good.doc["declared_noise"].dump();
  EXPECT_NEAR(good.doc["declared_noise"]["ratio"].get<double>(), 1.0, 0.25);
  EXPECT_TRUE(good.offsets_refused.empty());
}

}  // namespace
}  // namespace rotacal
