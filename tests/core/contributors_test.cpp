// The contributors file (core/contributors.hpp): 000 Table 5's values in their units, and precise
// errors for bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "core/contributor_draw.hpp"
#include "core/contributors.hpp"
#include "core/errors.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

TEST(Contributors, Table5FileHoldsThePapersValuesInInternalUnits) {
  const ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/table5.json"));
  // Every id of 000 Table 5 plus form_error (the catalog's rtest_* ids are the R-test's, its
  // laser_* ids the laser's of 004).
  size_t touch_ids = 0;
  for (const auto& c : contributorCatalog())
    touch_ids += c.id.substr(0, 6) == "rtest_" || c.id.substr(0, 6) == "laser_" ? 0 : 1;
  EXPECT_EQ(cs.items.size(), touch_ids);
  EXPECT_EQ(touch_ids, 21u);
  EXPECT_DOUBLE_EQ(cs.find("probe_repeatability")->u[0], 0.7e-3);            // 0.7 um -> mm
  EXPECT_DOUBLE_EQ(cs.find("E_yy_lin")->u[0], 1e-5);                          // 1 um/100mm (000: "1 um/mm")
  EXPECT_DOUBLE_EQ(cs.find("E_zx_rand")->u[0], 2e-3);                         // 2 um
  EXPECT_DOUBLE_EQ(cs.find("S_yz")->u[0], 3e-5);                              // 3 um/100mm
  EXPECT_EQ(cs.find("setup_position")->u, Eigen::Vector3d(0.01, 0.01, 0.12));  // 10, 10, 120 um
  EXPECT_DOUBLE_EQ(cs.find("setup_orientation")->u[2], 1e-4);                 // 10 um/100mm
  EXPECT_DOUBLE_EQ(cs.find("form_error")->u[1], 2e-3);                        // 2 mrad
  EXPECT_DOUBLE_EQ(cs.node_spacing_min_mm, 20.0);
  EXPECT_DOUBLE_EQ(cs.node_spacing_max_mm, 50.0);
  const LinearAxisModel m = cs.linearAxisModel();
  EXPECT_DOUBLE_EQ(m.u_rand(1, 0), 2e-3);  // E_yx_rand: direction Y of the X axis
  EXPECT_DOUBLE_EQ(m.u_S_xy, 3e-5);
  ASSERT_TRUE(cs.reference.has_value());
  EXPECT_DOUBLE_EQ(cs.reference->combined.at("b_AY"), 2.0);
  EXPECT_DOUBLE_EQ(cs.reference->contributors.at("S_yz").at("dy_AY"), 5.5);
}

TEST(Contributors, UnitsConvert) {
  double f = 0;
  ASSERT_TRUE(unitFactor(Quantity::Ratio, "um/m", &f));
  EXPECT_DOUBLE_EQ(f, 1e-6);
  ASSERT_TRUE(unitFactor(Quantity::Ratio, "um/100mm", &f));
  EXPECT_DOUBLE_EQ(f, 1e-5);
  ASSERT_TRUE(unitFactor(Quantity::Ratio, "mdeg", &f));
  EXPECT_NEAR(f, 1.745329252e-5, 1e-14);
  EXPECT_FALSE(unitFactor(Quantity::Length, "um/m", &f));
  EXPECT_FALSE(unitFactor(Quantity::Ratio, "um", &f));
}

void expectInputError(const std::string& text, int line, const std::string& fragment) {
  try {
    contributorsFromJson(parseJsonText(text, "c.json"));
    FAIL() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "c.json");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Contributors, BadInputNamesTheFileLineAndProblem) {
  expectInputError(R"({"format": "x"})", 1, "not a contributors file");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"probe_noise\": {\"u\": 1, \"unit\": \"um\"}}}",
                   3, "unknown contributor 'probe_noise'");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"S_xy\": {\"u\": 3, \"unit\": \"um\"}}}", 3,
                   "unit 'um' is not one of");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"E_xx_rand\": {\"u\": -2, \"unit\": \"um\"}}}",
                   3, ">= 0");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"node_spacing_mm\": [50, 20],\n \"contributors\": {\"S_xy\": {\"u\": 3, \"unit\": \"urad\"}}}",
                   2, "min <= max");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"form_error\": {\"offset\": {\"u\": 1, \"unit\": \"um\"}}}}",
                   3, "'form_error' needs");
}

