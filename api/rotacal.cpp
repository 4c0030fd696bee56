// The public library (include/rotacal/rotacal.hpp): a translation of its plain types to the
// internal ones and back. The work itself is the command line's (tasks/), so that the library
// and `rotacal compensate` / `rotacal check` cannot drift apart.
#include "rotacal/rotacal.hpp"

#include <cstdio>
#include <exception>
#include <string>
#include <utility>

#include "controllers/dialect.hpp"
#include "core/compensation.hpp"
#include "core/error_model.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/units.hpp"
#include "postproc/report_errors.hpp"
#include "tasks/compensate.hpp"
#include "tasks/one_line.hpp"
#include "tasks/program_safety.hpp"

namespace rotacal {

namespace {

std::string located(const std::string& input, int line, const std::string& why) {
  return oneLine(input.empty() ? why : input + ":" + std::to_string(line) + ": " + why);
}

// Every internal exception leaves the library as Error: a post catches one type, and the
// internal ones are not exported (their type information would not match across the boundary).
template <class F>
auto translated(F&& work) -> decltype(work()) {
  try {
    return work();
  } catch (const Error&) {
    throw;
  } catch (const InputError& e) {
    const std::string prefix = e.file() + ":" + std::to_string(e.line()) + ": ";
    const std::string what = e.what();
    throw Error(e.file(), e.line(), what.compare(0, prefix.size(), prefix) == 0 ? what.substr(prefix.size()) : what);
  } catch (const std::exception& e) {
    throw Error("", 0, e.what());
  }
}

std::vector<JsonDoc> parsed(const std::vector<NamedText>& texts) {
  std::vector<JsonDoc> docs;
  for (const auto& t : texts) docs.push_back(parseJsonText(t.text, t.name));
  return docs;
}

std::optional<MachineModel> machineOf(const std::optional<NamedText>& machine) {
  if (!machine) return std::nullopt;
  const JsonDoc doc = parseJsonText(machine->text, machine->name);
  return machineFromJson(doc, doc.value);
}

CompensationInputs inputsOf(const std::vector<NamedText>& reports, const std::optional<NamedText>& machine, bool force,
                            const ReportChecks& checks = {}) {
  if (reports.empty()) throw Error("", 0, "no report: give at least one REPORT.json of analyze");
  const std::vector<JsonDoc> docs = parsed(reports);
  return compensationInputs(docs, machineOf(machine), force, checks);
}

std::string withoutLineEnd(std::string s) {
  while (!s.empty() && s.back() == '\n') s.pop_back();
  return s;
}

// The value as a program prints it (4 decimals) and the control reads it back.
double printed(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.4f", v);
  const double r = std::stod(text);
  return r == 0.0 ? 0.0 : r;  // no "-0.0000"
}

double& axis(Pose& q, char name) { return name == 'A' ? q.A : name == 'B' ? q.B : q.C; }
double axis(const Pose& q, char name) { return name == 'A' ? q.A : name == 'B' ? q.B : q.C; }

}  // namespace

Error::Error(const std::string& input, int line, const std::string& why)
    : std::runtime_error(located(input, line, why)), input_(input), line_(line) {}

Error::~Error() = default;

std::string version() { return ROTACAL_VERSION_STRING; }

CompensateResult compensate(const CompensateRequest& request) {
  return translated([&] {
    if (!(request.max_deviation_um >= 0.001 && request.max_deviation_um <= 1000.0))
      throw Error("", 0, "max_deviation_um " + std::to_string(request.max_deviation_um) + " is outside [0.001, 1000]");
    const NcSyntax syntax = ncSyntaxOf(request.dialect);
    ReportChecks checks;
    checks.table_holds = request.table_holds;
    checks.now_s = request.now_unix_s;
    if (request.machine) checks.machine_file = request.machine->name;
    const CompensationInputs in = inputsOf(request.reports, request.machine, request.force, checks);
    ProgramCompensationOptions opt;
    const auto& o = request.program_origin_mm;
    opt.program_origin_m_mm = Eigen::Vector3d(o[0], o[1], o[2]);
    opt.subdivision.max_deviation_mm = umToMm(request.max_deviation_um);
    opt.header = in.header;
    const ProgramCompensation r = compensateVerified(request.program.text, request.program.name, request.output_name,
                                                     request.dialect, syntax, in, opt);
    CompensateResult out;
    out.text = r.text;
    out.motion_blocks = r.motion_blocks;
    out.compensated_blocks = r.compensated_blocks;
    out.uncompensated_blocks = r.uncompensated_blocks;
    out.rewritten_checks = r.rewritten_checks;
    out.split_blocks = r.split_blocks;
    out.added_blocks = r.added_blocks;
    out.max_shift_um = mmToUm(r.max_shift_mm);
    out.max_rotary_change_mdeg = r.max_rotary_change_deg * 1000.0;
    out.max_direction_residual_urad = r.max_direction_residual_rad * 1e6;
    out.max_check_shift_um = mmToUm(r.max_check_shift_mm);
    out.max_unsplit_deviation_um = mmToUm(r.max_unsplit_deviation_mm);
    out.max_path_deviation_um = mmToUm(r.max_path_deviation_mm);
    if (in.read.errors.location_covariance) out.position_uncertainty_k2_um = 2.0 * mmToUm(r.max_position_u_mm);
    out.notes = in.read.notes;
    for (const auto& line : compensateMessages(in, r, request.output_name, request.max_deviation_um))
      out.messages.push_back(withoutLineEnd(line));
    return out;
  });
}

CheckResult check(const CheckRequest& request) {
  return translated([&] {
    if (const Dialect& d = dialectByName(request.dialect); !d.hasPrograms())
      throw Error("", 0, std::string(d.name()) + " has no NC programs to check");
    const std::optional<MachineModel> machine = machineOf(request.machine);
    const ProgramCheckResult r =
        verifyProgram(request.program.text, request.dialect, *machine, nullptr, request.rotacal_program);
    CheckResult out;
    for (const auto& v : r.violations) out.violations.push_back({v.line, v.problem});
    out.motion_blocks = r.motion_blocks;
    out.probing_moves = r.probing_moves;
    out.obstacles = r.obstacles;
    out.min_clearance_mm = r.min_clearance_mm;
    out.required_gap_mm = r.required_gap_mm;
    if (out.violations.empty()) out.summary = withoutLineEnd(checkSummary(request.program.name, request.program.text, r));
    return out;
  });
}

struct Compensator::State {
  MachineModel machine;
  GeometricErrors errors;
  std::array<char, 2> rotary{};
  std::array<int, 2> sign{1, 1};
};

Compensator::Compensator(const std::vector<NamedText>& reports, const std::string& dialect,
                         const std::optional<NamedText>& machine, bool force) {
  state_ = translated([&] {
    const CompensationInputs in = inputsOf(reports, machine, force);
    auto s = std::make_shared<State>();
    s->machine = in.machine;
    s->errors = in.read.errors;
    if (s->machine.rotary.size() != 2)
      throw Error("", 0, reports.front().name + ": the machine has not two rotary axes");
    for (int i = 0; i < 2; ++i) {
      s->rotary[i] = s->machine.rotary[i].name;
      if (!dialect.empty()) s->sign[i] = s->machine.controllerSign(s->rotary[i], dialect);
    }
    return std::shared_ptr<const State>(std::move(s));
  });
}

Compensator::~Compensator() = default;
Compensator::Compensator(const Compensator&) = default;
Compensator& Compensator::operator=(const Compensator&) = default;

std::string Compensator::machineName() const { return state_->machine.name; }

std::string Compensator::kinematics() const { return std::string(kinematicsName(state_->machine.kinematics)); }

std::array<char, 2> Compensator::rotaryAxes() const { return state_->rotary; }

std::vector<ErrorValue> Compensator::locationErrors() const {
  std::vector<ErrorValue> out;
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const auto& p = locationParameters(state_->machine.kinematics)[i];
    out.push_back({std::string(p.name), state_->errors.location.reportValue(i), std::string(reportUnit(p.kind))});
  }
  return out;
}

