#pragma once
// Analysis of the three-sphere cycle (001 Sec. 3-5), in two stages.
//
// Stage 1, sphere centres: the five ball centres at trigger of one sphere at one angle lie
// exactly at rho = R + r from the true sphere centre (ball-on-sphere contact), so a least-squares
// sphere through them (Gauss-Newton on |c_j - x| - rho, 4 unknowns, 1 redundancy) gives the
// centre x in the machine frame. The fitted radius rho - r is compared with the nominal R as a
// plausibility test (a chip, coolant or a wrong radius in the plan): beyond
// `radius_tolerance_um` the analysis refuses. A uniform probe pretravel or ball-size error moves
// all five touches along their normals alike and is absorbed by rho, not by the centre.
//
// Stage 2, the C axis (001 Table 1, tilt axis at 0): the sphere centre i at angle C is
//   p_i(C) = T_L  T_E(C)  Dc(-C)  s_i
//   T_L    = Dx(Oxc) Dy(Oyc) Da(Sxc) Db(Syc)                     4 location errors (X0C Y0C A0C B0C)
//   T_E(C) = Dx(EXC) Dy(EYC) Dz(EZC) Da(EAC) Db(EBC) Dc(ECC)     6 component errors, functions of C
// with s_i the spheres' true centres on the table (9 nuisance parameters). All transforms exact;
// Gauss-Newton with a finite-difference Jacobian of this exact model, weighted by each centre's
// covariance from stage 1.
//
// What the data cannot separate, and the convention that settles it (documented in
// docs/spheres3.md): the mean of each component error over the turn is a location error (XY
// offsets and tilts) or a sphere position (EZC, ECC); a component error that turns with the
// table (first harmonic rotating at -C, e.g. EXC = g cos C, EYC = -g sin C) is a sphere
// position. So the component errors are Fourier series over the N sampled angles without their
// mean and without the rotating first harmonic:
//   (EXC, EYC) and (EAC, EBC): counter-rotating first harmonic (cos C, sin C), (-sin C, cos C),
//                              and cos kC, sin kC for 2 <= k < N/2 (and cos(N/2)C) per component
//   EZC, ECC:                  cos kC, sin kC for 1 <= k < N/2 (and cos(N/2)C)
// That is 6N - 9 terms, + 4 location errors + 9 sphere coordinates = 6N + 3: exactly the rank
// of N rigid table poses plus the 3 inter-sphere distances. The location errors are then the
// axis average line (ISO 230-7) at z = 0 of the machine frame. On an A/C machine at A = 0 they
// are, to first order, Oxc = dx_AY, Oyc = dy_AY + dy_CA, Sxc = a_AY, Syc = b_AY + b_CA
// (000 Eq. (1)); on a B/C machine at B = 0, Oxc = dx_BY + dx_CB, Oyc = dy_CB, Sxc = a_BY + a_CB,
// Syc = b_BY (002 Eq. (2)-(3)).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "core/geometric_errors.hpp"
#include "core/json_io.hpp"
#include "core/measurement.hpp"
#include "core/outliers.hpp"
#include "core/probe_plan.hpp"
#include "core/sphere_centre_fit.hpp"
#include "core/uncertainty_budget.hpp"

