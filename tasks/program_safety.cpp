// The program verifier on a program's text (tasks/program_safety.hpp).
#include "tasks/program_safety.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "controllers/motion_reader.hpp"
#include "core/errors.hpp"
#include "cycles/check_rules.hpp"

namespace rotacal {

constexpr size_t kMaxProgramLineChars = 1024;

ProgramCheckResult verifyProgram(const std::string& text, const std::string& dialect, const MachineModel& machine,
                                 const ProbePlan* plan, bool rotacal_number, const GeometricErrors* errors,
                                 const std::optional<Eigen::Vector3d>& part_program_origin) {
  ProgramCheckSetup s = programCheckSetup(machine, dialect, ctl::numbersPrograms(dialect), plan, rotacal_number);
  if (errors) s.errors = *errors;
  if (part_program_origin) {
    s.part_program = true;
    s.program_origin_m_mm = *part_program_origin;
  }
  ProgramCheckResult r = checkProgram(ctl::readMotions(dialect, text), s);
  // What no control reads: an empty program, a line beyond the longest block any of the dialects
  // takes (compensate's limit, 1024 characters; LinuxCNC stops at 255).
  std::vector<ProgramViolation> text_problems;
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    text_problems.push_back({1, "empty program: nothing to run"});
  size_t start = 0;
  for (int line = 1; start < text.size(); ++line) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    if (end - start > kMaxProgramLineChars)
      text_problems.push_back({line, fmt::format("line of {} characters: no control reads a block longer than {}",
                                                 end - start, kMaxProgramLineChars)});
    start = end + 1;
  }
  r.violations.insert(r.violations.begin(), text_problems.begin(), text_problems.end());
  return r;
}

void requireSafeProgram(const std::string& text, const std::string& file, const std::string& dialect,
                        const MachineModel& machine, const ProbePlan* plan, bool rotacal_number,
                        const GeometricErrors* errors, const std::optional<Eigen::Vector3d>& part_program_origin) {
  const ProgramCheckResult r = verifyProgram(text, dialect, machine, plan, rotacal_number, errors, part_program_origin);
  if (r.violations.empty()) return;
  const ProgramViolation& v = r.violations.front();
  throw InputError(file, v.line,
                   fmt::format("the program fails rotacal check ({} violation{}; nothing written): {}", r.violations.size(),
                               r.violations.size() == 1 ? "" : "s", v.problem));
}

std::string checkSummary(const std::string& file, const std::string& text, const ProgramCheckResult& r) {
  const auto lines = std::count(text.begin(), text.end(), '\n') + (!text.empty() && text.back() != '\n' ? 1 : 0);
  return fmt::format("{}: ok: {} lines, {} motion blocks, {} probing moves, minimum clearance {} ({} obstacles modelled, "
                     "{} positions swept)\n",
                     file, lines, r.motion_blocks, r.probing_moves,
                     r.obstacles == 0 || !std::isfinite(r.min_clearance_mm)
                         ? std::string("not modelled")
                         : fmt::format("{:.3f} mm (required {:.3f} mm)", r.min_clearance_mm, r.required_gap_mm),
                     r.obstacles, r.swept_samples);
}

}  // namespace rotacal
