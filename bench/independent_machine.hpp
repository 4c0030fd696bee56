#pragma once
// A second machine generator for the acceptance benches, written from 000 (Ibaraki, Iritani,
// Matsushita) and the contributors file alone, so that the estimator under test and the machines
// it is tested on share no code. It uses rotacal's data types (the plan, the machine, the
// contributors file, the names of the location errors) but none of rotacal's simulation, truth,
// contributor-draw, linear-axis or budget code: the A/C table's homogeneous transforms of 000
// Eq. (1), the square column's faces, the ball-plane contact and the linear axes of 000
// Eq. (22)-(23) are all written again here.
//
// One machine of A/C tilting-table kind (000 Fig. 1) with a square-column test piece (or the
// calibration sphere of a sphere cycle's plan):
//   - the 8 location errors of 000 Table 1, drawn normally around 000 Table 4's means;
//   - the piece's set-up: a rigid rotation about the nominal top centre (about X, then Y, then
//     Z, exact) then a translation, drawn from setup_orientation / setup_position;
//   - the piece's form (form_error, not in 000): per face an offset along its outward normal and
//     two tilts of the normal about the face's in-plane axes, pivoting at the face's centre;
//   - the linear axes of 000 Eq. (22)-(23): per axis a scale E_aa,lin q, random values at nodes
//     Q_i = p i (p uniform in the file's node spacing, i integer; node values normal with the
//     declared u, one set per error direction, the three directions sharing the axis's nodes),
//     linearly interpolated, and the squareness S_xy y, S_xz z, S_yz z in X, X and Y. The error
//     is "actual ball centre minus the position the controller reads", evaluated at the read
//     position (000: "positioning error ... at the nominal position");
//   - pretravel per probing direction (+X -X +Y -Y +Z -Z of the machine), along the approach,
//     an oblique approach weighing each axis by its squared direction cosine;
//   - per touch: the probe's unidirectional repeatability along the approach and the surface
//     roughness (the height of the surface under the ball along its normal);
//   - optionally a chip under one touch: the surface raised by c, so the ball triggers early
//     and the touch reads the surface c closer.
// Internal units mm and rad; the contributors file's u are read through core/contributors.hpp,
// which already converts them to mm, mm/mm and rad.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/contributors.hpp"
#include "core/error_model.hpp"
#include "core/machine.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "cycles/tooltip/plan.hpp"

namespace rotacal::independent {

/// The homogeneous transforms of 000 Eq. (1), here as plain 4x4 matrices: translations along and
/// right-handed rotations about the machine's X, Y, Z.
Eigen::Matrix4d Dx(double mm);
Eigen::Matrix4d Dy(double mm);
Eigen::Matrix4d Dz(double mm);
Eigen::Matrix4d Da(double rad);
Eigen::Matrix4d Db(double rad);
Eigen::Matrix4d Dc(double rad);

/// 000 Eq. (1): the workpiece (table) frame in the machine frame at the commanded angles A and C
/// (deg, the papers' sign), with the location errors (mm, rad; order of 000 Table 1 as
/// core/error_model.hpp names them). a_CA and c_CA of Eq. (1) are left at zero: 000 Table 1 has
/// no such parameters (they are the A zero and a set-up rotation).
Eigen::Matrix4d tableTransform(const LocationErrors& errors, double A_deg, double C_deg);

/// The linear-axis errors of one machine (000 Eq. (22)-(23)).
struct LinearAxes {
  /// Per moving axis a (0 X, 1 Y, 2 Z): node spacing p (mm), index of the first node, and the
  /// random values at the nodes per error direction b (mm): value[a][b][i - first[a]] = E_ba,rand(Q_i).
  std::array<double, 3> spacing_mm{20.0, 20.0, 20.0};
  std::array<int, 3> first{0, 0, 0};
  std::array<std::array<std::vector<double>, 3>, 3> node_mm;
  std::array<double, 3> scale{0.0, 0.0, 0.0};  // E_xx,lin E_yy,lin E_zz,lin (mm/mm)
  double S_xy = 0.0, S_xz = 0.0, S_yz = 0.0;    // mm/mm