TEST(Contributors, ProbeAxesCovarianceIsWhatTheDrawsShow) {
  // probeAxesCovariance (first order, node correlation by quadrature) against the sample
  // covariance of 20000 runs of drawProbeAxes on 000 Table 5 (pretravel set to 1 um so that it
  // acts): touches 8 mm apart (one node span), 60 mm apart, and oblique, in all three axes.
  ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/table5.json"));
  for (auto& c : cs.items)
    if (c.info->kind == ContributorKind::ProbePretravel) c.u[0] = 1e-3;
  ProbePlan plan;
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> touches = {
      {{10.0, -80.0, 40.0}, {0, 0, -1}},
      {{18.0, -80.0, 40.0}, {0, 0, -1}},
      {{10.0, -20.0, 100.0}, {-1, 0, 0}},
      {{70.0, -75.0, 35.0}, Eigen::Vector3d(1, 1, -1).normalized()},
      {{-30.0, 40.0, 40.0}, {0, 1, 0}},
      {{12.0, -78.0, 44.0}, {1, 0, 0}}};
  std::vector<Eigen::Vector3d> t, u;
  for (const auto& [at, along] : touches) {
    ProbePoint p;
    p.trigger_m_mm = at;
    p.approach_m = along;
    plan.points.push_back(p);
    t.push_back(at);
    u.push_back(along);
  }
  const Eigen::MatrixXd C = probeAxesCovariance(cs, isProbeAxesContributor, t, u);
  const int runs = 20000;
  const auto n = static_cast<Eigen::Index>(t.size());
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
  ProbeAxesDraw d;
  for (int run = 0; run < runs; ++run) {
    drawProbeAxes(plan, cs, isProbeAxesContributor, 5, run, -1, &d);
    Eigen::VectorXd x(n);
    for (Eigen::Index i = 0; i < n; ++i)
      x[i] = pretravelAlong(d.pretravel_mm, u[static_cast<size_t>(i)]) -
             d.linear_errors.error(t[static_cast<size_t>(i)]).dot(u[static_cast<size_t>(i)]);
    S += x * x.transpose();
  }
  S /= runs;
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j <= i; ++j) {
      const double se = std::sqrt((C(i, i) * C(j, j) + C(i, j) * C(i, j)) / runs);
      EXPECT_NEAR(S(i, j), C(i, j), 5 * se) << i << "," << j;
    }
  EXPECT_GT(C(0, 1), 0.3 * C(0, 0));  // 8 mm apart: mostly the same random errors
  // The per-touch contributors add 0.7^2 + 1^2 um^2 on the diagonal and nothing else.
  const Eigen::MatrixXd A = probeAxesCovariance(
      cs, [](const ContributorInfo& c) { return isProbeAxesContributor(c) || isPerTouchContributor(c); }, t, u);
  const Eigen::MatrixXd diff = A - C;
  EXPECT_NEAR((diff - 1.49e-6 * Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 0.0, 1e-18);
}

TEST(Contributors, ProbeAxesDrawsHaveTheCovariance) {
  // probeAxesDraws' sample covariance over 20000 draws against probeAxesCovariance (the node
  // correlation by quadrature, not by draws) on 000 Table 5 with 1 um pretravel and the per-touch
  // contributors: touches 8 mm apart, 60 mm apart, oblique.
  ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/table5.json"));
  for (auto& c : cs.items)
    if (c.info->kind == ContributorKind::ProbePretravel) c.u[0] = 1e-3;
  const std::vector<Eigen::Vector3d> t = {{10.0, -80.0, 40.0}, {18.0, -80.0, 40.0}, {10.0, -20.0, 100.0}, {70.0, -75.0, 35.0}};
  const std::vector<Eigen::Vector3d> u = {{0, 0, -1}, {0, 0, -1}, {-1, 0, 0}, Eigen::Vector3d(1, 1, -1).normalized()};
  const auto all = [](const ContributorInfo& c) { return isProbeAxesContributor(c) || isPerTouchContributor(c); };
  const Eigen::MatrixXd C = probeAxesCovariance(cs, all, t, u);
  const int runs = 20000;
  const Eigen::MatrixXd D = probeAxesDraws(cs, all, t, u, runs, 11);
  ASSERT_EQ(D.rows(), 4);
  ASSERT_EQ(D.cols(), runs);
  const Eigen::MatrixXd S = D * D.transpose() / runs;
  for (Eigen::Index i = 0; i < 4; ++i)
    for (Eigen::Index j = 0; j <= i; ++j) {
      const double se = std::sqrt((C(i, i) * C(j, j) + C(i, j) * C(i, j)) / runs);
      EXPECT_NEAR(S(i, j), C(i, j), 5 * se) << i << "," << j;
    }
  // The same seed draws the same machines; another seed others.
  EXPECT_EQ((probeAxesDraws(cs, all, t, u, 3, 11) - D.leftCols(3)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT((probeAxesDraws(cs, all, t, u, 3, 12) - D.leftCols(3)).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace rotacal
