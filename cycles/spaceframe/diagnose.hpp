#pragma once
// Diagnosis (issues 6 and 16) for the space-frame cycle (003), decided by the one judge
// (core/judge.hpp; rules in docs/diagnosis.md "The judge").
//
// Baseline: the eight location errors and the frame's setup (translation, rotation; or, when the
// frame self-calibrates, nominal_from=initial, every sphere's offset), fitted by weighted
// Gauss-Newton to the measured centres. Each centre is whitened by its sphere fit's covariance
// per unit touch noise, C_i / runs (W_i = L_i^-1), so the judge's observations are W_i r_i with
// the DECLARED probe noise (MACHINE.json) as sigma: chi-square with m - rank dof when the model
// is complete. The judge gets the baseline's Jacobian and, at the baseline's solution, each
// cause's columns by central differences of the same exact centre model (sphere fit of the
// touches through the linear axes' map):
//   linear_axis_scale       s_x, s_y, s_z (actual = read (1 + s)), um/m
//   linear_axis_squareness  S_xy, S_xz, S_yz (000 Eq. (23): actual = read + E(read)), um/m
//   thermal_drift           dx, dy, dz of the first rotary axis change linearly with time, um/h
//   frame_temperature       the frame grows about its origin by e (um/m): exactly an isotropic
//                           scale to this plan, which the judge reports from the Jacobians.
// Groups: orientations (theta and theta + 360 are one). Factors: sphere, C, A, time, X/Y/Z.
#include <string>
#include <vector>

#include "core/judge.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/spaceframe/noise.hpp"

namespace rotacal {

/// One weighted Gauss-Newton fit of a parameter subset of FrameModel to the measured centres.
struct SpaceframeFit {
  FrameModel model;
  Eigen::Matrix<double, FrameModel::kSize, 1> u = Eigen::Matrix<double, FrameModel::kSize, 1>::Zero();  // k = 1, mm / rad / 1
  std::vector<int> active;       // FrameModel::toVector indices
  int rank = 0;
  int dof = 0;
  double chi2 = 0.0;             // whitened residual^2 / sigma^2
  double residual_rms_um = 0.0;  // plain centre residual, per coordinate
  double linearisation_um = 0.0; // |exact residual - linear prediction| of the last step, max
  bool converged = false;
};

struct SpaceframeDiagnosisOptions {
  JudgeOptions judge;     // alpha from the CLI's --alpha
  double sigma_um = 0.7;  // declared probe noise (MACHINE.json), k = 1
  /// The declaration (spaceframeDeclaredNoise: the machine's contributors): given, the judge
  /// reads the centres' declared covariance (JudgeProblem::covariance, structured between
  /// centres) and sigma_um is not used; null: each centre whitened by its sphere fit and sigma_um.
  const SpaceframeNoise* noise = nullptr;
  /// Touches the outlier screen left out (SpaceframeOptions::held_out_ids).
  std::set<int> held_out_ids;
  /// Candidate causes by name; empty: the whole catalog above.
  std::vector<std::string> candidates;
};

struct SpaceframeDiagnosis {
  double sigma_um = 0.0;            // declared touch noise
  std::string declaration;          // what the judge tests against
  double fit_noise_um = 0.0;        // the sphere fits' pooled touch noise (reported, not used)
  int centres = 0;
  int holdout_groups = 0;
  SpaceframeFit baseline;
  JudgeProblem problem;             // what the judge was given (tests read its Jacobians)
  JudgeSummary judged;
};

/// The catalog's names, in order.
std::vector<std::string> spaceframeCatalog();

SpaceframeDiagnosis diagnoseSpaceframe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                       const SpaceframeDiagnosisOptions& options);

Json spaceframeDiagnosisJson(const SpaceframeDiagnosis& d, const ProbePlan& plan);
std::string spaceframeDiagnosisText(const SpaceframeDiagnosis& d);

}  // namespace rotacal
