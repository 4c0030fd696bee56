// core/uncertainty_budget: the Monte Carlo's moments against closed forms, independence of the
// thread count, and the combination rules (u_c^2 = u_A^2 + u_B^2, U = 2 u_c, correlation).
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.hpp"
#include "core/uncertainty_budget.hpp"

using namespace rotacal;

namespace {

// A linear estimator x_hat = A y of readings y = y0 + sum_c e_c, contributor c a normal vector of
// standard deviation s_c along its own direction d_c: deviation = A (sum_c s_c z_c d_c). The
// covariance is A (sum_c s_c^2 d_c d_c^T) A^T in closed form.
struct LinearToy {
  Eigen::MatrixXd A;
  std::vector<Eigen::VectorXd> d;
  std::vector<double> s;
  MonteCarloProblem problem() const {
    MonteCarloProblem p;
    p.parameters = static_cast<int>(A.rows());
    for (size_t c = 0; c < d.size(); ++c) p.contributors.push_back("c" + std::to_string(c));
    p.deviation = [this](std::uint64_t seed, int run, int only) {
      Eigen::VectorXd y = Eigen::VectorXd::Zero(A.cols());
      for (size_t c = 0; c < d.size(); ++c) {
        Rng r(seed, static_cast<std::uint64_t>(run) * 16 + c);
        const double z = r.normal();
        if (only < 0 || static_cast<size_t>(only) == c) y += s[c] * z * d[c];
      }
      return Eigen::VectorXd(A * y);
    };
    return p;
  }
  Eigen::MatrixXd covariance() const {
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(A.cols(), A.cols());
    for (size_t c = 0; c < d.size(); ++c) C += s[c] * s[c] * d[c] * d[c].transpose();
    return A * C * A.transpose();
  }
};

LinearToy toy() {
  LinearToy t;
  t.A.resize(3, 4);
  t.A << 1.0, 0.5, 0.0, -0.2, 0.0, 1.0, 2.0, 0.3, 0.4, 0.0, -1.0, 1.0;
  t.d = {Eigen::Vector4d(1, 0, 0, 1), Eigen::Vector4d(0, 1, 1, 0), Eigen::Vector4d(0.5, -0.5, 0.2, 1)};
  t.s = {2.0, 0.7, 1.5};
  return t;
}

}  // namespace

TEST(SampleMoments, MatchesTheTwoPassFormulas) {
  Rng r(3, 1);
  std::vector<Eigen::VectorXd> xs;
  SampleMoments m(2), a(2), b(2);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector2d x(1e3 + r.normal(), 5.0 * r.normal() - 0.3);
    xs.push_back(x);
    m.add(x);
    (i < 20 ? a : b).add(x);
  }
  a.merge(b);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& x : xs) mean += x;
  mean /= 50.0;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& x : xs) cov += (x - mean) * (x - mean).transpose();
  cov /= 49.0;
  EXPECT_LT((m.mean() - mean).norm(), 1e-9);
  EXPECT_LT((m.covariance() - cov).norm(), 1e-6 * cov.norm());
  EXPECT_LT((a.covariance() - cov).norm(), 1e-6 * cov.norm());
  EXPECT_EQ(a.count(), 50);
}

TEST(MonteCarlo, CovarianceMatchesTheClosedFormWithinSampling) {
  const LinearToy t = toy();
  const MonteCarloResult mc = runMonteCarlo(t.problem(), 20000, 20000, 11, 2);
  const Eigen::MatrixXd exact = t.covariance();
  const Eigen::MatrixXd got = mc.combined.covariance();
  for (int i = 0; i < 3; ++i) {
    // Relative standard error of a variance from n normal samples: sqrt(2 / n) = 1 %; 4 of them.
    EXPECT_NEAR(std::sqrt(got(i, i)), std::sqrt(exact(i, i)), 0.02 * std::sqrt(exact(i, i)));
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(got(i, j) / std::sqrt(got(i, i) * got(j, j)), exact(i, j) / std::sqrt(exact(i, i) * exact(j, j)), 0.03);
  }
  // Each contributor alone: A s_c^2 d_c d_c^T A^T.
  for (size_t c = 0; c < t.d.size(); ++c) {
    const Eigen::VectorXd col = t.A * t.d[c] * t.s[c];
    const Eigen::VectorXd u = mc.alone[c].covariance().diagonal().cwiseSqrt();
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(u[i], std::abs(col[i]), 0.02 * std::abs(col[i]) + 1e-12);
  }
}

TEST(MonteCarlo, ResultsDoNotDependOnTheNumberOfThreads) {
  const LinearToy t = toy();
  const MonteCarloResult one = runMonteCarlo(t.problem(), 1000, 300, 5, 1);
  const MonteCarloResult two = runMonteCarlo(t.problem(), 1000, 300, 5, 2);
  EXPECT_EQ(one.combined.covariance(), two.combined.covariance());
  EXPECT_EQ(one.alone[2].covariance(), two.alone[2].covariance());
  const MonteCarloResult other_seed = runMonteCarlo(t.problem(), 1000, 300, 6, 2);
  EXPECT_NE(one.combined.covariance(), other_seed.combined.covariance());
}

TEST(UncertaintyBudget, CombinesTypeAAndTypeBAndExpandsWithK2) {
  const LinearToy t = toy();
  UncertaintyBudget b;
  b.names = {"x", "y", "z"};
  b.units = {"um", "um", "mdeg"};
  b.cov_a = Eigen::Vector3d(0.09, 0.16, 0.01).asDiagonal();
  setTypeB(&b, runMonteCarlo(t.problem(), 4000, 1000, 2, 2), t.problem().contributors);
  std::string why;
  ASSERT_TRUE(b.validate(&why)) << why;
  const Eigen::VectorXd ua = b.uA(), ub = b.uB(), uc = b.uC();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(uc[i] * uc[i], ua[i] * ua[i] + ub[i] * ub[i], 1e-9);
    EXPECT_NEAR(b.expanded()[i], 2.0 * uc[i], 1e-12);
  }
  const Eigen::MatrixXd r = b.correlation();
  const Eigen::MatrixXd c = b.covariance();
  EXPECT_NEAR(r(0, 1), c(0, 1) / std::sqrt(c(0, 0) * c(1, 1)), 1e-12);
  EXPECT_DOUBLE_EQ(r(2, 2), 1.0);
  // The JSON carries the same numbers, and the budget lists the largest contributor first.
  const Json j = budgetJson(b);
  EXPECT_NEAR(j["parameters"]["y"]["U"].get<double>(), 2.0 * uc[1], 1e-5);
  EXPECT_EQ(j["covariance"].size(), 3u);
  const auto& top = j["budget"]["x"];
  ASSERT_GE(top.size(), 2u);
  EXPECT_GE(top[0]["u"].get<double>(), top[1]["u"].get<double>());
  Json params = {{"x", {{"value", 1.0}, {"u", 0.3}}}, {"w", {{"value", 2.0}}}};
  addBudgetFields(&params, b);
  EXPECT_NEAR(params["x"]["u_c"].get<double>(), uc[0], 1e-5);
  EXPECT_DOUBLE_EQ(params["x"]["u"].get<double>(), 0.3);  // contract.md: u stays the data's
  EXPECT_FALSE(params["w"].contains("u_c"));
}
