#pragma once
// Diagnosis (issue 6) for the space-frame cycle (003): do the linear axes have scale errors that
// the calibration engineer's model (rotary-axis location errors + the frame's setup on the
// table) leaves in the centres?
//
// Baseline: the eight location errors and the frame's setup (translation, rotation; or, when the
// frame self-calibrates, nominal_from=initial, every sphere's offset). Candidate cause
// `linear_axis_scale` (variant xyz): the scale errors s_x, s_y, s_z of the linear axes (actual =
// read (1 + s); self-calibration: s_x, s_y relative to s_z). Both fits are weighted by each
// centre's covariance from its sphere fit, sigma^2 C_i / runs, so the whitened residual is
// chi-square with m - rank dof when the model is complete. The cause is reported only when
// (a) the baseline's whitened residual fails that chi-square test at alpha, sigma = max(probe
// repeatability, the sphere fits' pooled touch noise, which no machine model can change), and
// (b) the extended model predicts held-out orientations (leave one orientation out; theta and
// theta + 360 are one orientation) better by at least max(2 %, 2 standard errors of the held-out
// rms).
#include <string>
#include <vector>

#include "core/diagnosis.hpp"
#include "cycles/spaceframe/analyze.hpp"

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

struct SpaceframeDiagnosis {
  double sigma_um = 0.0;            // touch noise used by the chi-square test
  double fit_noise_um = 0.0;        // the sphere fits' pooled touch noise
  int centres = 0;
  int holdout_groups = 0;
  int holdout_coordinates = 0;
  SpaceframeFit baseline;
  double baseline_p_value = 1.0;    // chi-square test of the baseline against sigma
  double baseline_holdout_rms_um = 0.0;
  SpaceframeFit candidate;          // baseline + linear_axis_scale, always fitted
  double candidate_holdout_rms_um = 0.0;
  double needed_gain = 0.0;         // fraction
  std::vector<CandidateScore> candidates;
  bool found = false;
  double gain_pct = 0.0;            // held-out rms, baseline -> extended
};

SpaceframeDiagnosis diagnoseSpaceframe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                       const DiagnosisOptions& options);

Json spaceframeDiagnosisJson(const SpaceframeDiagnosis& d, const ProbePlan& plan);
std::string spaceframeDiagnosisText(const SpaceframeDiagnosis& d);

}  // namespace rotacal
