// `rotacal compensate` on texts already read (tasks/compensate.hpp).
#include "tasks/compensate.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/errors.hpp"
#include "controllers/dialect.hpp"
#include "controllers/motion_reader.hpp"
#include "core/iso_time.hpp"
#include "core/units.hpp"
#include "tasks/program_safety.hpp"

namespace rotacal {

// Only word-address G-code is rewritten: a program of another language (Klartext) is refused with
// its dialect's reason, and a dialect without programs (the neutral csv) with the list of those
// that have them.
NcSyntax ncSyntaxOf(const std::string& dialect) {
  NcSyntax s;
  s.dialect = dialect;
  const Dialect* d = findDialect(dialect);
  const ProgramLanguage language = d ? d->language() : ProgramLanguage::None;
  if (isWordAddress(language)) {
    if (language == ProgramLanguage::Sinumerik) s.comment = NcSyntax::Comment::Semicolon;
    return s;
  }
  if (d && !d->rewriteRefusal().empty())
    throw std::invalid_argument(dialect + ": " + std::string(d->rewriteRefusal()));
  std::string rewritten;
  for (const Dialect* o : dialects())
    if (isWordAddress(o->language())) rewritten += (rewritten.empty() ? "" : ", ") + std::string(o->name());
  throw std::invalid_argument("'" + dialect + "' has no NC programs to compensate (" + rewritten + ")");
}

namespace {

// The report must be of this machine: its identity and kinematics, as analyze recorded them.
void requireSameMachine(const JsonDoc& report, const MachineModel& machine, const std::string& machine_file) {
  const Json& j = report.value;
  if (!j.is_object() || !j.contains("machine_model") || !j["machine_model"].is_object()) return;
  const Json& mm = j["machine_model"];
  const std::string name = mm.contains("name") && mm["name"].is_string() ? mm["name"].get<std::string>() : "";
  const std::string kin =
      mm.contains("kinematics") && mm["kinematics"].is_string() ? mm["kinematics"].get<std::string>() : "";
  if (name != machine.name || kin != kinematicsName(machine.kinematics))
    report.fail(j, "machine_model", fmt::format("the report was measured on machine '{}' ({}); {} is '{}' ({}): a "
                                                "compensation is for the machine that was measured",
                                                name, kin, machine_file, machine.name,
                                                kinematicsName(machine.kinematics)));
}

// When the report was analyzed, and whether that is old; empty when it is not.
std::string reportAgeNote(const JsonDoc& report, double now_s) {
  const Json& j = report.value;
  if (!j.is_object() || !j.contains("analyzed_utc") || !j["analyzed_utc"].is_string())
    return report.file + " records no date (analyze records one since this version): how old it is is not known";
  double t = 0.0;
  try {
    t = parseIsoTime(j["analyzed_utc"].get<std::string>());
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

}  // namespace

CompensationInputs compensationInputs(const std::vector<JsonDoc>& reports, const std::optional<MachineModel>& machine,
                                      bool force, const ReportChecks& checks) {
  CompensationInputs in;
  if (machine) {
    in.machine = *machine;
    for (const auto& r : reports) requireSameMachine(r, in.machine, checks.machine_file);
  } else {
    const JsonDoc& report = reports.front();
    if (report.value.is_object() && report.value.contains("machine_model"))
      in.machine = machineFromJson(report, report.value["machine_model"]);
    else
      report.fail(report.value, "", "the report does not carry its machine ('machine_model', written by analyze since "
                                    "this version): give --machine MACHINE.json");
  }
  for (const std::string& h : checks.table_holds) {
    bool known = false;
    for (const auto& r : in.machine.rotary)
      for (const auto& n : componentErrorNames(r.name)) known = known || n == h;
    if (!known)
      throw UnknownHeldError("'" + h + "' is no component error of this machine's rotary axes (e.g. ECC: the C "
                                  "axis's angular positioning)");
  }
  in.read = errorsFromReports(reports, in.machine.kinematics, force, checks.table_holds);
  if (checks.now_s)
    for (const auto& r : reports)
      if (const std::string age = reportAgeNote(r, *checks.now_s); !age.empty()) in.read.notes.push_back(age);
  const GeometricErrors& errors = in.read.errors;
  // The reports' paths are outside text: the dialect's comment form keeps only its safe characters.
  for (const auto& s : in.read.sources) in.header.push_back(s);
  std::string values = "location errors:";
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const auto& p = locationParameters(in.machine.kinematics)[i];
    values += fmt::format("{} {} {:.2f} {}", i == 0 ? "" : ",", p.name, errors.location.reportValue(i), reportUnit(p.kind));
  }
  in.header.push_back(values);
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
    in.header.push_back(line);
  }
  for (const auto& n : in.read.notes) in.header.push_back(n);
  return in;
}

ProgramCompensation compensateVerified(const std::string& text, const std::string& program_file, const std::string& out,
                                       const std::string& dialect, const NcSyntax& syntax, const CompensationInputs& in,
                                       const ProgramCompensationOptions& options) {
  ProgramCompensation r = compensateProgram(text, program_file, in.machine, in.read.errors, syntax, options);
  // A program without a probing move is a part program: checked as one (the tool's point against
  // the table; no probe, no calibration artefact on the table), from its own zero. A probing
  // program keeps the probing checks.
  bool probing = false;
  for (const auto& m : ctl::readMotions(dialect, text)) probing = probing || m.kind == nc::Motion::Kind::Probe;
  r.part_program = !probing;
  const std::optional<Eigen::Vector3d> part =
      probing ? std::nullopt : std::optional<Eigen::Vector3d>(options.program_origin_m_mm);
  // The input, on the nominal machine it was written for: what makes it unsafe is named at its
  // own line (the rewrite's lines are not the user's).
  requireSafeProgram(text, program_file, dialect, in.machine, nullptr, false, nullptr, part);
  // The program verifier (`rotacal check`) on the rewrite, before it is written: the guards follow
  // their moves, strokes, clearances on the machine's set-up - the machine with the errors it is
  // compensated for, where it keeps its planned gaps. The input's program number is kept.
  requireSafeProgram(r.text, out, dialect, in.machine, nullptr, false, &in.read.errors, part);
  return r;
}

std::vector<std::string> compensateMessages(const CompensationInputs& in, const ProgramCompensation& r,
                                            const std::string& out, double max_deviation_um) {
  std::vector<std::string> lines;
  for (const auto& n : in.read.notes) lines.push_back(fmt::format("compensate: note: {}\n", n));
  if (r.part_program)
    lines.push_back("compensate: a part program (no probing move): checked as one, the tool's point against the table, "
                    "no probe and no calibration artefact\n");
  lines.push_back(fmt::format("compensate: {} of {} motion blocks rewritten ({} left as written: machine-coordinate moves or "
                              "before every axis was known); largest shift {:.2f} um, largest rotary change {:.2f} mdeg, tool "
                              "direction not restorable by the rotary axes up to {:.2f} urad; {} no-trigger check statements "
                              "moved with their probing moves (up to {:.2f} um) -> {}\n",
                              r.compensated_blocks, r.motion_blocks, r.uncompensated_blocks, mmToUm(r.max_shift_mm),
                              r.max_rotary_change_deg * 1000.0, r.max_direction_residual_rad * 1e6, r.rewritten_checks,
                              mmToUm(r.max_check_shift_mm), out));
  lines.push_back(fmt::format("compensate: {} feed moves split into {} more lines (a move unsplit would leave the nominal path by "
                              "up to {:.3f} um; written: {:.3f} um, tolerance {:.3f} um)\n",
                              r.split_blocks, r.added_blocks, mmToUm(r.max_unsplit_deviation_mm),
                              mmToUm(r.max_path_deviation_mm), max_deviation_um));
  if (in.read.errors.location_covariance)
    lines.push_back(fmt::format("compensate: the identification's uncertainty leaves the compensated tool point uncertain by "
                                "up to {:.2f} um (k = 2) at this program's end points\n",
                                2.0 * mmToUm(r.max_position_u_mm)));
  return lines;
}

}  // namespace rotacal
