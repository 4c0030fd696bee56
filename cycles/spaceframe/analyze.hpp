#pragma once
// The space-frame cycle (003): the 7-sphere frame of 003 Table 1 on the table of a five-axis
// machine, turned by the machine's own rotary axes through 003's rotation/tilt map, each sphere's
// centre found from probe touches; then 003's length errors dL = Lm - Ln for every pair of the
// measured points (003 Eq. (2)-(5)), their check against U = +-(A + K L), and the least-squares
// identification of what explains them (rotary-axis location errors, linear-axis scale errors,
// the frame's setup on the table).
//
// Map onto an A/C tilting table (docs/spaceframe.md): theta -> C, phi -> A, both in the papers'
// convention, so a frame point p_f lands at p_m = D_a(-phi) D_c(-theta) (o_w + p_f): the machine
// turns the frame on the table first and tilts the table after (C rides on A). 003's RotTilt
// applies them the other way round (tilt in the frame, then turn about the fixed Z: a rotary
// table carrying a tilt stage). The count is the same: 45 orientations, 315 points, 49455
// lengths; the nominal lengths are those of the poses the machine takes.
#include <set>
#include <string>
#include <vector>

#include "core/least_squares.hpp"
#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "cycles/spaceframe/frame.hpp"
#include "core/sphere_centre_fit.hpp"
#include "core/uncertainty_budget.hpp"

namespace rotacal {

struct SpaceframeLayout {
  std::vector<double> theta_deg{0, 45, 90, 135, 180, 225, 270, 315, 360};  // 003: 0..360 step 45
  std::vector<double> phi_deg{-90, -45, 0, 45, 90};                         // 003: -90..90 step 45
  Eigen::Vector3d origin_w_mm = Eigen::Vector3d(0, 0, 30);  // frame origin on the table (workpiece frame)
  double sphere_diameter_mm = 19.05;                         // 003: about 19 mm (3/4")
  LengthSpec spec;                                           // A (um), K (um/m)
  double min_touch_angle_deg = 60.0;  // touch normals must point this far from the sphere's stem
  /// Where the nominal points come from: "table1" (the frame's coordinates as calibrated, 003
  /// Table 1) or "initial" (003 Sec. 3.1: the centres this machine measured at theta = phi = 0,
  /// turned by the nominal map: self-calibration; needs the pose theta = phi = 0 in the map).
  std::string nominal_from = "table1";
  /// The frame's calibrated sphere centres (plan option frame_file=FRAME.json at plan time; the
  /// plan then carries them inline as frame_spheres_mm, frame_u_um, frame_source).
  FrameCalibration frame;

  static SpaceframeLayout fromOptions(const CycleOptions& options);
  CycleOptions toOptions() const;
};

ProbePlan makeSpaceframePlan(const MachineModel& machine, const CycleOptions& options);

/// One measured point of the map: a sphere at an orientation (003's points).
struct FramePoint {
  int index = 0;            // 0-based, order of the plan
  std::string pose_name;
  Pose pose;
  int sphere = 0;           // 1..7
  Eigen::Vector3d center_w_mm = Eigen::Vector3d::Zero();  // nominal, workpiece frame
  Eigen::Vector3d nominal_m_mm = Eigen::Vector3d::Zero(); // perfect machine, machine frame
  std::vector<int> point_ids;                              // its touches
};
std::vector<FramePoint> framePoints(const ProbePlan& plan);

/// What the identification may explain dL with: the eight location errors, the three
/// linear-axis scale errors (actual = read (1 + s)), and the frame's rigid setup on the table
/// (translation, and rotation about the frame origin: exact D_a D_b D_c).
struct FrameModel {
  LocationErrors errors;
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();          // s_x, s_y, s_z (dimensionless)
  Eigen::Vector3d setup_translation_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d setup_rotation_rad = Eigen::Vector3d::Zero();
  /// Self-calibration (nominal_from=initial): each sphere's true centre minus Table 1's, frame
  /// coordinates, mm (spheres 1..7). Zero when the frame is taken as calibrated.
  std::array<Eigen::Vector3d, 7> sphere_offset_w_mm = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                      Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                      Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                      Eigen::Vector3d::Zero()};  // Eigen does not zero by itself

  /// Off-diagonal part of the linear axes' map (actual = (diag(1 + scale) + shear) read):
  /// squareness, which only the diagnosis adds (not a fitted parameter of the analysis).
  Eigen::Matrix3d shear = Eigen::Matrix3d::Zero();
  static constexpr int kRigidSize = kNumLocationErrors + 9;  // errors, scale, setup
  static constexpr int kSize = kRigidSize + 21;                // + sphere offsets
  Eigen::Matrix<double, kSize, 1> toVector() const;  // mm, rad, 1
  static FrameModel fromVector(Kinematics k, const Eigen::Matrix<double, kSize, 1>& v);
  /// Report units per entry of toVector() (um, mdeg, um/m, um, mdeg, um per mm / rad / 1): the
  /// identification and the diagnosis take their Jacobians in these.
  static Eigen::Matrix<double, kSize, 1> reportUnits(Kinematics k);
  /// Where the frame's sphere `sphere` (1..7, nominal centre center_w) really sits on the table:
  /// set-up and sphere offset applied, workpiece frame.
  Eigen::Vector3d placedCentre_w(const Eigen::Vector3d& center_w, int sphere, const Eigen::Vector3d& origin_w) const;
  /// Actual centre of a frame point, machine frame (exact HTMs).
  Eigen::Vector3d actualCentre_m(const FramePoint& p, const Eigen::Vector3d& origin_w) const;
  /// What the analysis reports as the centre on such a machine: the sphere fit of the triggers the
  /// plan's touches give (exact ball-on-sphere contact seen through the scaled linear axes). On
  /// an anisotropic scale this is not actual / (1 + s): one-sided touches bias the fit.
  Eigen::Vector3d fittedCentre_m(const ProbePlan& plan, const FramePoint& p, const Eigen::Vector3d& origin_w) const;
  /// The readings this model gives for the point's touches (p.point_ids' order): where the
  /// exact ball meets the model's sphere (nominal R + r) through the linear axes' map, as the
  /// distance (mm) along each touch's approach from its nominal trigger (trigger_m_mm).
  std::vector<double> readingsAlong(const ProbePlan& plan, const FramePoint& p, const Eigen::Vector3d& origin_w) const;
};

