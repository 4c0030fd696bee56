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

}  // namespace rotacal
