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

}  // namespace rotacal
