#pragma once
// The post-processor route of compensation (mission item 3): rewrite each commanded pose so that
// the machine WITH its identified geometric errors puts the tool where the nominal machine would
// have put it relative to the workpiece. What the offsets route (000 Sec. 4.5) cannot shift —
// the orientation errors a_AY b_AY c_AY b_CA — the rewritten program cancels point by point.
//
// For a table-tilting machine the tool does not turn; a program that runs without TCP commands
// the controlled point (tool tip or ball centre) in machine coordinates x and the table pose q.
// On the nominal machine the tool is at the workpiece point p_w = T_m_w(0, q)^-1 x with the tool
// direction t_w = R_m_w(0, q)^T k (k: spindle axis, machine frame). Compensation finds
//   q' with R_m_w(e, q')^T k = t_w   (two rotary angles for a 2-DOF direction), then
//   x' = T_m_w(e, q') p_w            (exact: the controlled point lands on p_w whatever q' is).
// Everything exact (full HTMs); q' by the shared estimation engine (core/least_squares) on the exact direction. The errors are the
// location errors and, where a cycle identified them, the component errors of a rotary axis
// (core/geometric_errors.hpp).
//
// Near a pose where a rotary axis is parallel to the tool (A = 0 on an A/C table: C turns the
// tool about itself) a tilt of a few urad would need degrees of that axis. Below the tilt
// `singular_blend_deg` the step along that axis (the weak right singular vector of the nominal
// J_t_q) is damped, the damping growing smoothly to full at the singular pose
// (lambda = s1 (1 - (s/s1)^2)^2, s the smallest singular value of J_t_q, s1 its value at the
// blend tilt): the command varies continuously along a path through A = 0 (no jump of C between
// neighbouring blocks) and is exact beyond the blend tilt. What the damped axis does not restore
// stays as a tool-direction error, reported: at A = 0 exactly it is the tilt about the axis
// neither rotary axis turns about, |b_AY + b_CA| on an A/C table (position exact regardless).
//
// A move between two compensated end points is a straight line in joint space, not the image of
// the nominal move: compensateMove() splits it where the controlled point would leave the
// nominal path by more than a tolerance, evaluated on the exact model along the move.
#include <Eigen/Geometry>

#include <functional>
#include <string>
#include <vector>

#include "core/geometric_errors.hpp"

namespace rotacal {

struct CompensationOptions {
  Eigen::Vector3d tool_axis_m = Eigen::Vector3d::UnitZ();  // spindle axis k, machine frame
  int max_iterations = 30;
  double step_tolerance_rad = 1e-13;  // stop when the angle update is below this
  /// Tilt from the singular pose (deg) below which the axis parallel to the tool is damped
  /// (above). Near the singular pose that axis then moves at most about 1.25 / sin(2 deg) = 36
  /// times the tilt it restores (the undamped solve needs 1 / sin A times: unbounded at A = 0).
  double singular_blend_deg = 2.0;
  /// False (and why, naming the field) when a field is out of range.
  bool validate(std::string* why) const;
};

struct CompensatedCommand {
  Pose pose;                      // q', papers' convention, deg
  Eigen::Vector3d x_m_mm;         // x', machine frame, mm
  double direction_residual_rad;  // angle between R(e,q')^T k and the nominal t_w (0 when reachable)
  int iterations = 0;
};

/// The rotary angles q' (deg) that best restore the nominal tool direction relative to the
/// workpiece on the machine with `errors`; only the two rotary axes of the kinematics move.
/// Angles not moved by the solve stay at the nominal value (minimum-norm steps).
CompensatedCommand compensatePose(const GeometricErrors& errors, const Pose& nominal_pose,
                                  const CompensationOptions& options = {});

/// x' for a commanded pose q' (which may be q' rounded to the program's decimals): the machine
/// position that puts the controlled point on the nominal workpiece point of (x, q).
Eigen::Vector3d compensatedPosition(const GeometricErrors& errors, const Pose& nominal_pose,
                                    const Eigen::Vector3d& x_nominal_m_mm, const Pose& commanded_pose);

/// Angle (rad) between the tool direction relative to the workpiece at (errors, pose) and at the
/// nominal pose of the nominal machine.
double toolDirectionError(const GeometricErrors& errors, const Pose& pose, const Pose& nominal_pose,
                          const Eigen::Vector3d& tool_axis_m = Eigen::Vector3d::UnitZ());

/// A block's end point as the machine is commanded: controlled point (machine frame, relative
/// to the rotary-axis intersection, mm) and rotary pose (papers' convention, deg).
struct MachineCommand {
  Eigen::Vector3d x_m_mm = Eigen::Vector3d::Zero();
  Pose pose;
};

struct SubdivisionOptions {
  /// Largest distance (mm) of the controlled point, seen from the workpiece, from where the
  /// nominal machine would put it at the same fraction of the move (0.2 um).
  double max_deviation_mm = 0.2e-3;
  int samples_per_piece = 8;  // interior points at which each piece is evaluated
  int max_pieces = 1000;      // a move needing more is refused (compensateMove throws)
  bool validate(std::string* why) const;  // false (and why, naming the field) when out of range
};

struct CompensatedMove {
  std::vector<double> s;                  // fraction of the nominal move at each piece's end
  std::vector<MachineCommand> ends;       // compensated command at each piece's end (last: the move's)
  std::vector<double> direction_residual_rad;  // at each piece's end
  double max_deviation_mm = 0.0;          // along the compensated pieces, from the nominal path
  double unsplit_deviation_mm = 0.0;      // the same for the move left in one piece
};

/// Rounds a compensated pose as the program will print it (identity when not given): the
/// positions are computed for the printed angles.
using PoseRounding = std::function<Pose(const Pose&)>;

/// The nominal move from -> to (straight in joint space on the nominal machine) compensated and
/// split into the fewest equal pieces whose controlled point stays within max_deviation_mm of the
/// nominal path (seen from the workpiece) at every evaluated point. Throws std::runtime_error when
/// more than max_pieces would be needed.
CompensatedMove compensateMove(const GeometricErrors& errors, const MachineCommand& from, const MachineCommand& to,
                               const CompensationOptions& options = {}, const SubdivisionOptions& subdivision = {},
                               const PoseRounding& rounding = {});

/// Largest distance (mm) of the controlled point from the nominal path, seen from the workpiece,
/// over `samples` interior points of the joint-space straight line from compensated command c0 to
/// c1, which stand for the nominal fractions s0 and s1 of the nominal move from -> to.
double pieceDeviation(const GeometricErrors& errors, const MachineCommand& from, const MachineCommand& to, double s0,
                      double s1, const MachineCommand& c0, const MachineCommand& c1, int samples);

}  // namespace rotacal
