#pragma once
// Analysis of fixed-tool-tip readings (004). 004 Sec. V turns the transverse reading into an
// angular error, dA = -dYp / (R cos A); with dYp = -dy (004's laser reads the sphere moving
// toward it; rotacal's dy is the tip's deviation, machine frame) that is dA = dy / (R cos A).
// It divides by zero at 90 deg, ignores dz, and reads a pivot-length error dR as angular error
// dR tan A / R. rotacal fits the exact model instead:
//   d(theta_k) = F(theta_k + e_k, R + dR) - F(theta_k, R) - [same at the sweep's zero pose]
// with F = the tip offset Rx(A) Ry(B) (0, 0, -R) projected on the read plane, one angular error
// e_k per commanded angle and one pivot-length error dR (model "angular+pivot"), or e_k alone
// (model "angular", 004's). Gauss-Newton on the exact model (each step a linear least squares),
// standard uncertainties from the residual (k = 1).
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "core/uncertainty_budget.hpp"
#include "core/json_io.hpp"
#include "cycles/tooltip/plan.hpp"
#include "core/statistics.hpp"  // fSurvival

namespace rotacal {

struct TooltipFitOptions {
  bool fit_pivot_length = true;  // false: 004's model (angular errors only)
  int max_iterations = 20;
  // The engine's step tolerance (core/least_squares): stop when a step changes no reading's model
  // value by more than this (um). The model values reach the radius (381 mm = 3.8e5 um), whose
  // double rounding is 6e-11 um: 1e-9 um stops at the rounding, far below any laser's resolution.
  double step_tol = 1e-9;
  double sigma_floor_um = 0.0;   // lower bound of the noise used for uncertainties and tests

  /// False, and what is wrong naming the field, when invalid (as LeastSquaresOptions).
  bool validate(std::string* why) const;
};

struct TooltipFit {
  std::string model;             // "angular" | "angular+pivot"
  bool converged = false;
  int iterations = 0;
  std::vector<double> angles_deg;  // distinct commanded angles of the stepping axis, ascending
  std::vector<double> e_mdeg, u_e_mdeg;  // angular positioning error at each angle
  double dR_um = 0.0, u_dR_um = 0.0;     // pivot-length error (0 and 0 in the angular model)
  double rss_um2 = 0.0;
  int observations = 0;          // readings x 2 components (zero readings excluded)
  int dof = 0;
  double residual_rms_um = 0.0;
  double sigma_um = 0.0;         // noise used for the uncertainties
  double last_step_um = 0.0;     // largest parameter change (mm, rad) one more Gauss-Newton step would make at the solution
  std::vector<double> res_t_um, res_z_um;  // residual per reading (data - model; NaN where not read)
  std::vector<double> model_t_um, model_z_um;  // the model per reading (0 at the zero readings)
  /// The values fitted (read, not a zero reading): (run, 2 k + c) with k the plan point and c = 0
  /// the transverse component, 1 Z; their residual (um) and the Jacobian of the fitted
  /// parameters there (um per rad or mm): what a test against the declared noise reads.
  std::vector<std::pair<int, int>> kept_values;
  Eigen::VectorXd kept_residual_um;
  Eigen::MatrixXd kept_J;
};

/// The exact model of every non-zero reading (transverse, Z interleaved; um) at the parameters
/// x = [e_0 .. e_{J-1} (rad, one per distinct angle, ascending), dR (mm)] and its analytic
/// Jacobian J_model_x (what the Gauss-Newton uses; tests check it against finite differences).
struct TooltipModelEval {
  Eigen::VectorXd model_um;
  Eigen::MatrixXd J_model_x;
  int angles = 0;
};
TooltipModelEval evaluateTooltipModel(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const Eigen::VectorXd& x);

/// Fits readings of one or more repeats of `plan`.
TooltipFit fitTooltip(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipFitOptions& options);

/// Leave-one-angle-out: each commanded angle (other than 0) is left out, the model is fitted to
/// the rest, its angular error at the left-out angle is fitted to the left-out readings alone,
/// and what remains is the held-out residual (rms over the left-out components, um).
double tooltipHoldoutRms(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipFitOptions& options);

/// 004's dA = dy / (R cos A) for each reading of the first run (mdeg); NaN where cos A = 0.
std::vector<double> angularError004Mdeg(const ProbePlan& plan, const TooltipRun& run);

/// The analysis of `analyze`: both models, 004's formula, REPORT.json with figures.
struct TooltipAnalysis {
  TooltipFit joint;      // angular + pivot
  TooltipFit angular;    // 004's model
  std::vector<double> da004_mdeg;
  std::vector<std::string> result_files;
  bool transverse_only = false;  // no dz read: dR not identifiable, joint = the angular model
};
TooltipAnalysis analyzeTooltip(const ProbePlan& plan, const std::vector<TooltipRun>& runs);
Json tooltipReportJson(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipAnalysis& a);
/// `budget` (its u_c, what REPORT.json's u is) when given: dR's and each angle's u is u_c; else
/// the fit's own u, said so.
std::string tooltipReportText(const ProbePlan& plan, const TooltipAnalysis& a, const UncertaintyBudget* budget = nullptr);

}  // namespace rotacal
