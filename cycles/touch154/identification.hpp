#pragma once
// Identification of the eight location errors from touch-probe triggers.
//  - ClosedForm: 000 Eq. (3)-(19) on the relative displacements of Eq. (21), with the
//    corrections documented in closed_form.hpp.
//  - LeastSquaresRigidSetup: Gauss-Newton over all points with the exact simulator as the model;
//    nuisance = the test piece's rigid setup (3 translations, 3 rotations).
//  - LeastSquaresPerPoint: the form-immune variant: nuisance = one surface offset per target
//    point (the piece's setup and form together), so only the displacement of each point
//    between poses informs the location errors (the idea of 000 Eq. (21), over all points).
//    Face orientations (which enter at second order only) are re-estimated at every iteration
//    from the reference pose's points.
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/error_model.hpp"
#include "core/least_squares.hpp"
#include "core/measurement.hpp"
#include "core/outliers.hpp"
#include "core/probe_plan.hpp"
#include "cycles/touch154/model_extension.hpp"

namespace rotacal {

enum class Method { ClosedForm, LeastSquaresRigidSetup, LeastSquaresPerPoint };
std::string_view methodName(Method method);   // "closed_form", "lsq_rigid_setup", "lsq_per_point"
Method methodFromName(std::string_view name);  // throws std::invalid_argument

struct IdentificationOptions {
  Method method = Method::LeastSquaresPerPoint;
  int max_iterations = 30;
  /// Stop when the largest scaled step is below this (relative to the scaled parameter size).
  // mm of trigger effect: 1e-7 um, two decades above the rounding floor of 200 mm coordinates.
  double step_tolerance = 1e-10;
  /// Singular values of the column-scaled Jacobian below this fraction of the largest one count
  /// as zero: the parameters in their null space are reported as not identifiable. 1e-6 sits
  /// far above the finite-difference noise of extension columns (~1e-9) and far below any
  /// usable conditioning (000's 154-point plan: condition ~1e3).
  double rank_tolerance = 1e-6;
  /// Probe repeatability (um, k = 1) used for the closed form's uncertainty, and reported beside
  /// the fit's own noise estimate.
  double prior_sigma_um = 0.7;
  /// Model extensions fitted together with the location errors (least squares only).
  std::vector<ExtensionPtr> extensions;
  /// Observations left out of the fit (held out); their residuals are still predicted.
  std::function<bool(int run, const ProbePoint& point)> hold_out;

  bool validate(std::string* why) const;
};

struct IdentificationResult : ScreenedFit {  // summary: rms and sigma in um, cost in mm^2
  LocationErrors estimate;
  ErrorVector u = ErrorVector::Zero();  // standard uncertainty (k = 1), mm / rad
  Eigen::Matrix<double, kNumLocationErrors, kNumLocationErrors> covariance =
      Eigen::Matrix<double, kNumLocationErrors, kNumLocationErrors>::Zero();
  std::vector<std::string> unidentifiable;  // parameter names, when RankDeficient
  Eigen::VectorXd extension_values;         // internal units, in the order of the extensions' parameters
  Eigen::VectorXd extension_u;
  /// Correlation of each extension parameter with each location error (rows: extension params).
  Eigen::MatrixXd extension_correlation;
  double holdout_rms_um = 0.0;              // rms of the held-out residuals (0 when none)
  int holdout_points = 0;
  Method method = Method::LeastSquaresPerPoint;
};

/// Identifies the location errors from one or more runs of the same plan (repeats share the
/// test piece, hence its nuisance parameters). Never throws on bad data: the summary says why.
IdentificationResult identify(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                              const IdentificationOptions& options);

/// The least-squares problem linearised at the baseline's solution (the judge works on
/// it). The baseline (location errors + nuisance, no extension) is fitted to convergence; then
/// the model with the candidate extensions, all at zero, is differentiated there: the baseline's
/// columns analytically, the extensions' by central differences of the exact model (the same
/// columns the identification itself uses when it fits them).
struct Linearisation {
  IdentificationResult baseline;                  // the converged baseline fit
  struct Observation {
    int run = 0;
    const ProbePoint* point = nullptr;
    double t_h = 0.0;                             // relative to the data's mean time
  };
  std::vector<Observation> observations;          // fitted ones, in the residuals' order
  Eigen::VectorXd residual_um;                    // measured - baseline model
  /// d(model, um) / d(parameter, report unit): location errors (um, mdeg) then nuisance (mm of
  /// surface offset per target: um).
  Eigen::MatrixXd J0;
  std::vector<std::string> J0_names, J0_units;
  std::vector<Eigen::MatrixXd> extension_J;       // per extension: um per its report unit
  bool ok = false;                                // false: the baseline did not converge
};

/// Linearises the least-squares problem (options.method must be a least-squares method; its
/// `extensions` are ignored: `candidates` are differentiated, not fitted).
Linearisation lineariseAtBaseline(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                  const IdentificationOptions& options, const std::vector<ExtensionPtr>& candidates);

/// Observation time (s) of a trigger: its own clock when the controller has one, else the
/// plan's t_s plus one cycle duration (plus one minute) per earlier repeat.
double observationTime_s(const ProbePlan& plan, int run, const ProbePoint& point, const TriggerPoint& trigger);


}  // namespace rotacal
