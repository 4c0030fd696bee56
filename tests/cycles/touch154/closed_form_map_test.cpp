// The closed form as a linear map (cycles/touch154/closed_form_map.hpp), against the closed form itself
// (core/closed_form.cpp) and against the exact simulator.
#include <gtest/gtest.h>

#include <cmath>

#include "cycles/touch154/closed_form.hpp"
#include "cycles/touch154/closed_form_map.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/rng.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

/// Triggers moved along their approaches by s (mm) from the nominal ones.
MeasurementRun displaced(const ProbePlan& plan, const Eigen::VectorXd& s) {
  MeasurementRun r;
  for (size_t i = 0; i < plan.points.size(); ++i)
    r.points.push_back({plan.points[i].id, plan.points[i].trigger_m_mm + s[static_cast<long>(i)] * plan.points[i].approach_m, 0.0});
  return r;
}

TEST(ClosedFormMap, PooledMapIsAnalyzesClosedForm) {
  // On arbitrary displacements (10 um rms), G s equals solvePatterns(touch154Patterns(...)): the
  // closed form is linear in the coordinates. Agreement to rounding: 1e-9 mm, 1e-10 rad.
  const ProbePlan plan = test::touch154Plan();
  const ClosedFormMatrix G = closedFormMap(plan, tiltPairsPooled());
  Rng rng(11, 0);
  for (int k = 0; k < 5; ++k) {
    Eigen::VectorXd s(static_cast<long>(plan.points.size()));
    for (long i = 0; i < s.size(); ++i) s[i] = 0.01 * rng.normal();
    const ErrorVector direct = solvePatterns(touch154Patterns(plan, displaced(plan, s))).values;
    const ErrorVector mapped = G * s;
    for (int i = 0; i < kNumLocationErrors; ++i) EXPECT_NEAR(mapped[i], direct[i], i < 4 ? 1e-9 : 1e-10) << i;
  }
}

TEST(ClosedFormMap, OwnPattern3MapsEqualTheClosedFormsOwn) {
  // pattern3Map rebuilds Patterns 3-a..c from the relative displacements; with the pooled pairs
  // its values and first-order rows (map x J_s_e of the exact simulator) must be those of
  // touch154Patterns (its rows come from nominal coordinates; agreement 1e-6 relative, the
  // central-difference truncation of J_s_e).
  const ProbePlan plan = test::touch154Plan();
  const long n = static_cast<long>(plan.points.size());
  const MeasurementRun nominal = displaced(plan, Eigen::VectorXd::Zero(n));
  const auto eq0 = touch154Patterns(plan, nominal);
  const Eigen::MatrixXd J = J_s_e(plan, LocationErrors{});
  for (const auto& e : eq0) {
    if (e.name != "3-a" && e.name != "3-b" && e.name != "3-c") continue;
    int count = 0;
    const Eigen::RowVectorXd m = pattern3Map(plan, e.name, tiltPairsPooled(), &count);
    EXPECT_EQ(count, e.points) << e.name;
    Rng rng(5, 1);
    Eigen::VectorXd s(n);
    for (long i = 0; i < n; ++i) s[i] = 0.01 * rng.normal();
    double value = 0;
    for (const auto& x : touch154Patterns(plan, displaced(plan, s)))
      if (x.name == e.name) value = x.value_mm;
    EXPECT_NEAR(m.dot(s), value, 1e-12) << e.name;
    const Eigen::RowVectorXd row = m * J;
    for (int j = 0; j < kNumLocationErrors; ++j)
      EXPECT_NEAR(row[j], e.row[j], 1e-6 * std::max(1.0, std::abs(e.row[j]))) << e.name << " coefficient " << j;
  }
}

TEST(ClosedFormMap, PaperPairsRecoverTheErrorsOfTheExactSimulator) {
  // 000's pose pairs (III -> VI only) are still a closed form of the eight errors: on the exact
  // simulator with 000 Table 4's errors it recovers them to its second-order bias (0.1 um,
  // 0.02 mdeg, as the pooled closed form in tests/cycles/touch154/identification_test.cpp).
  const ProbePlan plan = test::touch154Plan();
  const LocationErrors truth = test::table4Mean();
  const MeasurementRun run = simulate(plan, test::truthWith(truth), {});
  Eigen::VectorXd s(static_cast<long>(plan.points.size()));
  for (size_t i = 0; i < plan.points.size(); ++i) s[static_cast<long>(i)] = alongApproach(plan.points[i], run.points[i]);
  LocationErrors e;
  e.values = closedFormMap(plan, tiltPairs000()) * s;
  for (int i = 0; i < kNumLocationErrors; ++i)
    EXPECT_NEAR(e.reportValue(i), truth.reportValue(i), i < 4 ? 0.1 : 0.02) << i;
  // And it differs from the pooled map: Patterns 3 see only III and VI.
  int count = 0;
  const Eigen::RowVectorXd m = pattern3Map(plan, "3-a", tiltPairs000(), &count);
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const auto& pose = plan.points[i].pose_name;
    if (pose != "I" && pose != "III" && pose != "VI") {
      EXPECT_EQ(m[static_cast<long>(i)], 0.0) << "point " << i + 1;
    }
  }
  EXPECT_GT(count, 0);
}

}  // namespace
}  // namespace rotacal
