#pragma once
// The program verifier on a program's text (`rotacal check`, and what `generate` and `compensate`
// run on a program before they write it): postproc/program_check.hpp on the motions the
// dialect's reader finds, with what no control reads (an empty program, an overlong line).
#include <optional>
#include <string>

#include "core/geometric_errors.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "postproc/program_check.hpp"

namespace rotacal {

/// The program verifier on a program's text in `dialect` for `machine`; `plan` (may be null) gives
/// the cycle's program number and the spheres it touches; without it and with `rotacal_number`, a
/// program number must be one of rotacal's cycles' (compensate, which also rewrites programs
/// rotacal did not write, keeps the number it was given and asks for none).
/// `errors` (may be null): simulate on the machine with these location errors (compensate's).
/// `part_program_origin` (set: a part program, ProgramCheckSetup::part_program, its zero there).
ProgramCheckResult verifyProgram(const std::string& text, const std::string& dialect, const MachineModel& machine,
                                 const ProbePlan* plan, bool rotacal_number, const GeometricErrors* errors = nullptr,
                                 const std::optional<Eigen::Vector3d>& part_program_origin = std::nullopt);
/// Throws InputError(file, line, ...) with the first violation of verifyProgram and their count:
/// `generate` and `compensate` call it before they write, so an unsafe program is never written.
void requireSafeProgram(const std::string& text, const std::string& file, const std::string& dialect,
                        const MachineModel& machine, const ProbePlan* plan, bool rotacal_number,
                        const GeometricErrors* errors = nullptr,
                        const std::optional<Eigen::Vector3d>& part_program_origin = std::nullopt);
/// The one line `check` prints for a clean program.
std::string checkSummary(const std::string& file, const std::string& text, const ProgramCheckResult& result);

}  // namespace rotacal
