#pragma once
// Tooltip plan -> neutral NC program (004 Table 1): per sweep, the head to the zero pose in
// absolute G90 G94, a program stop to zero the laser, then G91 G93 steps of the stepping axis
// with the pivot moving so that the tip stays fixed (Yp = -R sin A, Zp = -R (1 - cos A)), an
// inverse-time F on every block, a dwell for each reading (static test), back to G90 G94.
// Increments are differences of positions rounded to the program's decimals, so that the
// rounding never accumulates over the sweep.
#include <string>

#include "core/probe_plan.hpp"
#include "gcode/program.hpp"

namespace rotacal {

nc::Program tooltipProgram(const ProbePlan& plan, const std::string& dialect);

}  // namespace rotacal
