#pragma once
// The one-sphere cycle's identification: every trigger of every pose in one fit of the five-axis
// model (core/kinematic_model.hpp) and the probe's effective radius, on the exact geometry:
//   r_j = |t_j - X(p, pose_j)| - (R + r + dR),
// t_j the trigger (ball centre), X the linear-axis position of the sphere centre. No per-pose
// centre fit in between: a pose with four touches and a pretravel error would bias its centre
// along its own touch directions, which change from pose to pose; here dR absorbs it once.
// What the plan cannot separate (core/identifiability.hpp) is held at nominal and named.
#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "core/error_model.hpp"
#include "core/identifiability.hpp"
#include "core/json_io.hpp"
#include "core/kinematic_model.hpp"
#include "core/least_squares.hpp"
#include "core/measurement.hpp"
#include "core/outliers.hpp"
#include "core/probe_plan.hpp"
#include "core/uncertainty_budget.hpp"
#include "cycles/one_sphere/design.hpp"

namespace rotacal {

struct SphereCycleResult {
  KinematicModel model;
  std::vector<IdentifiabilityParameter> names;  // the model's parameters, dR, squareness, backlash terms
  SphereBacklashTerms backlash;                 // where the lost-motion terms sit in x (option backlash)
  Eigen::VectorXd x;                            // mm, rad (held ones at 0), then dR in mm
  Identifiability identifiability;
  Eigen::MatrixXd cov_per_sigma2;               // covariance of x per unit reading variance (mm^2 per mm^2)
  FitSummary summary;
  int touches = 0;
  int dof = 0;
  double residual_sd_um = 0.0;
  std::vector<double> residuals_um;             // per trigger, in the runs' order
  /// Per trigger: J_r_x at the solution (mm per mm / rad, every parameter, held ones included),
  /// the unit normal from the fitted sphere centre, the plan point (index) and run, the time (s:
  /// the controller's clock, else the plan's time from each run's start at the run's end).
  Eigen::MatrixXd J_r_x;
  std::vector<Eigen::Vector3d> normals;
  std::vector<int> point_index, run_index;
  std::vector<double> t_s;
  /// The location errors in the papers' parameters of the machine (000 Eq. (1) / 002 Eq. (2)),
  /// mapped from the fit, and the largest difference between the two models' sphere positions
  /// over the plan's poses (the mapping is exact to first order; this is what the second order
  /// leaves).
  LocationErrors location;
  std::array<int, kNumLocationErrors> location_index_in_x{};  // each papers parameter: its index in x
  double mapping_residual_um = 0.0;
  /// The touches left out of the fit (SphereCycleOptions::hold_out): each one's plan point (index),
  /// run and residual against the model fitted without it (um). The per-trigger vectors above
  /// hold the fitted touches alone.
  struct HeldOut {
    int point_index = 0;
    int run = 0;
    double residual_um = 0.0;
  };
  std::vector<HeldOut> held_out;
};

struct SphereCycleOptions {
  /// Touches left out of the fit (the outlier screen's): still predicted, never fitted. What the
  /// plan cannot separate is decided on every touch of the plan, so that leaving a touch out never
  /// changes which parameters are reported; a hold-out that leaves a fitted parameter without data
  /// is refused (InputError).
  std::function<bool(int run, const ProbePoint& point)> hold_out;
};

/// Throws std::invalid_argument naming the results file when a trigger is missing or the fit fails.
SphereCycleResult identifySphereCycle(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                      const SphereCycleOptions& options = {});

/// The declaration the cycle's tests read (core/declared_noise.hpp), over the plan's touches in
/// plan order. White: the per-touch contributors (perTouchDeclaration: probe repeatability and
/// roughness, else MACHINE.json's repeatability). Structured: the probe's pretravel by direction
/// and the linear axes (probeAxesCovariance at the plan's nominal triggers), each touch's trigger
/// displacement along its approach u read by its residual as (n . u) ds, n the nominal contact
/// normal; none when `declared` is null. The set-up is fitted (dX_S ...), so it is not part of
/// the noise. Throws std::invalid_argument when the two repeatabilities contradict each other.
DeclaredNoise sphereDeclaredNoise(const ProbePlan& plan, const ContributorSet* declared);

/// A fit's residuals (fitted touches, um), the columns of the parameters it frees (its span) and
/// their declared covariance (um^2): what deletionStatistics, testAgainstDeclared and the judge read.
struct SphereFittedProblem {
  Eigen::VectorXd residual_um;
  Eigen::MatrixXd J;
  Eigen::MatrixXd covariance_um2;
  std::vector<std::pair<int, int>> readings;  // (run, plan index) per row: the declaration's keys
};
SphereFittedProblem sphereFittedProblem(const DeclaredNoise& noise, const SphereCycleResult& r);

/// The outlier screen of analyze (core/outliers.hpp) on the sphere cycle's one-stage fit: each
/// fitted touch's GLS deletion residual under `noise`, worst first, refitted without it. `fit` is
/// the fit with the excluded touches held out (the first fit when none is excluded).
struct SphereScreen {
  OutlierOptions options;
  OutlierScreen screen;
  SphereCycleResult fit;
};
SphereScreen screenSphereTouches(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const DeclaredNoise& noise);

Json sphereReportJson(const ProbePlan& plan, const SphereCycleResult& r, const UncertaintyBudget& b,
                      const std::vector<std::string>& files);
/// REPORT.json's figures: each touch's residual against every rotary axis the plan turns and
/// against time, the touches left out beside the fitted ones, a band of +-2 white_sd_um (the
/// declared per-touch scatter; none when 0).
Json sphereFiguresJson(const ProbePlan& plan, const SphereCycleResult& r, double white_sd_um);
std::string sphereText(const SphereCycleResult& r, const UncertaintyBudget& b);

}  // namespace rotacal
