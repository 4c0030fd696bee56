// `rotacal compensate`: the post-processor route of contract.md. Reads an NC program and the
// REPORT.json of `analyze`, and writes the program rewritten so that the machine with the
// identified location errors moves the tool as the nominal machine would have
// (postproc/compensate_program.hpp, docs/compensation.md).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/command.hpp"
#include "cli/output.hpp"
#include "controllers/common.hpp"
#include "controllers/motion_reader.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/units.hpp"
#include "history/store.hpp"
#include "postproc/compensate_program.hpp"
#include "postproc/report_errors.hpp"

namespace rotacal {
namespace {

// The syntax the rewrite needs from a word-address dialect. Heidenhain Klartext (L X+.. Y+..)
// is not word-address G-code and the neutral csv is no program: both are refused.
NcSyntax syntaxOf(const std::string& dialect) {
  NcSyntax s;
  s.dialect = dialect;
  if (dialect == "linuxcnc" || dialect == "fanuc" || dialect == "haas" || dialect == "okuma") return s;
  if (dialect == "siemens") {
    s.comment = NcSyntax::Comment::Semicolon;
    return s;
  }
  if (dialect == "heidenhain")
    throw CLI::ValidationError("--dialect", "heidenhain: Klartext programs are not rewritten; enter the kinematics "
                                            "values of `analyze --offsets` instead (docs/compensation.md)");
  throw CLI::ValidationError("--dialect", "'" + dialect + "' has no NC programs to compensate (linuxcnc, fanuc, haas, "
                                          "siemens, okuma)");
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

// A report older than this is flagged: a machine's location errors move with crashes,
// maintenance and the seasons, and a compensation for last quarter's machine is a guess.
constexpr double kReportAgeFlagDays = 30.0;

// The report must be of this machine: its identity and kinematics, as analyze recorded them.
void requireSameMachine(const JsonDoc& report, const MachineModel& machine, const std::string& machine_file) {
  const Json& j = report.value;
  if (!j.is_object() || !j.contains("machine_model") || !j["machine_model"].is_object()) return;
  const Json& mm = j["machine_model"];
  const std::string name = mm.contains("name") && mm["name"].is_string() ? mm["name"].get<std::string>() : "";
  const std::string kin = mm.contains("kinematics") && mm["kinematics"].is_string() ? mm["kinematics"].get<std::string>() : "";
  if (name != machine.name || kin != kinematicsName(machine.kinematics))
    report.fail(j, "machine_model", fmt::format("the report was measured on machine '{}' ({}); --machine {} is '{}' ({}): "
                                                "a compensation is for the machine that was measured",
                                                name, kin, machine_file, machine.name,
                                                kinematicsName(machine.kinematics)));
}

// When the report was analyzed, and whether that is old.
std::string reportAgeNote(const JsonDoc& report, double now_s) {
  const Json& j = report.value;
  if (!j.is_object() || !j.contains("analyzed_utc") || !j["analyzed_utc"].is_string())
    return report.file + " records no date (analyze records one since this version): how old it is is not known";
  double t = 0.0;
  try {
    t = history::parseIsoTime(j["analyzed_utc"].get<std::string>());
  } catch (const std::invalid_argument& e) {
    report.fail(j, "analyzed_utc", e.what());
  }
  const double days = (now_s - t) / 86400.0;
  if (days > kReportAgeFlagDays)
    return fmt::format("{} was analyzed {} ({:.0f} days ago, more than {:.0f}): the machine may have moved since; "
                       "measure again before cutting",
                       report.file, j["analyzed_utc"].get<std::string>(), days, kReportAgeFlagDays);
  return {};
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
  MachineModel machine;
  if (!machine_file.empty()) {
    machine = loadMachine(machine_file);
  } else {
    const JsonDoc& report = reports.front();
    if (report.value.is_object() && report.value.contains("machine_model"))
      machine = machineFromJson(report, report.value["machine_model"]);
    else
      report.fail(report.value, "", "the report does not carry its machine ('machine_model', written by analyze since "
                                    "this version): give --machine MACHINE.json");
  }
  if (!machine_file.empty())
    for (const auto& r : reports) requireSameMachine(r, machine, machine_file);
  for (const std::string& h : table_holds) {
    bool known = false;
    for (const auto& r : machine.rotary)
      for (const auto& n : componentErrorNames(r.name)) known = known || n == h;
    if (!known)
      throw CLI::ValidationError("--table-holds", "'" + h + "' is no component error of this machine's rotary axes "
                                                  "(e.g. ECC: the C axis's angular positioning)");
  }
  ReportErrors read = errorsFromReports(reports, machine.kinematics, force, table_holds);
  for (const auto& r : reports) {
    const std::string age = reportAgeNote(r, nowUnixS());
    if (!age.empty()) read.notes.push_back(age);
  }
  const GeometricErrors& errors = read.errors;
  ProgramCompensationOptions opt;
  if (!origin.empty()) {
    const auto v = parseTriple("--program-origin", origin);
    opt.program_origin_m_mm = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  opt.subdivision.max_deviation_mm = umToMm(max_deviation_um);
  // The reports' paths are outside text: the dialect's comment form keeps only its safe characters.
  for (const auto& s : read.sources) opt.header.push_back(s);
  std::string values = "location errors:";
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const auto& p = locationParameters(machine.kinematics)[i];
    values += fmt::format("{} {} {:.2f} {}", i == 0 ? "" : ",", p.name, errors.location.reportValue(i), reportUnit(p.kind));
  }
  opt.header.push_back(values);
  for (const auto& comp : errors.components) {
    // The largest magnitude of each component error over the sampled angles.
    std::string line = fmt::format("component errors of {}, largest over the turn:", comp.axis);
    const auto names = componentErrorNames(comp.axis);
    for (int k = 0; k < kNumComponentErrors; ++k) {
      double worst = 0.0;
      for (const auto& v : comp.values) worst = std::max(worst, std::abs(v[k]));
      line += fmt::format("{} {} {:.2f} {}", k == 0 ? "" : ",", names[static_cast<size_t>(k)],
                          k < 3 ? mmToUm(worst) : radToMdeg(worst), k < 3 ? "um" : "mdeg");
    }
    opt.header.push_back(line);
  }
  for (const auto& n : read.notes) opt.header.push_back(n);
  const std::string text = readTextFile(program_file);
  const ProgramCompensation r = compensateProgram(text, program_file, machine, errors, syntax, opt);
  // A program without a probing move is a part program: checked as one (the tool's point against
  // the table; no probe, no calibration artefact on the table), from its own zero. A probing
  // program keeps the probing checks.
  bool probing = false;
  for (const auto& m : ctl::readMotions(dialect, text)) probing = probing || m.kind == nc::Motion::Kind::Probe;
  const std::optional<Eigen::Vector3d> part =
      probing ? std::nullopt : std::optional<Eigen::Vector3d>(opt.program_origin_m_mm);
  // The input, on the nominal machine it was written for: what makes it unsafe is named at its
  // own line (the rewrite's lines are not the user's).
  requireSafeProgram(text, program_file, dialect, machine, nullptr, false, nullptr, part);
  // The program verifier (`rotacal check`) on the rewrite, before it is written: the guards follow
  // their moves, strokes, clearances on the machine's set-up - the machine with the errors it is
  // compensated for, where it keeps its planned gaps. The input's program number is kept.
  requireSafeProgram(r.text, out, dialect, machine, nullptr, false, &errors, part);
  writeFileAtomic(out, r.text);
  for (const auto& n : read.notes) say(c, fmt::format("compensate: note: {}\n", n));
  if (!probing)
    say(c, "compensate: a part program (no probing move): checked as one, the tool's point against the table, no "
           "probe and no calibration artefact\n");
  say(c, fmt::format("compensate: {} of {} motion blocks rewritten ({} left as written: machine-coordinate moves or "
                     "before every axis was known); largest shift {:.2f} um, largest rotary change {:.2f} mdeg, tool "
                     "direction not restorable by the rotary axes up to {:.2f} urad; {} no-trigger check statements "
                     "moved with their probing moves (up to {:.2f} um) -> {}\n",
                     r.compensated_blocks, r.motion_blocks, r.uncompensated_blocks, mmToUm(r.max_shift_mm),
                     r.max_rotary_change_deg * 1000.0, r.max_direction_residual_rad * 1e6, r.rewritten_checks,
                     mmToUm(r.max_check_shift_mm), out));
  say(c, fmt::format("compensate: {} feed moves split into {} more lines (a move unsplit would leave the nominal path by "
                     "up to {:.3f} um; written: {:.3f} um, tolerance {:.3f} um)\n",
                     r.split_blocks, r.added_blocks, mmToUm(r.max_unsplit_deviation_mm), mmToUm(r.max_path_deviation_mm),
                     max_deviation_um));
  if (errors.location_covariance)
    say(c, fmt::format("compensate: the identification's uncertainty leaves the compensated tool point uncertain by up "
                       "to {:.2f} um (k = 2) at this program's end points\n",
                       2.0 * mmToUm(r.max_position_u_mm)));
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
  cmd->add_option("--dialect", a->dialect, "linuxcnc | fanuc | haas | siemens | okuma")->required();
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