namespace rotacal {

// Stage 1 is core/sphere_centre_fit.hpp (fitSphereCentre, the radius fitted).

// ---- Stage 2 ------------------------------------------------------------------------------

// The six component errors of the C axis in ISO 230-7 order, lengths mm, angles rad:
// ComponentVector of core/geometric_errors.hpp.
const std::array<const char*, kNumComponentErrors>& componentNames();  // EXC EYC EZC EAC EBC ECC
const std::array<const char*, 4>& spheres3LocationNames();              // Oxc Oyc Sxc Syc
const std::array<const char*, 4>& spheres3LocationIso();                // X0C Y0C A0C B0C

/// Which component-error terms the model carries.
enum class ComponentModel {
  None,               // location errors only (the diagnosis baseline)
  SecondOrderRadial,  // EXC, EYC: cos 2C and sin 2C (rotary_error_motion)
  Full                // every identifiable harmonic (the analysis model)
};

/// One basis function of the component errors: a 6-vector function of C.
struct ComponentTerm {
  enum class Kind { Cos, Sin, CounterCos, CounterSin } kind;
  int component;  // 0..5; for Counter*: the first of the pair (0: EXC/EYC, 3: EAC/EBC)
  int k;          // harmonic order
  std::string name() const;  // e.g. "EXC_cos2C", "EXC+EYC_counter1_cos"
  ComponentVector value(double c_rad) const;
};
std::vector<ComponentTerm> componentTerms(ComponentModel model, int n_angles);

struct Spheres3Options {
  ComponentModel model = ComponentModel::Full;
  double prior_sigma_um = 0.7;        // probe repeatability along the normal, k = 1 (MACHINE.json)
  double radius_tolerance_um = 10.0;  // stage 1 plausibility limit on |fitted R - nominal R|
  int max_iterations = 20;
  double step_tolerance_mm = 1e-9;    // largest position change of a step (1e-6 um)
  int hold_out_angle = -1;            // index of an angle left out of the fit (predicted only)
  /// Touches left out of their sphere's fit (the outlier screen's): the sphere's centre and
  /// radius from the others. Where the others do not fix the whole centre (the top touch left
  /// out: the four side touches fix x, y and the radius, not the height; a pair of opposite side
  /// touches left out: nothing fixes the centre along their line), the sphere gives stage 2 the
  /// coordinates they fix and no weight along the rest (Spheres3Observation::measured). Fewer than
  /// two coordinates fixed is refused.
  std::function<bool(int run, const ProbePoint& point)> hold_out_touch;

  bool validate(std::string* why) const;
};

struct Spheres3Observation {
  int run = 0;
  int angle = 0;   // index into c_deg
  int sphere = 0;  // 0..2
  SphereFit fit;
  std::vector<int> point_ids;       // the touches fitted (all the plan's but those held out)
  std::vector<int> held_point_ids;  // Spheres3Options::hold_out_touch's
  Eigen::Vector3d residual_mm = Eigen::Vector3d::Zero();  // measured centre - model
  bool held_out = false;
  /// How many coordinates of the centre the fitted touches fix (3 unless touches were held out),
  /// and the projector onto those they do not fix: there fit.centre_mm is the stage-2 model's own
  /// prediction (the touches' distances do not depend on it to first order), and stage 2 gives
  /// it no weight.
  int measured = 3;
  Eigen::Matrix3d unmeasured = Eigen::Matrix3d::Zero();
  /// The centre's information per unit touch variance (inverse of fit.cov_centre_per_sigma2 when
  /// all three are fixed; of rank `measured` otherwise): what stage 2 weighs the centre by.
  Eigen::Matrix3d information_per_sigma2 = Eigen::Matrix3d::Zero();
};

/// A fitted sphere's touches fix a direction of its centre when the centre's information (the
/// touches' normals, the radius eliminated) along it is at least this many squared direction
/// cosines. A side pair fixes its line with 2, a top touch the height with 0.8 (5 touches) or
/// 0.67 (3); a direction no touch faces has only the second-order geometry of the touches not
/// lying exactly at the equator (about 1e-5): fixed by the layout, never by the data.
inline constexpr double kSpheres3MeasuredFloor = 0.1;

struct Spheres3Result {
  ComponentModel model = ComponentModel::Full;
  std::vector<double> c_deg;
  std::array<Eigen::Vector3d, 3> nominal_w_mm;
  double nominal_radius_mm = 0.0;
  std::vector<Spheres3Observation> observations;

  Eigen::Vector4d location = Eigen::Vector4d::Zero();  // Oxc Oyc (mm), Sxc Syc (rad)
  Eigen::Vector4d location_u = Eigen::Vector4d::Zero();
  std::array<Eigen::Vector3d, 3> sphere_w_mm;          // fitted true sphere centres, table frame
  std::vector<ComponentTerm> terms;
  Eigen::VectorXd h, h_u;                              // term coefficients (mm or rad)
  Eigen::MatrixXd covariance;                          // of [location, spheres, h]
  /// Component errors at each sampled angle (rows) and their standard uncertainty.
  Eigen::Matrix<double, Eigen::Dynamic, kNumComponentErrors> values, values_u;

  /// Volumetric error |measured centre - ideal| per angle (rows) and sphere (columns), um, first
  /// run: before (ideal = perfect machine: Dc(-C) s_i), after compensating the location errors
  /// only, and after compensating location and component errors (the fit's residual).
  Eigen::MatrixXd volumetric_before_um, volumetric_after_location_um, volumetric_after_um;

