// The distributions against closed forms (not against Boost itself): chi-square with 2 degrees of
// freedom is exponential, Student's t with 1 is Cauchy, F(2, 2) has survival 1 / (1 + f).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/statistics.hpp"

namespace rotacal {
namespace {

TEST(Statistics, ChiSquareTwoDofIsExponential) {
  for (double x : {0.01, 0.5, 3.0, 40.0, 700.0}) EXPECT_NEAR(chiSquareSurvival(x, 2) / std::exp(-x / 2), 1.0, 1e-12) << x;
  EXPECT_EQ(chiSquareSurvival(0.0, 5), 1.0);
  // The quantile inverts the tail.
  for (double p : {0.5, 1e-3, 1e-9}) EXPECT_NEAR(chiSquareUpperQuantile(p, 2), -2 * std::log(p), 1e-9 * (1 - std::log(p)));
}

TEST(Statistics, ChiSquareMeanOfManyDofNearHalf) {
  // Wilson-Hilferty: the median of chi-square(k) is about k (1 - 2/(9k))^3.
  const double k = 553;
  EXPECT_NEAR(chiSquareSurvival(k * std::pow(1 - 2 / (9 * k), 3), k), 0.5, 1e-3);
}

TEST(Statistics, StudentOneDofIsCauchy) {
  for (double t : {0.1, 1.0, 7.6, 300.0}) EXPECT_NEAR(studentTwoSided(t, 1), 1 - 2 * std::atan(t) / M_PI, 1e-13) << t;
  EXPECT_NEAR(studentTwoSided(-1.0, 1), 0.5, 1e-14);
  // Two dof: P(|T| > t) = 1 - t / sqrt(2 + t^2).
  for (double t : {0.3, 2.0, 50.0}) EXPECT_NEAR(studentTwoSided(t, 2), 1 - t / std::sqrt(2 + t * t), 1e-13) << t;
}

TEST(Statistics, FTwoTwoSurvival) {
  for (double f : {0.2, 1.0, 19.0, 1e4}) EXPECT_NEAR(fSurvival(f, 2, 2), 1 / (1 + f), 1e-13) << f;
  EXPECT_EQ(fSurvival(0.0, 3, 4), 1.0);
}

TEST(Statistics, NormalQuantile) {
  EXPECT_NEAR(normalQuantile(0.975), 1.959963984540054, 1e-12);
  EXPECT_NEAR(normalQuantile(0.5), 0.0, 1e-15);
}

TEST(Statistics, BadArgumentsThrowInvalidArgument) {
  EXPECT_THROW(chiSquareSurvival(1, 0), std::invalid_argument);
  EXPECT_THROW(studentTwoSided(1, -1), std::invalid_argument);
  EXPECT_THROW(studentTwoSided(NAN, 3), std::invalid_argument);
  EXPECT_THROW(fSurvival(1, 0, 3), std::invalid_argument);
  EXPECT_THROW(normalQuantile(1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
