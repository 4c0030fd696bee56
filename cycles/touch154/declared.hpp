#pragma once
// touch154's declared noise (core/declared_noise.hpp): the touches' covariance under the
// machine's declared contributors, the same first-order chain its u_B propagates
// (triggerCovariance), so that the outlier screen and diagnose test the machine the budget
// describes; and the per-point model's span, which the outlier statistic needs.
#include <Eigen/Core>
#include <cstdint>
#include <map>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct Touch154Noise {
  DeclaredNoise noise;
  Eigen::MatrixXd basis;           // plan points x rank: the lsq_per_point model's span; empty: none
  std::map<int, int> index_of_id;  // plan point id -> index in plan order
};

/// Draws of the declared machine behind the whole-residual test's null (DeclaredNoise::
/// structured_draws_um): its p-value near the offsets' 1e-3 needs the null's variance to a few per
/// cent, i.e. some thousands of draws; the seed is fixed so that one data set gets one verdict.
constexpr int kTouch154NullDraws = 4000;
constexpr std::uint64_t kTouch154NullSeed = 0x154;

/// White: the per-touch contributors (perTouchDeclaration). Structured: every other declared
/// contributor through the exact chain linearised at the nominal machine; none when `declared` is
/// null or the plan cannot identify the location errors by least squares (then no basis either).
Touch154Noise touch154DeclaredNoise(const ProbePlan& plan, const ContributorSet* declared);

/// The readings (run, plan index) of a fit's residuals that are not held out, in their order.
std::vector<std::pair<int, int>> fittedReadings(const Touch154Noise& n, const std::vector<PointResidual>& residuals);

/// A fit's residual (fitted touches only) with the per-point model's rows and their declared
/// covariance: what deletionStatistics and testAgainstDeclared read. Requires a basis.
struct FittedReadings {
  Eigen::VectorXd residual_um;
  Eigen::MatrixXd J;
  Eigen::MatrixXd covariance_um2;
  Eigen::MatrixXd null_draws_um;  // readings x draws of the declared noise (testAgainstDeclared's null)
};
FittedReadings fittedProblem(const Touch154Noise& n, const std::vector<PointResidual>& residuals);

/// The outlier statistic of each fitted touch of `fit` (deletionStatistics). Requires a basis.
Eigen::VectorXd touch154OutlierStatistic(const Touch154Noise& n, const ScreenedFit& fit);

}  // namespace rotacal