  double sigma_touch_um = 0.0;  // stage 1 a-posteriori touch noise, sqrt(RSS / dof)
  double sigma_used_um = 0.0;   // max(prior, stage 1): scales the uncertainties
  double residual_rms_um = 0.0; // stage 2 centre residual, rms per coordinate, fitted data
  double chi2 = 0.0;            // stage 2 whitened RSS / sigma_used^2
  int dof = 0;
  double holdout_rms_um = 0.0;  // held-out centres' prediction error, rms per coordinate
  int iterations = 0;
  double last_step_mm = 0.0;    // position change of the last Gauss-Newton step (convergence)
  int rank = 0, parameters = 0;
  double condition = 0.0;
  int points_used = 0;
  double max_radius_dev_um = 0.0;

  /// Component errors at any C (deg), from the fitted series.
  ComponentVector componentAt(double c_deg) const;
};

/// Identifies the spheres3 model from one or more runs of a spheres3 plan. Throws
/// std::invalid_argument naming the sphere, angle and points when the data are unusable
/// (missing triggers, a sphere fit beyond the radius tolerance, a rank-deficient model).
Spheres3Result identifySpheres3(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                const Spheres3Options& options);

/// The declaration the cycle's tests read (core/declared_noise.hpp), per plan point (plan order),
/// as the triggers' displacements along their approaches (um): white, the per-touch
/// contributors (perTouchDeclaration); structured, the probe's pretravel by direction and the
/// linear axes (probeAxesCovariance at the nominal triggers); none beyond the white part when
/// `declared` is null. `nu` = n . u per plan point (n the nominal contact normal): a touch's
/// residual |t - c| - rho moves by nu ds. Throws std::invalid_argument when the two
/// repeatabilities contradict each other.
struct Spheres3Noise {
  DeclaredNoise trigger;
  Eigen::VectorXd nu;
  std::vector<Eigen::Vector3d> approach;  // per plan point (unit)
  std::map<int, int> index_of_id;         // plan point id -> plan index
};
Spheres3Noise spheres3DeclaredNoise(const ProbePlan& plan, const ContributorSet* declared);

/// The identification seen touch by touch, what the outlier screen and the whitened adequacy
/// test read: each fitted touch's residual against its sphere as the stage-2 model places it,
/// |t_j - c_model| - rho (um, rho its sphere's stage-1 radius averaged over the angles), in
/// observation order; J the span of the full model linearised there: per C angle a rigid motion
/// of the table (3 translations, 3 rotations), the three spheres' positions on the table, and one
/// radius per sphere and run (the same sphere and ball at every angle; the
/// full component model has exactly the rank of N rigid poses plus the inter-sphere distances,
/// so the two spans agree); the declared covariance of the residuals (um^2).
struct Spheres3TouchProblem {
  Eigen::VectorXd residual_um;
  Eigen::MatrixXd J;
  /// The full model leaves no redundancy on some touches (the top touch alone sets its sphere's
  /// height at its angle, and the table's height and tilt at each angle take any three heights):
  /// a chip there goes wholly into the component errors. Those touches are tested against the
  /// smooth model instead: the location errors, the spheres' positions, the component errors up to
  /// the diagnosis's max_harmonic (an oval or trefoil bearing, a wobble) and the spheres' radii.
  Eigen::MatrixXd J_smooth;
  /// Each touch's residual against a member of the smooth model (the identified location errors
  /// and spheres, no component error; the sphere's mean stage-1 radius), um: what J_smooth's test reads.
  Eigen::VectorXd residual_smooth_um;
  /// Per row: the share of the touch's whitened weight the full model leaves (P_ii / (S^-1)_ii);
  /// below kSpheres3FullShareFloor the touch is screened against J_smooth.
  Eigen::VectorXd full_share;
  Eigen::MatrixXd covariance_um2;
  std::vector<std::pair<int, int>> touches;  // (run, point id) per row
  std::vector<std::pair<int, int>> readings; // (run, plan index) per row: the declaration's keys
  Eigen::VectorXd nu;                        // n . u per row: a trigger's displacement as the touch reads it
  std::vector<std::pair<std::pair<int, int>, double>> held;  // (run, point id) and residual (um)
};
Spheres3TouchProblem spheres3TouchProblem(const std::vector<MeasurementRun>& runs, const Spheres3Result& r,
                                          const Spheres3Noise& noise);

/// The outlier screen (core/outliers.hpp) on every touch: each fitted touch's GLS deletion
/// residual in spheres3TouchProblem, worst first, the model refitted without it. The screen's
/// fits take no radius refusal (a chip is what makes a radius wrong); the caller's final fit
/// with the excluded touches held out keeps it.
/// A touch whose share of weight left by the full model is below this is tested against the
/// smooth model. On the bundled plan the full model leaves each top touch 2-3 % of its weight
/// (only the declared shared linear-axis errors tie it to the others), so a 20 um chip there
/// moves its statistic by about 1; the side touches keep 10-50 %. Fixed by the plan and the
/// declaration, never by the data, so each statistic stays N(0, 1) under its own model.
inline constexpr double kSpheres3FullShareFloor = 0.1;

/// The screen's statistic for each row of a touch problem: the GLS deletion residual under the
/// full model, or under the smooth one where the full model leaves the touch no redundancy.
Eigen::VectorXd spheres3OutlierStatistic(const Spheres3TouchProblem& p);
/// What a gross error of 1 um at each row moves that row's statistic by (deletionSensitivity under
/// the same model the statistic reads): the screen's reach.
Eigen::VectorXd spheres3OutlierSensitivity(const Spheres3TouchProblem& p);
/// The same statistic of each column of `readings_um` (draws of the declared noise as the touches
/// read it) in place of the residual: the screen's null.
Eigen::MatrixXd spheres3OutlierStatisticColumns(const Spheres3TouchProblem& p, const Eigen::MatrixXd& readings_um);

/// Touches of one sphere at one angle of which the data say one hit a chip but not which: each
/// one's deletion alone makes the data consistent with the declaration (the screen's test at its
/// level, no touch beyond its threshold). Two opposite side touches are the usual pair: a chip on
/// either makes the sphere look narrower along their line by the same amount; only where its
/// centre then sits tells them apart, and the other two spheres at that angle may not see that
/// shift beyond the noise. All are left out, the sphere's centre along their line not measured
/// at that angle (or, where all cannot be, the screen's own pick: `left_out`).
struct Spheres3Ambiguity {
  int run = 0;
  int sphere = 0;  // 1..3
  double c_deg = 0.0;
  std::vector<int> point_ids;
  /// Empty: all of point_ids are left out. Else all cannot be (the sphere would fix fewer than
  /// two coordinates of its centre there) and these, the screen's own pick, are.
  std::vector<int> left_out;
  std::string text() const;
};

struct Spheres3Screen {
  OutlierOptions options;
  /// The touches left out: the screen's own (worst first), then per sphere and angle with a touch
  /// left out the touches whose deletion alone makes the data consistent (the chip's confidence
  /// set at the screen's level): one, and that one is the chip; several, and all are left out
  /// (`ambiguous`), or the screen's pick where all cannot be.
  OutlierScreen screen;
  std::vector<Spheres3Ambiguity> ambiguous;
  /// Why the data cannot be analysed with these touches left out (empty: they can): the
  /// touches left out leave a sphere at an angle fixing fewer than two coordinates of its centre,
  /// and without that sphere the table's pose at that angle is not fixed.
  std::string refused;
  /// Touches beyond the threshold in the screen's last fit that it could not leave out (the fit
  /// cannot do without them): analyze refuses such data, naming them (keptBeyondText).
  std::vector<ExcludedTouch> kept_beyond;
  std::string keptBeyondText() const;
};
Spheres3Screen screenSpheres3Touches(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const Spheres3Noise& noise, const Spheres3Options& options);

/// The table pose of the stage-2 model at a paper-convention C (rad): T_L T_E(C) Dc(-C).
Eigen::Isometry3d spheres3Table_m_w(const Eigen::Vector4d& location, const ComponentVector& component, double c_rad);

/// REPORT.json for a spheres3 analysis (contract + component errors, volumetric errors, figures).
Json spheres3ReportJson(const ProbePlan& plan, const Spheres3Result& r, const std::vector<std::string>& result_files);
/// `location` (the location errors' budget: its u_c, what REPORT.json's u is) when given: the
/// headline's +- is u_c; else the fit's own u.
std::string spheres3Text(const Spheres3Result& r, const UncertaintyBudget* location = nullptr);

}  // namespace rotacal