std::vector<ComponentErrorSummary> Compensator::componentErrors() const {
  std::vector<ComponentErrorSummary> out;
  for (const auto& c : state_->errors.components) out.push_back({c.axis, c.angle_deg.size()});
  return out;
}

CompensatedPose Compensator::compensate(const MachinePose& nominal) const {
  return translated([&] {
    const State& s = *state_;
    const Eigen::Vector3d x(nominal.x, nominal.y, nominal.z);
    // The nominal pose in the papers' convention, and the compensated one.
    Pose q;
    for (int i = 0; i < 2; ++i) axis(q, s.rotary[i]) = s.sign[i] * nominal.angles[i];
    const CompensatedCommand cc = compensatePose(s.errors, q);
    // The angles as they will be printed, and the position for exactly those: what the control
    // will be told.
    Pose q_cmd = q;
    CompensatedPose out;
    for (int i = 0; i < 2; ++i) {
      out.pose.angles[i] = printed(s.sign[i] * axis(cc.pose, s.rotary[i]));
      axis(q_cmd, s.rotary[i]) = s.sign[i] * out.pose.angles[i];
      const RotaryAxis& a = s.machine.rotaryAxis(s.rotary[i]);
      if (!a.continuous && !a.stroke_deg.contains(axis(q_cmd, s.rotary[i])))
        throw Error("", 0, std::string("the compensated ") + s.rotary[i] + " is outside its stroke in MACHINE.json");
    }
    const Eigen::Vector3d x_cmd = compensatedPosition(s.errors, q, x, q_cmd);
    out.pose.x = x_cmd[0];
    out.pose.y = x_cmd[1];
    out.pose.z = x_cmd[2];
    out.shift_um = (x_cmd - x).norm() * 1000.0;
    out.tool_direction_residual_urad = toolDirectionError(s.errors, q_cmd, q) * 1e6;
    return out;
  });
}

}  // namespace rotacal
