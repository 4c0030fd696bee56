#pragma once
// How a command joins the `rotacal` command line: each cmd_*.cpp adds its subcommands to the
// app and returns what to run when one of them was given. Shared helpers for all commands.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "core/geometric_errors.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "postproc/program_check.hpp"
#include "tasks/one_line.hpp"
#include "tasks/program_safety.hpp"  // verifyProgram, requireSafeProgram, checkSummary

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

/// A failure tied to a file given on the command line, when the core cannot name a line.
[[noreturn]] inline void failFile(const std::string& file, const std::string& what) { throw InputError(file, 0, what); }

inline void say(const Common& c, const std::string& text) {
  if (!c.quiet) std::fputs(text.c_str(), stdout);
}

/// The dialects `keep` accepts, in the registry's order, as --help lists a choice: "a | b | c".
template <class Keep>
std::string dialectChoices(Keep keep) {
  std::string s;
  for (const Dialect* d : dialects())
    if (keep(*d)) s += (s.empty() ? "" : " | ") + std::string(d->name());
  return s;
}
/// The dialects that write NC programs.
inline std::string programDialectChoices() {
  return dialectChoices([](const Dialect& d) { return d.hasPrograms(); });
}

inline const Dialect& dialectOrFail(const std::string& name) {
  try {
    return dialectByName(name);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--dialect", e.what());
  }
}

}  // namespace rotacal
