#pragma once
// R-test plan -> dialect-neutral NC program (002 Sec. 2.3): at each pose the sphere enters the
// nest along its axis, dwells and triggers the R-test logger's reading. With the thermal
// schedule the tilt axis reciprocates between the cycles (002: B -90 <-> -60 deg at 5000
// deg/min) so that a cycle starts every interval; loops keep the program short.
#include <string>

#include "core/probe_plan.hpp"
#include "gcode/program.hpp"

namespace rotacal {

nc::Program rtestProgram(const ProbePlan& plan, const std::string& dialect);

}  // namespace rotacal
