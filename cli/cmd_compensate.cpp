// `rotacal compensate`: the post-processor route of contract.md. Reads an NC program and the
// REPORT.json of `analyze`, and writes the program rewritten so that the machine with the
// identified location errors moves the tool as the nominal machine would have
// (postproc/compensate_program.hpp, docs/compensation.md).
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/command.hpp"
#include "cli/output.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/units.hpp"
#include "postproc/compensate_program.hpp"
#include "postproc/report_errors.hpp"
#include "tasks/compensate.hpp"

namespace rotacal {
namespace {

// The dialect's syntax (tasks/compensate.hpp), refused as a usage error of --dialect.
NcSyntax syntaxOf(const std::string& dialect) {
  try {
    return ncSyntaxOf(dialect);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--dialect", e.what());
  }
}

std::vector<double> parseTriple(const std::string& opt, const std::string& text) {
  std::vector<double> v;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    try {
      size_t used = 0;
      v.push_back(std::stod(part, &used));
      if (used != part.size()) throw std::invalid_argument(part);
    } catch (const std::exception&) {
      throw CLI::ValidationError(opt, "expected X,Y,Z in mm, got '" + text + "'");
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() != 3) throw CLI::ValidationError(opt, "expected X,Y,Z in mm, got '" + text + "'");
  return v;
}

int cmdCompensate(const Common& c, const std::string& program_file, const std::vector<std::string>& report_files,
                  const std::string& machine_file, const std::string& dialect, const std::string& origin,
                  const std::string& out, bool force, double max_deviation_um,
                  const std::vector<std::string>& table_holds) {
  const NcSyntax syntax = syntaxOf(dialect);
  std::vector<std::string> inputs = {program_file};
  for (const auto& r : report_files) inputs.push_back(r);
  if (!machine_file.empty()) inputs.push_back(machine_file);
  checkOutputs({{"-o", out}}, inputs);  // -o on an input is a usage error, before anything is read
  std::vector<JsonDoc> reports;
  for (const auto& r : report_files) reports.push_back(readJsonFile(r));
  std::optional<MachineModel> machine;
  if (!machine_file.empty()) machine = loadMachine(machine_file);
  ReportChecks checks;
  checks.table_holds = table_holds;
  checks.now_s = nowUnixS();
  checks.machine_file = "--machine " + machine_file;
  CompensationInputs in;
  try {
    in = compensationInputs(reports, machine, force, checks);
  } catch (const UnknownHeldError& e) {
    throw CLI::ValidationError("--table-holds", e.what());
  }
  ProgramCompensationOptions opt;
  if (!origin.empty()) {
    const auto v = parseTriple("--program-origin", origin);
    opt.program_origin_m_mm = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  opt.subdivision.max_deviation_mm = umToMm(max_deviation_um);
  opt.header = in.header;
  const std::string text = readTextFile(program_file);
  const ProgramCompensation r = compensateVerified(text, program_file, out, dialect, syntax, in, opt);
  writeFileAtomic(out, r.text);
  for (const auto& line : compensateMessages(in, r, out, max_deviation_um)) say(c, line);
  return 0;
}

}  // namespace

std::vector<Command> compensateCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string program, machine, dialect, origin, out;
    std::vector<std::string> reports;
    bool force = false;
    double max_deviation_um = 0.2;
    std::vector<std::string> table_holds;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("compensate", "rewrite an NC program to cancel the identified location errors");
  cmd->add_option("--program", a->program, "IN: the NC program (machine coordinates, no TCP)")->required();
  cmd->add_option("--report", a->reports,
                  "REPORT.json of analyze; repeat to combine (location errors from one, component errors from another)")
      ->required();
  cmd->add_option("--dialect", a->dialect,
                  dialectChoices([](const Dialect& d) { return isWordAddress(d.language()); }))
      ->required();
  cmd->add_option("--machine", a->machine, "MACHINE.json (default: the machine recorded in the report)");
  cmd->add_option("--program-origin", a->origin,
                  "X,Y,Z (mm): machine position of the program zero relative to the rotary-axis intersection (default "
                  "0,0,0)");
  cmd->add_option("-o,--output", a->out, "OUT: the rewritten program")->required();
  cmd->add_option("--max-deviation-um", a->max_deviation_um,
                  "split a feed move that turns a rotary axis where it would leave the nominal path by more (um)")
      ->check(CLI::Range(0.001, 1000.0));
  cmd->add_option("--table-holds", a->table_holds,
                  "a component error the controller's compensation table holds (e.g. ECC, loaded from `rotacal "
                  "comp-table`): left out here, so that it is compensated once; repeat for several");
  cmd->add_flag("--force", a->force,
                "compensate location errors beyond the plausibility limit of the offsets writers (0.5 mm, 100 mdeg)");
  return {{cmd, [a, &common] {
             return cmdCompensate(common, a->program, a->reports, a->machine, a->dialect, a->origin, a->out, a->force,
                                  a->max_deviation_um, a->table_holds);
           }}};
}

}  // namespace rotacal