  /// interpolate(Q_i, E_ba,rand(Q_i), q) of Eq. (22); throws std::out_of_range beyond the nodes.
  double randomPart(int axis, int direction, double q_mm) const;
  /// E_ba(q): the error in direction b of axis a's motion at its read coordinate q (mm).
  double component(int axis, int direction, double q_mm) const;
  /// Actual ball centre minus read position at a read position (machine frame, mm).
  Eigen::Vector3d error(const Eigen::Vector3d& read_m_mm) const;
};

/// Draws one machine's linear axes (000 Eq. (22)-(23), as drawMachine draws them) from its own seed:
/// the nodes cover the machine's strokes with a margin of two spacings.
LinearAxes drawLinearAxes(const ContributorSet& contributors, const MachineModel& machine, std::uint64_t seed);

/// Per-face form of the piece (form_error), indexed by rotacal's Face order.
struct FaceForm {
  double offset_mm = 0.0;
  double tilt_u_rad = 0.0;
  double tilt_v_rad = 0.0;
};

/// One drawn machine.
struct Machine {
  LocationErrors location;                                    // mm, rad
  Eigen::Vector3d setup_translation_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d setup_rotation_rad = Eigen::Vector3d::Zero();  // about X, then Y, then Z
  std::array<FaceForm, 5> form{};
  bool has_linear_axes = false;
  LinearAxes axes;
  std::array<double, 6> pretravel_mm{};                       // +X -X +Y -Y +Z -Z
  double repeatability_mm = 0.0;                              // per touch, k = 1
  double roughness_mm = 0.0;                                  // per touch, k = 1
  std::uint64_t touch_seed = 0;                               // the per-touch stream's seed
};

/// What to draw, and around what.
struct DrawOptions {
  /// 000 Table 4's means (um / mdeg, Table 1's order dx_AY dy_AY dz_AY dy_CA a_AY b_AY c_AY b_CA):
  /// the centre of the location errors.
  std::array<double, 8> centre{14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};
  /// The spread around it (k = 1): about Table 4's repeat-to-repeat spread, so that the
  /// population is machines like 000's, not one machine.
  double sd_um = 5.0;
  double sd_mdeg = 0.5;
  // Each contributor can be switched off (a clean machine keeps the location errors only).
  bool setup = true, form = true, linear_axes = true, pretravel = true, repeatability = true, roughness = true;
};

/// Draws one machine from the contributors (their declared u, k = 1, normal) with its own seed.
/// The linear axes' nodes cover the machine's strokes with a margin of two spacings.
Machine drawMachine(const ContributorSet& contributors, const MachineModel& machine, const DrawOptions& options,
                    std::uint64_t seed);

/// A machine with the given location errors and nothing else (the cross-check's clean machine).
Machine cleanMachine(const LocationErrors& errors);

/// A chip under one touch: the surface there stands `height_mm` proud (> 0: the ball triggers early).
struct Chip {
  int point_id = 0;
  double height_mm = 0.0;
};

/// The true face plane of a point's face in the machine frame at the point's pose.
struct FacePlane {
  Eigen::Vector3d point_m;
  Eigen::Vector3d normal_m;  // unit, outward
};
FacePlane facePlane_m(const ProbePlan& plan, const ProbePoint& point, const Machine& m);

/// Where a sphere cycle's touched sphere really is on the table (workpiece frame, mm): its plan
/// centre moved by the set-up. On the space frame (003: seven spheres on one plate) the whole frame
/// is turned about its origin on the table (the plan option origin_w_mm, X first, then Y, then Z,
/// exact) and shifted, so each sphere moves by its lever from the origin; a single sphere, or
/// spheres3's three, move by the shift alone (a turn about the column's top centre is the set-up of
/// the square column, not of those spheres).
Eigen::Vector3d sphereCentre_w(const ProbePlan& plan, const ProbePoint& point, const Machine& m);

/// The trigger of every plan point: the read ball-centre position (machine frame, mm) at which the
/// actual ball, moving along the plan's approach line, touches the true face, or on a sphere
/// cycle's point the true sphere (its centre moved by the set-up's translation) (exact contact,
/// linear axes solved by fixed-point iteration), plus pretravel and the per-touch scatter. The
/// per-touch draws come from the machine's touch_seed in plan order, so a chip changes nothing
/// but its own touch. t_s is the plan's. Throws std::runtime_error when a trigger would fall
/// outside the probing move (the program would alarm).
MeasurementRun measure(const ProbePlan& plan, const Machine& m, const std::optional<Chip>& chip = std::nullopt);

/// The spindle head of 004 (Optodyne, the fixed-tool-tip test) on a head machine (head_ab.json):
/// the head tilts in A (about X) and B (about Y) about a pivot, the tool tip (the centre of the
/// spindle tester's precision sphere) hanging at R + dR below it (004 Sec. V: tip = P + Rx(A)
/// Ry(B) (0, 0, -R), P the pivot), the stepping axis turning to its command plus an angular
/// positioning error e(theta). The linear axes carrying the pivot are those of 000 Eq. (22)-(23)
/// with what the contributors file declares (004 Sec. VII's machine positioning). A laser at
/// 004's position 2 reads the sphere along two beams in the rotation plane (the transverse axis
/// and Z), each tilted off its axis (laser_alignment, in and out of the plane), each reading
/// scattered by the laser's own error, the sphere's form and the lateral coupling (per reading and
/// beam), and zeroed at the sweep's first pose at 0 deg (004 Table 1's M0): that zero reading
/// carries its own scatter into every later reading of its sweep.
struct Head {
  double dR_mm = 0.0;
  /// e(theta) = c0 + c1 theta / 90 deg + c2 sin theta + c3 sin 2 theta (mdeg): 004 gives its
  /// angular errors as a curve (Fig. 4), not in numbers.
  std::array<double, 4> angular_mdeg{};
  bool has_linear_axes = false;
  LinearAxes axes;
  /// The beams' tilts (rad): transverse beam towards Z and out of the plane; Z beam towards the
  /// transverse axis and out of the plane.
  std::array<double, 4> beam_tilt_rad{};
  double laser_resolution_mm = 0.0, sphere_form_mm = 0.0, lateral_coupling_mm = 0.0;  // per reading and beam, k = 1
  std::uint64_t reading_seed = 0;

