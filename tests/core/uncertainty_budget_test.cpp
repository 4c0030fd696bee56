// core/uncertainty_budget: the Monte Carlo's moments against closed forms, independence of the
// thread count, the combination rules (u_c^2 = u_A^2 + u_B^2, U = k u_c, correlation), the
// coverage factor read off the Monte Carlo against closed forms, and u_A's scatter rule.
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

TEST(UncertaintyBudget, CombinesTypeAAndTypeBAndExpandsWithItsCoverageFactor) {
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
    // Normal contributors and a normal u_A: the Monte Carlo's k is the normal 2, within the
    // sampling of a 95.45 % point from 4000 runs (relative standard error about 1.5 %).
    EXPECT_NEAR(b.coverageFactors()[i], 2.0, 0.1);
    EXPECT_NEAR(b.expanded()[i], b.coverageFactors()[i] * uc[i], 1e-12);
  }
  const Eigen::MatrixXd r = b.correlation();
  const Eigen::MatrixXd c = b.covariance();
  EXPECT_NEAR(r(0, 1), c(0, 1) / std::sqrt(c(0, 0) * c(1, 1)), 1e-12);
  EXPECT_DOUBLE_EQ(r(2, 2), 1.0);
  // The JSON carries the same numbers, and the budget lists the largest contributor first.
  const Json j = budgetJson(b);
  EXPECT_NEAR(j["parameters"]["y"]["U"].get<double>(), b.expanded()[1], 1e-5);
  EXPECT_NEAR(j["parameters"]["y"]["k"].get<double>(), b.coverageFactors()[1], 1e-5);
  EXPECT_EQ(j["covariance"].size(), 3u);
  const auto& top = j["budget"]["x"];
  ASSERT_GE(top.size(), 2u);
  EXPECT_GE(top[0]["u"].get<double>(), top[1]["u"].get<double>());
  Json params = {{"x", {{"value", 1.0}, {"u", 0.3}}}, {"w", {{"value", 2.0}}}};
  addBudgetFields(&params, b);
  EXPECT_NEAR(params["x"]["u_c"].get<double>(), uc[0], 1e-5);
  // u is u_c in every report: the entry's earlier u (0.3) is replaced, and u_c is the quadrature
  // sum of its parts (to the printed rounding, 5e-7 each).
  EXPECT_EQ(params["x"]["u"], params["x"]["u_c"]);
  EXPECT_NE(params["x"]["u"].get<double>(), 0.3);
  const double pa = params["x"]["u_a"].get<double>(), pb = params["x"]["u_b"].get<double>(), pc = params["x"]["u_c"].get<double>();
  EXPECT_NEAR(pc * pc, pa * pa + pb * pb, 1.1e-6 * (pa + pb + pc));
  EXPECT_NEAR(pa, b.uA()[0], 5e-7);
  EXPECT_NEAR(pb, b.uB()[0], 5e-7);
  EXPECT_NEAR(params["x"]["U"].get<double>(), b.expanded()[0], 1e-5);
  EXPECT_NEAR(params["x"]["u_between"].get<double>(), b.uBetween()[0], 5e-7);
  EXPECT_EQ(j["parameters"]["y"]["u"], j["parameters"]["y"]["u_c"]);
  EXPECT_FALSE(params["w"].contains("u_c"));
  EXPECT_FALSE(params["w"].contains("u"));
  // No Type B evaluated for a number: u_c = u_A, u_B = 0, U = 2 u_c (k for a normal distribution).
  Json alone = Json::object();
  setTypeAOnlyFields(&alone, 0.25);
  EXPECT_DOUBLE_EQ(alone["u"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(alone["u_c"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(alone["u_b"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(alone["U"].get<double>(), 0.5);
  // Arrays: element by element, the same as one number at a time (3-4-5: u_c = 5 exactly).
  Json arr = Json::object();
  setUncertaintyArrays(&arr, Eigen::Vector2d(3.0, 0.0), Eigen::Vector2d(4.0, 1.0), Eigen::Vector2d(2.0, 1.5));
  EXPECT_DOUBLE_EQ(arr["u"][0].get<double>(), 5.0);
  EXPECT_DOUBLE_EQ(arr["u_c"][1].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(arr["U"][0].get<double>(), 10.0);
  EXPECT_DOUBLE_EQ(arr["U"][1].get<double>(), 1.5);
}

namespace {

// A Monte Carlo whose deviation is uniform on [-a, a] in its one parameter.
MonteCarloProblem uniformProblem(double a) {
  MonteCarloProblem p;
  p.parameters = 1;
  p.contributors = {"u"};
  p.deviation = [a](std::uint64_t seed, int run, int) {
    Rng r(seed, static_cast<std::uint64_t>(run));
    return Eigen::VectorXd::Constant(1, a * (2.0 * r.uniform() - 1.0));
  };
  return p;
}

// P(|X + E| <= q), X uniform on [-a, a], E ~ N(0, s^2), by the trapezoidal rule over x: the
// closed form's integrand, not the code's sample mean.
double uniformPlusNormalHeld(double a, double s, double q) {
  constexpr int kSteps = 20000;
  double sum = 0.0;
  for (int i = 0; i <= kSteps; ++i) {
    const double x = -a + 2.0 * a * i / kSteps;
    const double f = 0.5 * (std::erf((q - x) / (s * std::sqrt(2.0))) + std::erf((q + x) / (s * std::sqrt(2.0))));
    sum += (i == 0 || i == kSteps ? 0.5 : 1.0) * f;
  }
  return sum / kSteps;
}

}  // namespace

TEST(UncertaintyBudget, CoverageFactorOfABoundedContributorIsItsClosedForm) {
  // u_B alone, uniform on [-a, a]: U holds 95.45 % at q = 0.9545 a, u = a / sqrt(3): k = 1.653
  // (a normal's 2 would hold 100 %).
  const double a = 3.0;
  UncertaintyBudget b;
  b.names = {"x"};
  b.units = {"um"};
  b.cov_a = Eigen::MatrixXd::Zero(1, 1);
  setTypeB(&b, runMonteCarlo(uniformProblem(a), 20000, 0, 3, 2), {"u"});
  EXPECT_NEAR(b.uB()[0], a / std::sqrt(3.0), 0.02);
  EXPECT_NEAR(b.coverageFactors()[0], kCoverageProbability * std::sqrt(3.0), 0.02);
  // With a normal Type A part as large: k from the convolution, checked by quadrature.
  b.cov_a(0, 0) = 3.0;  // u_A = sqrt(3) um = u_B
  setTypeB(&b, runMonteCarlo(uniformProblem(a), 20000, 0, 3, 2), {"u"});
  const double U = b.expanded()[0];
  EXPECT_NEAR(uniformPlusNormalHeld(a, std::sqrt(3.0), U), kCoverageProbability, 0.003);
  EXPECT_LT(b.coverageFactors()[0], 2.0);
  // Below kMinRunsForCoverageFactor runs the tail is not read: k = 2.
  setTypeB(&b, runMonteCarlo(uniformProblem(a), kMinRunsForCoverageFactor - 1, 0, 3, 2), {"u"});
  EXPECT_DOUBLE_EQ(b.coverageFactors()[0], kCoverageFactor);
}

TEST(UncertaintyBudget, ReadingScatterRaisesOnlyWhatTheResidualShows) {
  // No systematic share: a residual at the declared 0.7 um (100 dof) keeps it.
  ReadingScatter r = readingScatter(0.49, 0.52, 100, {});
  EXPECT_DOUBLE_EQ(r.variance_um2, 0.49);
  EXPECT_GT(r.p_value, kScatterExcessAlpha);
  // Twice the declared variance over 100 dof: chi^2 survival of 200 at 100 dof, far below 5 %.
  r = readingScatter(0.49, 0.98, 100, {});
  EXPECT_LT(r.p_value, 1e-6);
  EXPECT_DOUBLE_EQ(r.variance_um2, 0.98);
  // A residual the contributors' own spread explains (10 % of their draws left 6 um^2, the rest
  // 4): the declared scatter, where "residual less the mean share" would have said 0.85 um^2.
  std::vector<double> sys(90, 4.0);
  sys.insert(sys.end(), 10, 6.0);
  r = readingScatter(0.05, 5.05, 100, sys);
  EXPECT_DOUBLE_EQ(r.variance_um2, 0.05);
  EXPECT_NEAR(r.p_value, 0.10, 1e-6);  // only the 6 um^2 draws reach 5.05 (the 4 um^2 ones need chi^2 >= 2100)
  // One draw in 100: p = 1 %, below the 5 % level, so the excess is taken.
  std::vector<double> rare(99, 4.0);
  rare.push_back(6.0);
  r = readingScatter(0.05, 5.05, 100, rare);
  EXPECT_NEAR(r.p_value, 0.01, 1e-6);
  EXPECT_NEAR(r.variance_um2, 5.05 - 4.02, 1e-12);  // the residual less the mean share
}

TEST(UncertaintyBudget, RepeatsRaiseTypeAOnlyWhenTheirScatterIsSignificant) {
  // Three repeats of two parameters, u_A 1 for both. x: 0, 10, 20 (a drift: standard error of the
  // mean 10 / sqrt(3), chi^2_2 = 2 * 33.3, p = 4e-15): raised to it, the correlation kept. y: 0,
  // 2, 4 (standard error 1.15, above u_A, but chi^2_2 = 2.67, p = 0.26): a fluctuation, left.
  Eigen::MatrixXd cov_a(2, 2);
  cov_a << 1.0, 0.5, 0.5, 1.0;
  const std::vector<Eigen::VectorXd> repeats = {Eigen::Vector2d(0, 0), Eigen::Vector2d(10, 2.0), Eigen::Vector2d(20, 4.0)};
  const std::string why = raiseToRepeatScatter(&cov_a, repeats);
  EXPECT_NEAR(cov_a(0, 0), 100.0 / 3.0, 1e-9);
  EXPECT_DOUBLE_EQ(cov_a(1, 1), 1.0);
  EXPECT_NEAR(cov_a(0, 1) / std::sqrt(cov_a(0, 0) * cov_a(1, 1)), 0.5, 1e-12);
  EXPECT_NE(why.find("1 parameter(s)"), std::string::npos) << why;
}
