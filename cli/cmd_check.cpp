// `rotacal check PROGRAM --dialect D --machine MACHINE.json [--plan PLAN.json]`: the program
// verifier (postproc/program_check.hpp) on a program file, and the same check that `generate`
// and `compensate` run on what they are about to write (requireSafeProgram): a program that
// fails it is never written.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/command.hpp"
#include "controllers/motion_reader.hpp"
#include "core/error_model.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "cycles/check_rules.hpp"
#include "cycles/cycle.hpp"
#include "postproc/program_check.hpp"

namespace rotacal {

namespace {

int cmdCheck(const Common& c, const std::string& program_file, const std::string& dialect,
             const std::string& machine_file, const std::string& plan_file, bool part_program) {
  if (part_program && !plan_file.empty())
    throw CLI::ValidationError("--part-program", "a part program has no cycle plan: give one of --plan, --part-program");
  const Dialect& d = dialectOrFail(dialect);
  if (!d.hasPrograms())
    throw CLI::ValidationError("--dialect", std::string(d.name()) + " has no NC programs to check");
  const MachineModel machine = loadMachine(machine_file);
  std::optional<ProbePlan> plan;
  if (!plan_file.empty()) {
    plan = loadCyclePlan(plan_file);
    try {
      cycleOfPlan(*plan);
    } catch (const std::invalid_argument& e) {
      failFile(plan_file, e.what());
    }
  }
  // With a plan, what stands on the table is the plan's, as `generate` checked it: a space frame's
  // plan takes the column off the table, and the machine file's column would be a collision on
  // every move. The plan must be of this machine.
  MachineModel checked = machine;
  if (plan) {
    if (plan->machine.name != machine.name || plan->machine.kinematics != machine.kinematics)
      failFile(plan_file, fmt::format("the plan is of machine '{}' ({}), --machine {} is '{}' ({})", plan->machine.name,
                                      kinematicsName(plan->machine.kinematics), machine_file, machine.name,
                                      kinematicsName(machine.kinematics)));
    checked.artefact = plan->machine.artefact;
  }
  const std::string text = readTextFile(program_file);
  // A part program (postproc/program_check.hpp): the tool's point against the table, from the
  // program's zero at the rotary-axis intersection, as rotacal's own programs; no program number.
  ProgramCheckResult r =
      part_program ? verifyProgram(text, dialect, checked, nullptr, false, nullptr, Eigen::Vector3d::Zero())
                   : verifyProgram(text, dialect, checked, plan ? &*plan : nullptr, true);
  // The dialect's own rules (comments, brackets, labels and jump targets, decimal points, the
  // no-trigger alarms it writes), against what the plan's program must show: the checker
  // `generate` runs before it writes, so a hand-edited program is not passed on its motion alone.
  if (plan) {
    nc::Shape shape;
    try {
      shape = nc::shapeOf(cycleOfPlan(*plan).program(*plan, dialect));
    } catch (const std::invalid_argument& e) {
      failFile(plan_file, e.what());
    }
    std::vector<ProgramViolation> rules;
    for (const std::string& p : d.check(text, *plan, shape)) {
      // "LINE: problem" (controllers/dialect.hpp); a problem of the whole program names line 1.
      const size_t colon = p.find(": ");
      int line = 1;
      std::string what = p;
      if (colon != std::string::npos && colon > 0 &&
          std::all_of(p.begin(), p.begin() + static_cast<long>(colon), [](char ch) { return ch >= '0' && ch <= '9'; })) {
        line = std::max(1, std::atoi(p.substr(0, colon).c_str()));
        what = p.substr(colon + 2);
      }
      rules.push_back({line, fmt::format("the {} checker: {}", d.name(), what)});
    }
    r.violations.insert(r.violations.begin(), rules.begin(), rules.end());
    std::stable_sort(r.violations.begin(), r.violations.end(),
                     [](const ProgramViolation& a, const ProgramViolation& b) { return a.line < b.line; });
  }
  if (!r.violations.empty()) {
    for (const auto& v : r.violations) std::printf("%s:%d: %s\n", program_file.c_str(), v.line, v.problem.c_str());
    std::fflush(stdout);
    // The one line of the contract: the first violation where it is, and how many there are.
    const ProgramViolation& v = r.violations.front();
    throw InputError(program_file, v.line,
                     r.violations.size() == 1
                         ? v.problem
                         : fmt::format("{} (and {} more violations, listed on stdout)", v.problem, r.violations.size() - 1));
  }
  say(c, checkSummary(program_file, text, r));
  if (part_program) {
    say(c, fmt::format("{}: checked as a part program: the tool's point against the table, no probe, no calibration "
                       "artefact\n",
                       program_file));
    return 0;
  }
  say(c, plan ? fmt::format("{}: the {} checker's rules (comments, brackets, labels, alarms): ok against the plan\n",
                            program_file, d.name())
              : fmt::format("{}: the {} checker's rules (comments, brackets, labels, alarms): not checked (give --plan)\n",
                            program_file, d.name()));
  return 0;
}

}  // namespace

std::vector<Command> checkCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string program, dialect, machine, plan;
    bool part_program = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("check", "verify an NC program on the machine: clearances swept along every move, "
                                          "guarded probing moves with their checks, strokes, feeds, program number");
  cmd->add_option("program", a->program, "PROGRAM: the NC program")->required();
  cmd->add_option("--dialect", a->dialect, programDialectChoices())->required();
  cmd->add_option("--machine", a->machine, "MACHINE.json")->required();
  cmd->add_option("--plan", a->plan, "PLAN.json: the cycle's number, the spheres it touches; every probing move must "
                                     "reach a surface");
  cmd->add_flag("--part-program", a->part_program,
                "check a part program: the tool's point against the table (MACHINE.json table_top_z_mm, else the "
                "artefact's foot), no probe and no calibration artefact; X Y Z from the rotary-axis intersection");
  return {{cmd, [a, &common] {
             return cmdCheck(common, a->program, a->dialect, a->machine, a->plan, a->part_program);
           }}};
}

}  // namespace rotacal