  double angularErrorMdeg(double theta_deg) const;
  /// The beams' unit directions (machine frame) for a plan stepping `axis` ('A' or 'B').
  Eigen::Vector3d beamT(char axis) const;
  Eigen::Vector3d beamZ(char axis) const;
};

/// What to draw for a head, and around what: 004 gives no head errors in numbers, so the centre is
/// docs/tooltip.md's worked example (dR 40 um; e = 3 + 5 theta/90 - 2 sin theta + 1.5 sin 2 theta
/// mdeg) with a spread of 20 um and 1 mdeg per coefficient (k = 1).
struct HeadDrawOptions {
  double dR_um = 40.0, sd_dR_um = 20.0;
  std::array<double, 4> angular_mdeg{3.0, 5.0, -2.0, 1.5};
  double sd_mdeg = 1.0;
  bool linear_axes = true, alignment = true, per_reading = true;
  bool pivot = true;  // false: dR = 0 (drawn all the same, so every other draw stays)
};

/// Draws one head machine from the contributors (laser_resolution, laser_sphere_form,
/// laser_lateral_coupling, laser_alignment, the linear axes' E_*_rand, E_*_lin, S_*), each normal
/// with its declared u (k = 1), with its own seed.
Head drawHead(const ContributorSet& contributors, const MachineModel& machine, const HeadDrawOptions& options,
              std::uint64_t seed);

/// A gross reading: the value of one beam (`z`: the Z beam, else the transverse one) at one plan
/// point off by `mm`.
struct ReadingChip {
  int point_id = 0;
  bool z = false;
  double mm = 0.0;
};

/// The laser readings of a tooltip plan (um, the deviation of the tip along each beam, zeroed at
/// the first pose at 0 deg of its sweep): exact head, pivot through the linear axes, tilted beams,
/// the per-reading scatter from the head's reading_seed in plan order (three draws per beam and
/// reading whatever is declared, so a chip or a switched-off term changes no other draw).
TooltipRun measureHead(const ProbePlan& plan, const Head& head, const std::optional<ReadingChip>& chip = std::nullopt);

}  // namespace rotacal::independent
