#pragma once
// The post-processor route of compensation (mission item 3): rewrite each commanded pose so that
// the machine WITH its identified location errors puts the tool where the nominal machine would
// have put it relative to the workpiece. What the offsets route (000 Sec. 4.5) cannot shift —
// the orientation errors a_AY b_AY c_AY b_CA — the rewritten program cancels point by point.
//
// For a table-tilting machine the tool does not turn; a program that runs without TCP commands
// the controlled point (tool tip or ball centre) in machine coordinates x and the table pose q.
// On the nominal machine the tool is at the workpiece point p_w = T_m_w(0, q)^-1 x with the tool
// direction t_w = R_m_w(0, q)^T k (k: spindle axis, machine frame). Compensation finds
//   q' with R_m_w(e, q')^T k = t_w   (two rotary angles for a 2-DOF direction; least squares when
//                                    the pose cannot reach it, e.g. near A = 0 where C is parallel
//                                    to the tool), then
//   x' = T_m_w(e, q') p_w            (exact: the controlled point lands on p_w whatever q' is).
// Everything exact (full HTMs); q' by Gauss-Newton on the exact direction.
#include <Eigen/Geometry>

#include "core/error_model.hpp"

namespace rotacal {

struct CompensationOptions {
  Eigen::Vector3d tool_axis_m = Eigen::Vector3d::UnitZ();  // spindle axis k, machine frame
  int max_iterations = 30;
  double step_tolerance_rad = 1e-13;  // stop when the angle update is below this
  /// Largest change of a rotary angle the solve may make (deg). Near a pose where a rotary axis is
  /// parallel to the tool (A = 0 on an A/C table: C turns the tool about itself) a tilt of a few
  /// urad would need degrees of that axis; such a component of the direction is left as it is
  /// and reported in direction_residual_rad instead (the position is exact regardless).
  double max_rotary_change_deg = 0.1;
  /// Throws std::invalid_argument naming the bad field.
  void validate() const;
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
CompensatedCommand compensatePose(const LocationErrors& errors, const Pose& nominal_pose,
                                  const CompensationOptions& options = {});

/// x' for a commanded pose q' (which may be q' rounded to the program's decimals): the machine
/// position that puts the controlled point on the nominal workpiece point of (x, q).
Eigen::Vector3d compensatedPosition(const LocationErrors& errors, const Pose& nominal_pose,
                                    const Eigen::Vector3d& x_nominal_m_mm, const Pose& commanded_pose);

/// Angle (rad) between the tool direction relative to the workpiece at (errors, pose) and at the
/// nominal pose of the nominal machine.
double toolDirectionError(const LocationErrors& errors, const Pose& pose, const Pose& nominal_pose,
                          const Eigen::Vector3d& tool_axis_m = Eigen::Vector3d::UnitZ());

}  // namespace rotacal