/// d(fitted centre)/d(parameter) at `model` for the `active` entries of FrameModel::toVector(),
/// in mm per report unit (3 rows per point): central differences of the readings with steps of
/// `step` report units, carried to the centre by the sphere fit's linear map at the model's
/// triggers. The least squares' Jacobian, and its map for the uncertainty budget.
Eigen::MatrixXd frameJacobian(const ProbePlan& plan, const std::vector<FramePoint>& points, const Eigen::Vector3d& origin_w,
                              const FrameModel& model, const std::vector<int>& active, double step);

struct SpaceframeOptions {
  double finite_step_scale = 1e-3;   // Jacobian steps: 1e-3 um / mdeg / um/m / ...
  int max_iterations = 20;
  double rank_tolerance = 1e-10;     // singular values below this x largest are dropped
  /// Touches (plan point ids) left out of every run (the outlier screen's): a touch left out in
  /// one repeat is left out of all, so that every repeat fits its sphere from the same touches
  /// and the model predicts one centre for them. A sphere whose touches left fix no centre and
  /// radius at a pose (fewer than 4, or the 4 on its equator) leaves the fit there.
  std::set<int> held_out_ids;
  bool validate(std::string* why) const;  // false, and why naming the field, when out of range
};

/// Which parameters the least squares fits. Calibrated frame (nominal_from=table1): location
/// errors, scale X/Y/Z, setup. Self-calibration (nominal_from=initial): location errors, scale
/// X and Y relative to Z, and every sphere's offset (which hold the setup): an isotropic scale
/// of the machine and the frame's size are the same thing to the data, so Z is the reference.
std::vector<int> activeParameters(bool frame_free);

struct SpaceframeAnalysis {
  std::vector<FramePoint> points;
  std::vector<SphereFit> fits;                 // per point (repeats: the mean centre)
  std::vector<Eigen::Vector3d> measured_m_mm;  // fitted centres
  std::vector<Eigen::Vector3d> nominal_m_mm;   // the L_n points (table1 or initial, see layout)
  std::vector<LengthError> lengths;            // 003 Eq. (2)-(4)
  LengthSpec spec;
  LengthVerdict verdict;
  double length_sigma_um = 0.0;                // per-touch scatter behind u(dL): declared, or the fits' when larger
  FrameModel model;                            // identified
  Eigen::Matrix<double, FrameModel::kSize, 1> u = Eigen::Matrix<double, FrameModel::kSize, 1>::Zero();  // k = 1, mm / rad / 1
  FitSummary summary;  // observations: 3 per centre; sigma_um per centre coordinate
  double dL_rms_um = 0.0;                      // before: the measured dL
  double dL_unexplained_rms_um = 0.0;          // dL minus the dL the identified model predicts
  int triggers = 0;
  int runs = 0;                                // repeats averaged per centre
  std::vector<int> held_out_ids;               // touches left out (SpaceframeOptions::held_out_ids)
  /// Centres left out because a touch of theirs was and the rest fix no centre and radius (fewer
  /// than 4, or 4 on the equator): "pose t45p-90 sphere 3 (points 101, 102, 103, 104)".
  std::vector<std::string> points_left_out;
  /// Plausibility of the sphere fits: fitted radius - nominal radius. A pretravel or a wrong
  /// ball diameter shows as every sphere smaller or larger; a dirty sphere or a bad touch as one.
  double radius_limit_um = 0.0;       // max(2 um, 6 x probe repeatability): far beyond the fits' noise
  double radius_max_dev_um = 0.0;     // largest |fitted - nominal|
  double radius_mean_dev_um = 0.0;    // mean of fitted - nominal
  int radius_outside = 0;             // fits beyond the limit
};

/// Fits every sphere, forms the lengths, checks them and identifies the model. Throws
/// std::invalid_argument (naming the point) when a results run lacks a touch of the plan.
SpaceframeAnalysis analyzeSpaceframe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const SpaceframeOptions& options = {});

Json spaceframeReportJson(const SpaceframeAnalysis& a, const ProbePlan& plan, const std::vector<std::string>& files);
/// `budget` (its u_c, what REPORT.json's u is) when given: the identification's +- is u_c; else
/// the fit's own u.
std::string spaceframeText(const SpaceframeAnalysis& a, const ProbePlan& plan, const UncertaintyBudget* budget = nullptr);

}  // namespace rotacal
