#pragma once
// How a command joins the `rotacal` command line: each cmd_*.cpp adds its subcommands to the
// app and returns what to run when one of them was given. Shared helpers for all commands.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "core/geometric_errors.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "postproc/program_check.hpp"

namespace rotacal {

struct Common {
  bool quiet = false;
};

struct Command {
  CLI::App* sub;
  std::function<int()> run;
};

std::vector<Command> cycleCommands(CLI::App& app, const Common& common);  // plan generate simulate analyze diagnose
std::vector<Command> uncertaintyCommands(CLI::App& app, const Common& common);
std::vector<Command> compensateCommands(CLI::App& app, const Common& common);
std::vector<Command> reportCommands(CLI::App& app, const Common& common);
std::vector<Command> historyCommands(CLI::App& app, const Common& common);
std::vector<Command> checkCommands(CLI::App& app, const Common& common);  // check (cmd_check.cpp)
std::vector<Command> compTableCommands(CLI::App& app, const Common& common);  // comp-table (cmd_comp_table.cpp)

/// A message as the one line on stderr the contract promises: control characters (a line end,
/// a NUL or an escape from an input file quoted in the message) become \xNN, and a message
/// beyond 1000 characters (a 1 MB line quoted whole) is cut, saying so.
inline std::string oneLine(const std::string& s) {
  constexpr size_t kMax = 1000;
  std::string out;
  for (const char ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u == 0x7f) {
      static const char* const hex = "0123456789abcdef";
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    } else {
      out += ch;
    }
    if (out.size() >= kMax) {
      if (&ch != &s.back()) out += "... (message cut at 1000 characters)";
      break;
    }
  }
  return out;
}

/// A failure tied to a file given on the command line, when the core cannot name a line.
[[noreturn]] inline void failFile(const std::string& file, const std::string& what) { throw InputError(file, 0, what); }

inline void say(const Common& c, const std::string& text) {
  if (!c.quiet) std::fputs(text.c_str(), stdout);
}

inline const Dialect& dialectOrFail(const std::string& name) {
  try {
    return dialectByName(name);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--dialect", e.what());
  }
}

/// The program verifier (cmd_check.cpp) on a program's text in `dialect` for `machine`; `plan`
/// (may be null) gives the cycle's program number and the spheres it touches; without it and with
/// `rotacal_number`, a program number must be one of rotacal's cycles' (compensate, which also
/// rewrites programs rotacal did not write, keeps the number it was given and asks for none).
/// `errors` (may be null): simulate on the machine with these location errors (compensate's).
/// `part_program_origin` (set: a part program, ProgramCheckSetup::part_program, with its zero there).
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
