#pragma once
// The one-sphere cycle (the KinematicsOpt / CYCLE996 / AxiSet class): one calibration
// sphere on the table, on a stem, touched at every pose of a grid of the tilt axis (A or B) and
// C. At each pose the ball comes from above (the top) and from the sides of the four horizontal
// directions whose contact lies on the sphere's half away from the stem (contact normal n with
// n . s <= 0, s the stem's direction from the centre in the pose): the stylus never reaches round
// to the stem side, and the ball's vertical way down to a side touch, its approach and its
// stylus stay on that half as long as the tilt keeps the table below the sphere (|tilt| <= 90 deg).
//
// It runs on the tilting-table machines (table_ac, table_bc, and table_ab, whose grid is B x A:
// an A table on a B axis, both tilting the sphere, each within 60 deg by default), on a B or A head over a C table
// (head_table), on an A head carrying a B head over a fixed table (head_ab, whose grid is A x B:
// the sphere stays, the probe turns round it) and on a C head carrying a B head over a fixed table
// (head_cb, LinuxCNC's 5axiskins bridge mill: grid B x C, the B head tilting the spindle and the C
// head turning the tilt round the sphere). On a head machine X Y Z read the head's pivot: every
// planned position is the reading at which the ball, L along the tilted spindle, is where the
// touch needs it; a side touch whose contact lies on the sphere's half away from the stylus
// (n . d < 0, d the stylus's direction) is left out, as the stem's side is, so that the stylus
// never reaches round the sphere.
#include <Eigen/Core>
#include <vector>

#include "core/kinematic_model.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// The papers' parameters of a tilting table (000 Eq. (1) for A/C, 002 Eq. (2) for B/C) and the
/// ISO 230-7 parameter of the model each one is, to first order (exactly where the factor orders
/// coincide: tests/core/kinematic_model_test.cpp).
const std::vector<std::pair<const char*, const char*>>& spherePapersNames(Kinematics k);

struct SphereLayout {
  Eigen::Vector3d center_w_mm = Eigen::Vector3d(120.0, 0.0, 80.0);  // on the table, workpiece frame
  double radius_mm = 12.7;          // a 25.4 mm calibration sphere (Heidenhain KKH, Renishaw)
  double stem_length_mm = 60.0;     // sphere centre to the table, along the table's -Z
  double stem_diameter_mm = 8.0;
  std::vector<double> tilt_deg;     // the tilt axis (A or B); default: 0 to 90 deg in 30 deg steps, within the stroke
  /// The second axis's angles: the C table's (option c_list), or on head_ab the B head's (b_list,
  /// by default -60 to 60 deg in 30 deg steps, within the stroke).
  std::vector<double> c_deg = {0.0, 90.0, 180.0, 270.0};
  char turn_axis = 'C';
  /// Explicit poses (tilt, C; on head_ab A, B) in deg, in the order run; when set, the grid is not used.
  std::vector<std::pair<double, double>> pose_list;
  /// > 0: a pose design picks this many poses of the grid (D-optimal on the fit's touches,
  /// cycles/one_sphere/design.hpp); the plan then carries them as pose_list. The grid it picks
  /// from is tilt_list x c_list, by default the tilt axis every 15 deg and C every 30 deg.
  int design_poses = 0;
  /// The design's criterion (option `design`): 'D' D-optimal for the probe's repeatability (the
  /// default); 'A' then refines it for the machine's declared contributors, the sum of the
  /// location errors' variances each in its reference uncertainty (core/pose_design.hpp,
  /// refinePosesForBudget).
  char design_criterion = 'D';
  /// Fit the linear axes' squareness S_xy S_xz S_yz alongside (design.hpp says why).
  bool fit_squareness = true;
  /// Measure the rotary axes' lost motion: the poses are run there and back (the list, then
  /// the list reversed without its last pose), so that a pose is reached from both sides by
  /// each axis that moves, and the fit carries each axis's backlash (design.hpp).
  bool backlash = false;

  /// Defaults for a machine, overridden by the options center_w_mm ("x,y,z"), radius_mm,
  /// stem_length_mm, stem_diameter_mm, tilt_list, c_list, pose_list ("tilt/c,tilt/c,..."),
  /// poses (the design's n), design (D or A), fit_squareness, backlash (0 or 1).
  static SphereLayout fromOptions(const MachineModel& machine, const CycleOptions& options);
  CycleOptions toOptions() const;
  /// The option that lists the second axis's angles: c_list, b_list on head_ab, a_list on table_ab.
  std::string turnListOption() const { return std::string(1, static_cast<char>(turn_axis - 'A' + 'a')) + "_list"; }
  /// The poses (tilt, C in deg): pose_list, else the grid tilt_list x c_list (a backlash plan
  /// runs them there and back).
  std::vector<std::pair<double, double>> poses() const;
};

/// The tilt axis: 'A' for table_ac and head_ab, 'B' for table_bc, table_ab and head_cb, the head's axis for head_table.
/// Throws std::invalid_argument naming the kinematics when the machine has no touch probe's place
/// (head_ab without its "head").
char sphereTiltAxis(const MachineModel& machine);
/// The pose grid's second axis: C, the B head that the A head carries on head_ab, or the A table
/// that the B axis carries on table_ab.
char sphereTurnAxis(const MachineModel& machine);

/// The exact model the cycle fits on this machine, the sphere at center_w_mm on the table.
KinematicModel sphereModel(const MachineModel& machine, const Eigen::Vector3d& center_w_mm);

/// How many directions of the fit no set of sphere poses shows (closed form in
/// tests/core/kinematic_model_test.cpp): 2 on a tilting table, 5 with a head, and on head_table one
/// more when the squareness is fitted: the table never tilts the sphere, so its height stays and
/// the shear across the head's axis (S_yz under a B head, S_xz under an A head) reads as the C
/// axis's place plus the head axis's tilt times L cos(tilt). head_ab's two head axes swing the
/// reading over a sphere of radius L round the ball, which shows all three shears: 5 either way;
/// so do head_cb's (its five: the head's place X0C Y0C Z0B as the sphere's, B0B as dX_T, C0C as
/// the B axis's tilt about Z C0B).
int sphereUnseenByAnyPlan(const KinematicModel& m, bool squareness);

/// The four horizontal approach directions the side touches take, and the top's (-Z).
const std::vector<Eigen::Vector3d>& sphereApproaches();

/// Held first where a direction involves them: the C zero (a sphere reads it as its own place on
/// the table, 000's "set-up rotation") and, on a tilting table, the tilt of the C axis about the
/// tilt axis, which the tilt axis's own zero does as well (000 keeps a_AY and drops a_CA). With a
/// head the others are held as core/identifiability.hpp chooses: the head pivot's X0B / Z0B (the
/// frame's origin), the ball's dY_T (Y0C carries it) and dX_T (the head's zero carries it). On
/// head_ab (no table axis) all five are its choice: the head's place X0B Y0A Z0A (the sphere's
/// set-up carries it), dX_T (B0B carries it) and A0B (A0A carries the spindle's tilt about X); on
/// head_cb likewise: X0C Y0C Z0B, dX_T, and C0B (C0C carries the spindle's turn about Z).
std::vector<int> sphereHeldFirst(const KinematicModel& m);

ProbePlan makeSpherePlan(const MachineModel& machine, const CycleOptions& options);

/// The plan's layout read back (the options a PLAN.json carries). Throws std::invalid_argument.
SphereLayout sphereLayoutOf(const ProbePlan& plan);

/// What a PLAN.json of this cycle must satisfy beyond the format (the cycle's identity).
PlanRules spherePlanRules();

}  // namespace rotacal
