// `rotacal comp-table`: the third compensation route (docs/compensation.md). Reads the angular
// positioning error of a rotary axis from a REPORT.json (its component_errors: ECC for C)
// and writes it as the controller's own axis / pitch compensation table
// (controllers/comp_table.hpp, docs/dialects.md "Compensation tables").
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/command.hpp"
#include "cli/output.hpp"
#include "controllers/comp_table.hpp"
#include "controllers/text.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"

namespace rotacal {
namespace {

// ---- Reading the report. The shared reader (postproc/report_errors.hpp: errorsFromReports) takes
// a report's location errors too and checks every component error; the table needs E_CC alone,
// from any report that carries it, with messages about E_CC. ----

/// The angular positioning error of `axis` (E<axis><axis>, e.g. ECC) from a REPORT.json's
/// `component_errors` (per ISO name: c_deg, values, u, unit). Every problem is an InputError at
/// the line of the offending value.
ctl::AngularPositionErrors angularErrorFromReport(const JsonDoc& report, char axis) {
  const Json& root = report.value;
  if (!root.is_object()) report.fail(root, "", "not a REPORT.json (expected a JSON object)");
  const std::string name = fmt::format("E{0}{0}", axis);
  if (!root.contains("component_errors"))
    report.fail(root, "", "the report has no component_errors (the angular positioning error " + name +
                              " comes from a cycle that identifies the component errors of C, e.g. the three-sphere cycle's analyze)");
  const Json& ce = root["component_errors"];
  if (!ce.is_object()) report.fail(root, "component_errors", "component_errors must be an object of ISO names");
  if (!ce.contains(name))
    report.fail(root, "component_errors", "component_errors has no " + name + " (the angular positioning error of " +
                                              std::string(1, axis) + ")");
  const Json& e = ce[name];
  if (!e.is_object()) report.fail(ce, name, name + " must be an object with c_deg, values, u and unit");
  const std::string unit = requireString(report, e, "unit");
  if (unit != "mdeg") report.fail(e, "unit", name + " must be in mdeg, not '" + unit + "'");
  auto numbersOf = [&](std::string_view key, bool required) {
    std::vector<double> v;
    if (!e.contains(key)) {
      if (required) report.fail(e, "", fmt::format("{} has no '{}'", name, key));
      return v;
    }
    const Json& a = e[std::string(key)];
    if (!a.is_array()) report.fail(e, key, fmt::format("{}.{} must be an array of numbers", name, key));
    if (a.size() > 360) report.fail(e, key, fmt::format("{}.{} has {} entries: at most 360 angles", name, key, a.size()));
    for (const auto& x : a) {
      if (!x.is_number() || !std::isfinite(x.get<double>()))
        report.fail(e, key, fmt::format("{}.{} holds '{}', not a finite number", name, key, x.dump()));
      v.push_back(x.get<double>());
    }
    return v;
  };
  ctl::AngularPositionErrors out;
  out.axis = axis;
  out.angle_deg = numbersOf("c_deg", true);
  out.error_mdeg = numbersOf("values", true);
  out.u_mdeg = numbersOf("u", false);
  if (out.error_mdeg.size() != out.angle_deg.size())
    report.fail(e, "values", fmt::format("{}: {} values for {} angles (c_deg)", name, out.error_mdeg.size(),
                                         out.angle_deg.size()));
  if (!out.u_mdeg.empty() && out.u_mdeg.size() != out.angle_deg.size())
    report.fail(e, "u", fmt::format("{}: {} uncertainties for {} angles (c_deg)", name, out.u_mdeg.size(),
                                    out.angle_deg.size()));
  for (double u : out.u_mdeg)
    if (u < 0) report.fail(e, "u", fmt::format("{}: a negative uncertainty ({} mdeg)", name, u));
  try {
    ctl::PeriodicInterpolant check(out.angle_deg, out.error_mdeg);
  } catch (const std::invalid_argument& ex) {
    report.fail(e, "c_deg", name + ": " + ex.what());
  }
  return out;
}

// ----

int cmdCompTable(const Common& c, const std::string& report_file, const std::string& dialect, const std::string& axis_text,
                 const std::string& machine_file, double step_deg, const std::string& out, bool force,
                 bool write_insignificant) {
  if (const std::string why = ctl::compTableRefusal(dialect); !why.empty()) throw CLI::ValidationError("--dialect", why);
  if (step_deg != 0.0)
    if (const std::string why = ctl::stepRefusal(step_deg); !why.empty()) throw CLI::ValidationError("--step-deg", why);
  if (axis_text != "C")
    throw CLI::ValidationError("--axis", "'" + axis_text + "': only the C axis' angular positioning error (ECC) is "
                                                           "in a report so far");
  const char axis = 'C';
  std::vector<std::string> inputs = {report_file};
  if (!machine_file.empty()) inputs.push_back(machine_file);
  checkOutputs({{"-o", out}}, inputs);  // -o on an input is a usage error, before anything is read
  const JsonDoc report = readJsonFile(report_file);
  const ctl::AngularPositionErrors errors = guardJson(report, [&] { return angularErrorFromReport(report, axis); });
  MachineModel machine;
  if (!machine_file.empty()) {
    machine = loadMachine(machine_file);
  } else if (report.value.contains("machine_model")) {
    machine = machineFromJson(report, report.value["machine_model"]);
  } else {
    report.fail(report.value, "", "the report does not carry its machine ('machine_model', written by analyze): give "
                                  "--machine MACHINE.json (it says how the control counts the axis)");
  }
  // A table of pure noise turns the axis by what the measurement cannot tell from zero: written
  // only on request. Significant: beyond its expanded uncertainty U = 2 u (about 95 %) at one
  // angle at least.
  if (!write_insignificant && !errors.u_mdeg.empty()) {
    bool beyond = false;
    for (size_t i = 0; i < errors.error_mdeg.size(); ++i)
      beyond = beyond || std::abs(errors.error_mdeg[i]) > 2.0 * errors.u_mdeg[i];
    if (!beyond)
      failFile(out, fmt::format("not written: E{0}{0} lies within its expanded uncertainty (2 u) at every angle of "
                                "{1}: the table would turn the axis by noise (--write-insignificant writes it anyway)",
                                axis, report_file));
  }
  const std::string machine_src = machine_file.empty() ? report_file : machine_file;
  if (!machine.hasRotary(axis))
    failFile(machine_src, fmt::format("the machine has no rotary axis {}", axis));
  const RotaryAxis& ra = machine.rotaryAxis(axis);
  ctl::CompTableRequest req;
  req.errors = errors;
  req.dialect = dialect;
  req.controller_sign = machine.controllerSign(axis, dialect);
  req.step_deg = step_deg;
  if (!ra.continuous && ra.stroke_deg.max - ra.stroke_deg.min < 1e6) {
    const double a = req.controller_sign * ra.stroke_deg.min, b = req.controller_sign * ra.stroke_deg.max;
    req.range_lo_deg = std::min(a, b);
    req.range_hi_deg = std::max(a, b);
  }
  req.source = report_file;
  req.force = force;
  ctl::CompTable table;
  try {
    table = ctl::writeCompTable(req);
  } catch (const std::invalid_argument& ex) {
    const Json& ce = report.value["component_errors"];
    report.fail(ce, fmt::format("E{0}{0}", axis), ex.what());
  }
  writeFileAtomic(out, table.text);
  std::string text = fmt::format("comp-table: {} {} table of E{}{} ({} angles identified): {} rows, {} to {} deg, largest "
                                 "error {:.4f} mdeg -> {}\n",
                                 dialect, axis, axis, axis, errors.angle_deg.size(), table.rows.size(),
                                 ctl::fixed(table.rows.front().controller_deg, 3),
                                 ctl::fixed(table.rows.back().controller_deg, 3), table.max_error_mdeg, out);
  for (const auto& s : table.setup) text += "  set: " + s + "\n";
  // The other route must not apply it again (docs/compensation.md: each error once).
  text += fmt::format("  with this table loaded, compensate programs with `--table-holds E{0}{0}`: the table applies "
                      "E{0}{0} to every program\n",
                      axis);
  say(c, text);
  return 0;
}

}  // namespace

std::vector<Command> compTableCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string report, dialect, axis = "C", machine, out;
    double step_deg = 0.0;
    bool force = false, write_insignificant = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("comp-table",
                                 "write a rotary axis' angular positioning error as the controller's compensation table");
  cmd->add_option("--report", a->report, "REPORT.json with component_errors (ECC)")->required();
  cmd->add_option("--dialect", a->dialect, "linuxcnc | fanuc | siemens | csv (heidenhain, okuma, haas: refused)")
      ->required();
  cmd->add_option("--axis", a->axis, "the rotary axis (C: ECC)");
  cmd->add_option("--machine", a->machine, "MACHINE.json (default: the machine recorded in the report)");
  cmd->add_option("--step-deg", a->step_deg, "table spacing in deg, dividing 360 (default 5)");
  cmd->add_option("-o,--output", a->out, "FILE: the table")->required();
  cmd->add_flag("--force", a->force, "write an error beyond the plausibility limit (100 mdeg)");
  cmd->add_flag("--write-insignificant", a->write_insignificant,
                "write the table although the error lies within its expanded uncertainty at every angle");
  return {{cmd, [a, &common] {
             return cmdCompTable(common, a->report, a->dialect, a->axis, a->machine, a->step_deg, a->out, a->force,
                                 a->write_insignificant);
           }}};
}

}  // namespace rotacal
