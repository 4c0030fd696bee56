#pragma once
// Plan -> dialect-neutral NC program: the safe path of core/probe_plan.hpp (index height,
// safe height per pose, approach start, guarded move, retract) in the controller's
// coordinates: program length unit, rotary angles with the controller's sign for the dialect.
#include <string>

#include "core/probe_plan.hpp"
#include "gcode/program.hpp"

namespace rotacal {

nc::Program probeProgram(const ProbePlan& plan, const std::string& dialect);

/// The operation of a linear move of the path (ClimbZ, Rapid, Position, Retract) in the program's
/// length unit (k: program units per mm). Other kinds come back with only xyz set: what they
/// carry (a pose's name, a probing move's guard, a dwell, a reading) is the cycle's to fill.
nc::Op pathMoveOp(const Waypoint& move, const MachineModel& machine, double k);

/// Controller rotary angle (deg) for a papers'-convention pose angle.
double controllerAngle(const MachineModel& machine, char axis, const std::string& dialect, double paper_deg);

/// An indexing move to `pose`: every rotary axis of the machine, or only `axis` when it is not
/// 0, at its controller angle for `dialect`; `feed` deg/min (0: the control's rapid).
nc::Op indexOp(const MachineModel& machine, const Pose& pose, const std::string& dialect, char axis = 0, double feed = 0.0);

nc::Op commentOp(const std::string& text);

/// The name of the plan's pose at exactly these angles (the last listed), "" when none: what a
/// program's comment before an index move calls the pose.
std::string poseNameAt(const ProbePlan& plan, const Pose& pose);

/// The header's line per rotary axis: the controller's sign against the papers' convention
/// (`source` names that convention's equation, may be empty).
std::vector<std::string> angleSignLines(const MachineModel& machine, const std::string& dialect, const std::string& source);

/// The convention the plan's angles follow on this kinematics: the papers' chain of a tilting
/// table (000 Eq. (1), 002 Eq. (2)) or, for a head, ISO 841 (the head turns by +angle).
std::string angleConvention(Kinematics kinematics);

/// What the program's X Y Z are and where its work offset must put them, derived from the
/// machine: on a table machine the probe-ball centre (through the probe's tool length when it has
/// a tool number) with the zero at the rotary axes' intersection; on a head machine the head's
/// pivot, the ball hanging pivot_to_ball_mm from it along the spindle. Every cycle's program
/// header states these, so that no operator sets up a head machine as a table.
std::vector<std::string> setupLines(const MachineModel& machine);

}  // namespace rotacal
