#pragma once
// The uncertainty the spaceframe cycle signs (core/uncertainty_budget.hpp) for what its
// least squares identifies: the eight location errors, the linear axes' scale and the frame's
// set-up on the table (calibrated frame), or the location errors and the scale of X and Y
// relative to Z (self-calibration: the sphere offsets keep the data's u only).
//   Type A  the per-touch scatter (probe repeatability, the sphere's form under the ball) through
//           the estimator's linear map G (sphere fits, then the least squares on the centres):
//           sigma^2 G G^T / repeats, sigma^2 = max(declared, s^2 - E[s_sys^2]) with s the sphere
//           fits' pooled residual and E[s_sys^2] what the Type B contributors leave in it. With no
//           contributors declared, a parameter whose a-posteriori u (the centres' misfit) is larger
//           takes it: unmodelled effects are then the data's to show. Repeats that scatter more
//           raise a parameter to the scatter of their mean.
//   Type B  the declared contributors that act on spheres touched from many directions (probe
//           pretravel per direction, the linear axes' scale, random and squareness errors) and
//           the frame's calibration (FRAME.json's u per coordinate, calibrated frame only), by
//           Monte Carlo: every run draws them, simulates every trigger on the exact simulator
//           (full HTMs, exact ball-on-sphere contact) around the identified model and runs the
//           triggers' deviation through G. Deviation = estimate - truth: a drawn scale is the
//           truth of the fitted scale, so only what the fit gets wrong about it counts.
// docs/uncertainty.md (spaceframe) states the coverage measured.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/json_io.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "core/uncertainty_budget.hpp"
#include "cycles/spaceframe/analyze.hpp"

namespace rotacal {

struct SpaceframeBudgetOptions : BudgetOptions {};

/// Contributors that act independently at every touch: the sphere fits' residual measures them.
bool spaceframeTypeA(const ContributorInfo& contributor);
/// Contributors that act on the space frame as Type B.
bool spaceframeTypeB(const ContributorInfo& contributor);

/// The id of the frame's calibration in the budget (it comes from FRAME.json, not the catalog).
inline constexpr const char* kFrameCalibrationContributor = "frame_calibration";

/// The identified model as the simulator's truth: location errors, scale, the set-up (and the
/// sphere offsets) as moved sphere centres.
Truth spaceframeIdentifiedTruth(const ProbePlan& plan, const SpaceframeAnalysis& analysis);

/// The estimator linearised at an identification: d theta = G d s, theta the budget's parameters
/// (report units), s the trigger of each plan point along its approach (mm).
struct SpaceframeLinearMap {
  std::vector<std::string> names, units;
  std::vector<int> entries;        // FrameModel::toVector() index of each parameter
  Eigen::MatrixXd G;               // parameters x plan points
  Eigen::MatrixXd residual;        // sphere-fit residuals from d s (plan points x plan points)
  int stage1_dof = 0;
  Eigen::VectorXd ideal_s_mm;      // the triggers along the approach on the identified model
};
SpaceframeLinearMap linearSpaceframe(const ProbePlan& plan, const SpaceframeAnalysis& analysis);

/// The budget of `analysis` (from per_run.size() repeats, or one run when per_run is empty).
/// `contributors` null: u_B not evaluated (said in words).
UncertaintyBudget spaceframeBudget(const ProbePlan& plan, const SpaceframeAnalysis& analysis,
                                   const std::vector<SpaceframeAnalysis>& per_run, const ContributorSet* contributors,
                                   const SpaceframeBudgetOptions& options);

/// The budget's parameters' values in report units (its order: location errors, scale, set-up).
Eigen::VectorXd spaceframeBudgetValues(const ProbePlan& plan, const SpaceframeAnalysis& analysis);

/// Adds u_a, u_b, u_c, U and k to REPORT.json's location_errors, linear_axis_scale and
/// frame_setup entries, and the `uncertainty` block.
void addSpaceframeBudget(Json* report, const UncertaintyBudget& budget, const Eigen::VectorXd& values);

}  // namespace rotacal
