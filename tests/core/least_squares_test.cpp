// The shared estimation engine against closed forms: a linear problem's solution and covariance
// ((A^T A)^-1), a rank-deficient one's minimum-norm answer and null space, a nonlinear curve
// recovered from noise-free data, and the validation of its options.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "core/least_squares.hpp"

namespace rotacal {
namespace {

TEST(LeastSquares, LinearProblemGivesTheNormalEquationsSolutionAndCovariance) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A(40, 4);
  Eigen::VectorXd y(40);
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 4; ++j) A(i, j) = g(rng) * std::pow(10.0, j - 2);  // columns of very different scale
    y[i] = g(rng);
  }
  const auto f = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    r = A * x - y;
    if (J) *J = A;
  };
  const LeastSquaresResult res = solveLeastSquares(f, Eigen::VectorXd::Zero(4));
  ASSERT_TRUE(res.summary.usable()) << res.summary.briefReport();
  const Eigen::MatrixXd N = A.transpose() * A;
  const Eigen::VectorXd x = N.ldlt().solve(A.transpose() * y);
  const Eigen::MatrixXd C = N.inverse();
  for (int j = 0; j < 4; ++j) {
    EXPECT_NEAR(res.x[j], x[j], 1e-10 * std::max(1.0, std::abs(x[j])));
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(res.covariance(j, k), C(j, k), 1e-9 * std::sqrt(C(j, j) * C(k, k)));
  }
  EXPECT_EQ(res.summary.rank, 4);
  EXPECT_EQ(res.null_space.cols(), 0);
  EXPECT_LE(res.summary.iterations, 3);
}

TEST(LeastSquares, RankDeficiencyGivesTheMinimumNormAnswerAndNamesTheNullSpace) {
  // y = (x0 + x1) t + x2: only x0 + x1 is seen. From x = 0 the minimum-norm answer splits the
  // sum equally, and the null space is (1, -1, 0) / sqrt(2).
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(10, -1.0, 2.0);
  const Eigen::VectorXd y = 3.0 * t + Eigen::VectorXd::Constant(10, 0.5);
  const auto f = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    r = (x[0] + x[1]) * t + Eigen::VectorXd::Constant(10, x[2]) - y;
    if (J) {
      J->resize(10, 3);
      J->col(0) = t;
      J->col(1) = t;
      J->col(2).setOnes();
    }
  };
  const LeastSquaresResult res = solveLeastSquares(f, Eigen::VectorXd::Zero(3));
  ASSERT_TRUE(res.summary.usable()) << res.summary.briefReport();
  EXPECT_EQ(res.summary.rank, 2);
  EXPECT_NEAR(res.x[0], 1.5, 1e-12);
  EXPECT_NEAR(res.x[1], 1.5, 1e-12);
  EXPECT_NEAR(res.x[2], 0.5, 1e-12);
  ASSERT_EQ(res.null_space.cols(), 1);
  const Eigen::Vector3d v = res.null_space.col(0).normalized();
  EXPECT_NEAR(std::abs(v[0] - v[1]) / std::sqrt(2.0), 1.0, 1e-12);
  EXPECT_NEAR(v[2], 0.0, 1e-12);
  // The covariance carries nothing along the unseen direction.
  EXPECT_NEAR((res.covariance * res.null_space.col(0)).norm(), 0.0, 1e-12);
}

TEST(LeastSquares, NonlinearCurveIsRecoveredFromNoiseFreeData) {
  // y = a exp(-b t) + c, truth (2, 0.7, -0.3), started 30-60 % off.
  const Eigen::Vector3d truth(2.0, 0.7, -0.3);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(25, 0.0, 6.0);
  const auto model = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
    return (x[0] * (-x[1] * t.array()).exp() + x[2]).matrix();
  };
  const Eigen::VectorXd y = model(truth);
  const auto f = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    r = model(x) - y;
    if (J) {
      J->resize(t.size(), 3);
      J->col(0) = (-x[1] * t.array()).exp().matrix();
      J->col(1) = (-x[0] * t.array() * (-x[1] * t.array()).exp()).matrix();
      J->col(2).setOnes();
    }
  };
  const LeastSquaresResult res = solveLeastSquares(f, Eigen::Vector3d(1.2, 1.0, 0.0));
  ASSERT_TRUE(res.summary.usable()) << res.summary.briefReport();
  EXPECT_LT((res.x - truth).norm(), 1e-12);
  EXPECT_LT(res.summary.cost, 1e-24);
  EXPECT_GT(res.summary.initial_cost, 0.1);
}

TEST(LeastSquares, AProblemsOwnConvergenceMeasureStopsTheSolve) {
  // The curve above with the tolerances off: the problem's own measure (no parameter moves by
  // more than 1e-6 in a step) alone decides. Gauss-Newton converges quadratically here, so when it
  // stops the estimate is within the last step's size squared, far below 1e-6, of the truth; the
  // measure is asked once per step with the x before and after it. A measure never met runs out
  // of iterations, and says so.
  const Eigen::Vector3d truth(2.0, 0.7, -0.3);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(25, 0.0, 6.0);
  const auto f = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    const Eigen::ArrayXd e = (-x[1] * t.array()).exp();
    r = (x[0] * e + x[2]).matrix() - (truth[0] * (-truth[1] * t.array()).exp() + truth[2]).matrix();
    if (J) {
      J->resize(t.size(), 3);
      J->col(0) = e.matrix();
      J->col(1) = (-x[0] * t.array() * e).matrix();
      J->col(2).setOnes();
    }
  };
  LeastSquaresOptions o;
  o.step_tolerance = 1e-300;
  o.function_tolerance = 0.0;
  int asked = 0;
  double last_move = 0.0;
  o.converged = [&](const Eigen::VectorXd& before, const Eigen::VectorXd& after) {
    ++asked;
    last_move = (after - before).cwiseAbs().maxCoeff();
    return last_move < 1e-6;
  };
  const LeastSquaresResult res = solveLeastSquares(f, Eigen::Vector3d(1.2, 1.0, 0.0), o);
  ASSERT_TRUE(res.summary.usable()) << res.summary.briefReport();
  EXPECT_EQ(asked, res.summary.iterations);
  EXPECT_LT(last_move, 1e-6);
  EXPECT_LT((res.x - truth).cwiseAbs().maxCoeff(), 1e-9);
  o.converged = [](const Eigen::VectorXd&, const Eigen::VectorXd&) { return false; };
  o.max_iterations = 7;
  const LeastSquaresResult never = solveLeastSquares(f, Eigen::Vector3d(1.2, 1.0, 0.0), o);
  EXPECT_EQ(never.summary.termination, Termination::MaxIterations);
  EXPECT_EQ(never.summary.iterations, 7);
}

TEST(LeastSquares, InvalidOptionsAreRefusedNamingTheField) {
  const auto f = [](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    r = x;
    if (J) *J = Eigen::MatrixXd::Identity(x.size(), x.size());
  };
  LeastSquaresOptions o;
  o.rank_tolerance = 0.0;
  const LeastSquaresResult res = solveLeastSquares(f, Eigen::VectorXd::Ones(2), o);
  EXPECT_EQ(res.summary.termination, Termination::InvalidInput);
  EXPECT_NE(res.summary.message.find("rank_tolerance"), std::string::npos);
  o = {};
  o.max_iterations = 0;
  std::string why;
  EXPECT_FALSE(o.validate(&why));
  EXPECT_NE(why.find("max_iterations"), std::string::npos) << why;
  EXPECT_TRUE(LeastSquaresOptions{}.validate(&why)) << why;
}

}  // namespace
}  // namespace rotacal
