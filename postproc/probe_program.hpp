#pragma once
// Plan -> dialect-neutral NC program: the safe path of core/probe_plan.hpp (index height,
// safe height per pose, approach start, guarded move, retract) in the controller's
// coordinates: program length unit, rotary angles with the controller's sign for the dialect.
#include <string>

#include "core/probe_plan.hpp"
#include "gcode/program.hpp"

namespace rotacal {

nc::Program probeProgram(const ProbePlan& plan, const std::string& dialect);

/// Controller rotary angle (deg) for a papers'-convention pose angle.
double controllerAngle(const MachineModel& machine, char axis, const std::string& dialect, double paper_deg);

}  // namespace rotacal
