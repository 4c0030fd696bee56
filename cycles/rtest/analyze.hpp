#pragma once
// Identification of the R-test cycle: the linearised least squares of 002 Eq. (6) for the six
// position-dependent errors of 002 Table 2 at every tilt angle of the plan, from each measuring
// cycle, and their change with time across cycles (002 Fig. 10).
//
// Conventions (docs/rtest.md):
//  - Eq. (4): the sensors are zeroed once, at tilt 0, C 0, before the first cycle. In the first
//    cycle the reference reading is wq(0,0) of that same cycle and Eq. (6) applies as written;
//    later cycles read against the reference of the first cycle, so the first cycle's estimate
//    enters their model (and their uncertainty).
//  - Tool length (002 Sec. 4.3): at tilt 0 a Z shift of the table is along the C axis and moves
//    the sphere the same at every C, which the reset cancels: dz (dz_BY, dz_AY) at tilt 0 is not
//    observable in the first cycle and is fixed to 0 there. A tool-length error (or that Z shift)
//    is indistinguishable from it and appears in the translations at the other tilts as a fixed
//    pattern; changes with time are free of it. Likewise c (c_BY, c_AY) at tilt 0, a rotation
//    about the C axis, is the C zero that the reset at C = 0 defines: fixed to 0 in the first
//    cycle, and a value c0 there shifts the rotations at the other tilts by -c0 about their C axis.
#include <Eigen/Core>
#include <Eigen/SVD>
#include <cstdint>
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "core/json_io.hpp"
#include "core/outliers.hpp"
#include "core/probe_plan.hpp"
#include "core/uncertainty_budget.hpp"
#include "cycles/rtest/plan.hpp"

