// The linear-axis error model of 000 Eq. (22)-(23) (core/linear_axes.hpp) against hand values.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "core/linear_axes.hpp"
#include "core/rng.hpp"

namespace rotacal {
namespace {

TEST(LinearAxes, ErrorIsEq22And23ByHand) {
  LinearAxisErrors e;
  e.scale = Eigen::Vector3d(1e-5, 2e-5, -1e-5);
  e.S_xy = 3e-5;
  e.S_xz = -2e-5;
  e.S_yz = 1e-5;
  // Y axis: nodes every 40 mm from -40 mm: values in X (0.001, 0.003, -0.002) mm, others zero.
  e.nodes[1].spacing_mm = 40.0;
  e.nodes[1].first = -1;
  e.nodes[1].mm = {std::vector<double>{0.001, 0.003, -0.002}, std::vector<double>{0, 0, 0}, std::vector<double>{0, 0, 0}};
  const Eigen::Vector3d c(100.0, 10.0, -50.0);
  // y = 10 lies between the nodes at 0 (0.003) and 40 (-0.002), a quarter of the way.
  const double rand_x = 0.75 * 0.003 + 0.25 * -0.002;
  const Eigen::Vector3d expected(1e-5 * 100 + 3e-5 * 10 + -2e-5 * -50 + rand_x,  // E_xx + E_xy + E_xz
                                 2e-5 * 10 + 1e-5 * -50,                         // E_yy + E_yz
                                 -1e-5 * -50);                                   // E_zz
  EXPECT_LT((e.error(c) - expected).norm(), 1e-15);
  // Beyond the drawn nodes the random part stays at the end value.
  EXPECT_NEAR(e.nodes[1].at(500.0).x(), -0.002, 1e-15);
  EXPECT_NEAR(e.asFunction()(c).x(), expected.x(), 1e-15);
}

TEST(LinearAxes, DrawnNodesHaveTheStatedSpreadAndSpacing) {
  // 000 Eq. (22): spacing uniform in [20, 50] mm (mean 35, sd 30/sqrt(12) = 8.66), node values
  // N(0, u). 4000 draws; tolerances 5 standard errors.
  LinearAxisModel m;
  m.u_rand(2, 0) = 2e-3;  // E_zx_rand = 2 um
  Rng rng(3, 0);
  const int n = 4000;
  double sp = 0, sp2 = 0, v2 = 0;
  long values = 0;
  AxisNodes nodes;
  for (int k = 0; k < n; ++k) {
    drawAxisNodes(m, 0, -300.0, 250.0, rng, &nodes);
    ASSERT_GE(nodes.spacing_mm, 20.0);
    ASSERT_LE(nodes.spacing_mm, 50.0);
    // The drawn nodes cover the range with one to spare on each side.
    ASSERT_LE(nodes.spacing_mm * (nodes.first + 1), -300.0);
    ASSERT_GE(nodes.spacing_mm * (nodes.first + static_cast<int>(nodes.mm[2].size()) - 2), 250.0);
    sp += nodes.spacing_mm;
    sp2 += nodes.spacing_mm * nodes.spacing_mm;
    for (double v : nodes.mm[2]) {
      v2 += v * v;
      ++values;
    }
    for (double v : nodes.mm[0]) ASSERT_EQ(v, 0.0);  // u = 0 in X
  }
  const double mean = sp / n, sd = std::sqrt(sp2 / n - mean * mean);
  EXPECT_NEAR(mean, 35.0, 5 * 8.66 / std::sqrt(n));
  EXPECT_NEAR(sd, 8.66, 0.3);
  EXPECT_NEAR(std::sqrt(v2 / static_cast<double>(values)), 2e-3, 5 * 2e-3 / std::sqrt(2.0 * values));
}

TEST(LinearAxes, NodeCorrelationIsWhatTheDrawnNodesShow) {
  // nodeCorrelation by quadrature against the sample correlation of 20000 drawn axes (unit node
  // values): at one place, 10 mm and 30 mm apart (within a spacing), across a node at 0, and
  // 120 mm apart (no shared node: exactly 0). Tolerance 5 standard errors of a product of unit
  // normals (sd <= sqrt(2)).
  LinearAxisModel m;
  m.u_rand(1, 2) = 1.0;
  Rng rng(11, 0);
  const int n = 20000;
  const std::vector<std::pair<double, double>> at = {{17.0, 17.0}, {17.0, 27.0}, {-12.0, 18.0}, {63.0, 33.0}, {-40.0, 80.0}};
  std::vector<double> sum(at.size(), 0.0);
  AxisNodes nodes;
  for (int k = 0; k < n; ++k) {
    drawAxisNodes(m, 2, -60.0, 100.0, rng, &nodes);
    for (size_t i = 0; i < at.size(); ++i) sum[i] += nodes.at(at[i].first).y() * nodes.at(at[i].second).y();
  }
  for (size_t i = 0; i < at.size(); ++i) {
    const double k = nodeCorrelation(at[i].first, at[i].second, 20.0, 50.0);
    EXPECT_NEAR(sum[i] / n, k, 5 * std::sqrt(2.0 / n)) << at[i].first << " " << at[i].second;
  }
  EXPECT_EQ(nodeCorrelation(-40.0, 80.0, 20.0, 50.0), 0.0);
  // At a node of every spacing (0) the value is the node's: correlation 1; between nodes less.
  EXPECT_NEAR(nodeCorrelation(0.0, 0.0, 20.0, 50.0), 1.0, 1e-12);
  EXPECT_LT(nodeCorrelation(17.0, 17.0, 20.0, 50.0), 1.0);
  EXPECT_NEAR(nodeCorrelation(17.0, 27.0, 20.0, 50.0), nodeCorrelation(27.0, 17.0, 20.0, 50.0), 1e-15);
}

TEST(LinearAxes, ModelIsValidated) {
  LinearAxisModel m;
  std::string why;
  EXPECT_TRUE(m.validate(&why));
  m.spacing_min_mm = 0;
  EXPECT_FALSE(m.validate(&why));
  m.spacing_min_mm = 20;
  m.u_S_xy = -1;
  EXPECT_FALSE(m.validate(&why));
}

}  // namespace
}  // namespace rotacal
