#pragma once
// What the program checker (postproc/program_check.hpp) learns from the cycles: `rotacal check`
// and its tests build the same setup.
#include "core/probe_plan.hpp"
#include "postproc/program_check.hpp"

namespace rotacal {

/// The setup of a program of `dialect` (`numbered`: its programs carry a number) on `machine`.
/// With a plan: whether its cycle's artefact stands on the table while it runs (a cycle whose
/// artefact is another, e.g. a sensor nest, says not) and, when numbered, the cycle's program
/// number. Without a plan and with `any_rotacal_number`: every cycle's number.
ProgramCheckSetup programCheckSetup(const MachineModel& machine, const std::string& dialect, bool numbered,
                                    const ProbePlan* plan, bool any_rotacal_number);

}  // namespace rotacal