namespace rotacal {

/// J_wq_w: derivative of the sphere centre in the workpiece frame (mm) with respect to the six
/// errors of the pose's tilt (mm, rad), exact at zero error: wq = T_m_w^-1 rq with rq fixed.
Eigen::Matrix<double, 3, kRtestParams> J_wq_omega(Kinematics kinematics, const Pose& pose, const Eigen::Vector3d& nest_w);

/// The plan's sensor noise (`sensor_noise_um`, default 002's 0.2 um), um.
double rtestSensorNoiseUm(const ProbePlan& plan);

/// What one reading scatters by, as declared: the sensors (the plan's `sensor_noise_um`) and the
/// sphere's form at the contact (`rtest_sphere_form` of the contributors, per reading, Type A:
/// the same per-reading part the uncertainty budget reads), added in quadrature, white. Every
/// test of the readings against the declared noise (the screen, the judge of diagnose) reads it.
///
/// And the structured part: what the declared contributors that act on every reading of the
/// machine alike move one cycle's readings by, to first order (rtestStructuredUm2), the model the
/// budget draws (drawRtest). The same machine in every cycle: cycles share it. `about`: the
/// readings the sensors' gain and cross-talk are taken about (one cycle of the plan, e.g. the
/// first); null: the nominal machine, where they move nothing to first order.
DeclaredNoise rtestDeclaredNoise(const ProbePlan& plan, const ContributorSet* declared, const RtestCycle* about = nullptr);

/// The structured part (um^2), rows 3 x (plan point index) + axis (x, y, z), of one cycle read
/// against the sensors' zero at the reset pose: the sphere offset s reads (R_i^T - R_ref^T) s;
/// the drift within the cycle R_i^T v t_i less the zero's; the linear axes their error at the
/// commanded centre (probeAxesCovariance) read the same way; the sensors' response S reads
/// dS x (the reading), each entry independent (gain on the diagonal, cross-talk off it).
Eigen::MatrixXd rtestStructuredUm2(const ProbePlan& plan, const ContributorSet& declared, const RtestCycle* about);
/// Draws of the same (um): 3 x (plan points) x draws, the Gaussian parts by the root of their
/// covariance, the linear axes by probeAxesDraws (each draw its own node spacing). What the tests
/// whose tails matter (the screen's threshold) read instead of a normal of the covariance.
Eigen::MatrixXd rtestStructuredDrawsUm(const ProbePlan& plan, const ContributorSet& declared, const RtestCycle* about,
                                       int draws, std::uint64_t seed);
/// rtestDeclaredNoise's draws of the declared machine and their seed (fixed: the same data give
/// the same threshold on every run).
constexpr int kRtestNullDraws = 2000;
constexpr std::uint64_t kRtestNullSeed = 0x72746573;

struct RtestFitOptions {
  double sensor_sigma_um = 0.2;  // the sensors' repeatability: a floor for the noise estimate
  double reset_alpha = 0.01;     // false-alarm rate of the re-read check over the whole series
  /// The declared scatter of one reading (sensors and sphere form, rtestDeclaredNoise), um; 0: the
  /// sensors alone. The screen of gross readings tests against it.
  double reading_sigma_um = 0.0;
  std::string declaration;       // what reading_sigma_um is, for the report
  /// The declared structured part of one cycle (rtestDeclaredNoise), shared by every cycle; the
  /// screen whitens by it beside reading_sigma_um. Empty: none.
  Eigen::MatrixXd structured_um2;
  /// Draws of that part (DeclaredNoise::structured_draws_um): the screen's threshold reads its
  /// tails from them (core/outliers.hpp). Empty: the Gaussian bound.
  Eigen::MatrixXd structured_draws_um;
  /// false: no screen of gross readings (the budget's Monte Carlo and its derivatives propagate
  /// noise-free simulated readings through the fixed estimator; a screen there would only cost time).
  bool screen = true;
  double screenSigmaUm() const { return reading_sigma_um > 0 ? reading_sigma_um : sensor_sigma_um; }
  bool validate(std::string* why) const;  // false, and why naming the field, when out of range
};

/// One cycle's estimate. value/u: 6 x (tilts), mm or rad, order of rtestParameterIndices.
struct RtestCycleFit {
  double t_s = 0.0;
  Eigen::MatrixXd value;
  Eigen::MatrixXd u;
  Eigen::MatrixXd cov;              // 6 N x 6 N, column 6 i + p
  double residual_rms_um = 0.0;     // readings minus the linear model
  double linearisation_um = 0.0;    // max |exact model - linear model| at the estimate
  double sigma_um = 0.0;            // noise used for u: max(sensor_sigma, residual estimate)
  double residual_sd_um = 0.0;      // residual standard deviation (divisor: dof)
  int dof = 0;
  bool dz_reference_fixed = false;  // referred to its own reset (first cycle, or every cycle with reset reads): dz and c at tilt 0 fixed to 0
  bool own_reset = false;           // the cycle's readings are referred to its own reset reading
  // The re-read check: the reset pose read again at the end of the cycle against its reading
  // before the first pose; chi2 = |d|^2 / (2 sigma^2) with the declared sensor noise, 3 dof.
  bool reset_checked = false;
  Eigen::Vector3d reread_minus_reset_mm = Eigen::Vector3d::Zero();
  double reset_chi2 = 0.0, reset_p = 1.0;
  bool sensor_step = false;  // reset_p below reset_alpha / (cycles checked)
  std::vector<Eigen::Vector3d> residual_w_mm;  // per reading
};

/// J_wq_e: the same for the eight ISO 230-7 location errors of both axes (locationParameters:
/// B/C X0B Y0C Z0B A0B B0B C0B, A0C-A0B, X0C-X0B), constant over the tilt.
Eigen::Matrix<double, 3, kNumLocationErrors> J_wq_e(Kinematics kinematics, const Pose& pose, const Eigen::Vector3d& nest_w);

/// The location errors of both axes separated: 002 Eq. (6) with omega_0 = the eight
/// constant location errors, fitted to the first cycle's readings. The per-tilt errors are what
/// the R-test measures; on a B/C table a constant X0C - X0B enters them as dx_BY(B) = (X0C-X0B)
/// cos B and dz_BY(B) = (X0C-X0B) sin B, A0C - A0B as a_BY(B) = (A0C-A0B) cos B and c_BY(B) =
/// (A0C-A0B) sin B (docs/rtest.md), so they are separated where the plan has a tilt besides 0.
/// The lengths are relative to the sphere's actual position (a sphere offset s reads as -s).
struct RtestLocationFit {
  bool identifiable = false;
  std::string why;                       // when not identifiable
  ErrorVector value = ErrorVector::Zero();  // mm / rad, order of locationParameters
  ErrorVector u = ErrorVector::Zero();
  double residual_rms_um = 0.0;  // first cycle's readings minus the eight-error model
  double sigma_um = 0.0;         // noise used for u: max(sensor_sigma, residual estimate)
  double residual_sd_um = 0.0;   // residual standard deviation (divisor: dof)
  int dof = 0;
};

/// The location fit's estimator: the design matrix A (rows: 3 per plan point in plan order, then
/// with `own` the reset and the re-read; columns: the eight location errors of locationParameters,
/// then with `own` the cycle's zero offset) and its least-squares map G (x = G y, mm / rad). The
/// estimator is linear in the readings: G is exact, not a linearisation (the budget's
/// Monte Carlo runs the readings of the exact simulator through G).
struct RtestLocationEstimator {
  bool own = false;
  bool identifiable = false;
  std::string why;
  int zero_rows = 0;  // rows that are 0 = 0 (the reset pose's own without a reset reading)
  Eigen::MatrixXd A, G;
  Eigen::VectorXd scale;  // column scales of the SVD
  Eigen::JacobiSVD<Eigen::MatrixXd> svd;
};
RtestLocationEstimator rtestLocationEstimator(const ProbePlan& plan, bool own);
/// The readings of one cycle as the estimator's rows y (mm).
Eigen::VectorXd rtestLocationRows(const ProbePlan& plan, const RtestCycle& cycle, bool own);

/// The screen of gross readings (a sensor glitch: one value tens of micrometres or millimetres
/// off): every pose reading's value (x, y, z apart) against what the rest of its cycle predicts
/// for it, the deletion residual under the declared per-reading noise (core/declared_noise.hpp),
/// Bonferroni over all the values of the series at kRtestScreenAlpha, worst first and refitted
/// (core/outliers.hpp); a value beyond is left out of every fit (analyze and diagnose) and named.
/// The reset and re-read rows are not screened: a jump between them is the re-read check's
/// (a sensor step, flagged there), which a screen would otherwise take for a glitch.
/// Each cycle is screened against its own fit (its own reset and sensor zero), so neither a drift
/// between cycles nor a step of the counts looks like a glitch.
constexpr double kRtestScreenAlpha = 0.01;       // a clean series loses a value in at most 1 %
constexpr double kRtestScreenMaxFraction = 0.05; // beyond: the model or the noise, not glitches
struct RtestScreen {
  OutlierOptions options;
  OutlierScreen screen;  // run = the cycle (0-based), point_id = 3 x (pose index) + axis
  /// (cycle, row) of the values left out: row = 3 x (plan point index) + axis (x, y, z).
  std::vector<std::pair<int, int>> excluded() const;
};
RtestScreen screenRtestReadings(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, double reading_sigma_um,
                                const std::string& declaration, const Eigen::MatrixXd& structured_um2 = {},
                                const Eigen::MatrixXd& structured_draws_um = {});
/// REPORT.json's `outliers` block of the R-test, and its one line.
Json rtestScreenJson(const ProbePlan& plan, const RtestScreen& s);
std::string rtestScreenText(const ProbePlan& plan, const RtestScreen& s);

struct RtestAnalysis {
  Kinematics kinematics = Kinematics::TableBC;
  RtestScreen screen;         // what was left out of every fit below
  RtestLocationFit location;  // the eight location errors, first cycle
  std::vector<double> tilt_deg;
  std::vector<RtestCycleFit> cycles;
  // Linear trend across cycles (weighted by u): per second, mm/s or rad/s; zero with one cycle.
  Eigen::MatrixXd rate, rate_u;
  Eigen::MatrixXd change;  // last cycle minus first, mm or rad
  int reset_checks = 0;         // cycles whose re-read was checked
  double reset_level = 0.0;     // the per-cycle level of the check: reset_alpha / reset_checks
};

RtestAnalysis analyzeRtest(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestFitOptions& options);

/// REPORT.json of the R-test (contract, extended): per cycle estimates, drift, figures.
Json rtestReportJson(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestAnalysis& analysis,
                     const std::vector<std::string>& result_files);
/// What REPORT.json's u holds (u_c), for the text to print the same numbers: the location errors'
/// budget, the first cycle's per-tilt u_c and u_B (6 x tilts, report units; a later cycle's u_c
/// is its own fit's u with the first cycle's u_B), the drift rates' u_c (per hour). Left empty,
/// the text prints the fit's own u and says so.
struct RtestSignedU {
  const UncertaintyBudget* location = nullptr;
  Eigen::MatrixXd tilt_u_c, tilt_u_b;
  Eigen::MatrixXd drift_u_c;
};
std::string rtestReportText(const ProbePlan& plan, const RtestAnalysis& analysis, const RtestSignedU& signed_u = {});

}  // namespace rotacal
