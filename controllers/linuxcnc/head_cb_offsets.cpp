// LinuxCNC's offsets of a head_cb machine (5axiskins, the bridge mill): what the kinematics
// module and the work offset can hold of the one-sphere cycle's parameters, and where the rest
// goes. 5axiskins (LinuxCNC 2.9, switchkins type 0) puts the tool tip at
//   pivot + Lp (sin B cos C, sin B sin C, -cos B),   Lp = the HAL pin 5axiskins.pivot-length,
// its B counted against rotacal's (ISO 841: the head turns by +angle, the ball at
// Rz(C) Ry(B) (0, 0, -L)); C alike. The module has one pin: the pivot-to-tip length.
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "controllers/linuxcnc/hal.hpp"
#include "controllers/offsets.hpp"
#include "controllers/text.hpp"
#include "core/machine.hpp"
#include "core/units.hpp"

namespace rotacal {

namespace {

constexpr const char* kComponent = "5axiskins";
constexpr const char* kDialect = "linuxcnc";

const ParameterEstimate& find(const OffsetRequest& r, const std::string& name) {
  for (const auto& p : r.parameters)
    if (p.name == name) return p;
  throw std::invalid_argument("head_cb offsets: the analysis carries no parameter '" + name + "'");
}

// The plausibility limit of every correction (controllers/offsets.hpp), on the model's parameters.
void requirePlausibleHead(const OffsetRequest& r) {
  if (!r.plan) throw std::invalid_argument("offset request without a plan");
  if (r.plan->machine.kinematics != Kinematics::HeadCB || r.identified.kinematics != Kinematics::HeadCB)
    throw std::invalid_argument("identified errors are for another kinematics than the plan's machine");
  if (r.parameters.empty()) throw std::invalid_argument("head_cb offsets: the analysis carries no parameters");
  for (const auto& p : r.parameters) {
    if (!std::isfinite(p.value)) throw std::invalid_argument(p.name + " is not a finite number; nothing written");
    if (r.force) continue;
    if (p.kind == ParamKind::Length && std::abs(p.value) > ctl::kMaxLengthCorrectionMm)
      throw std::invalid_argument(fmt::format("{} = {:.4f} mm exceeds the plausibility limit of {} mm: check the setup "
                                              "and the results, or force it",
                                              p.name, p.value, ctl::kMaxLengthCorrectionMm));
    if (p.kind == ParamKind::Angle && std::abs(radToMdeg(p.value)) > ctl::kMaxAngleCorrectionMdeg)
      throw std::invalid_argument(fmt::format("{} = {:.1f} mdeg exceeds the plausibility limit of {} mdeg: check the "
                                              "setup and the results, or force it",
                                              p.name, radToMdeg(p.value), ctl::kMaxAngleCorrectionMdeg));
  }
}

std::vector<std::string> parameterLines(const OffsetRequest& r) {
  std::vector<std::string> out;
  for (const auto& p : r.parameters) {
    const bool len = p.kind == ParamKind::Length;
    const double v = len ? mmToUm(p.value) : radToMdeg(p.value), u = len ? mmToUm(p.u) : radToMdeg(p.u);
    out.push_back(p.held ? fmt::format("{:<6} held at 0: not separable by one sphere", p.name)
                         : fmt::format("{:<6} {:>10} {:<4} +- {} {}", p.name, ctl::fixed(v, 3), reportUnit(p.kind),
                                       std::isfinite(u) ? ctl::fixed(u, 3) : std::string("?"), reportUnit(p.kind)));
  }
  return out;
}

// The parameters no LinuxCNC form holds, and their route.
std::vector<std::string> reportedOnly(const OffsetRequest& r, const std::set<std::string>& written) {
  std::string names;
  for (const auto& p : r.parameters) {
    if (p.held || written.count(p.name) || (p.name.rfind("d", 0) == 0 && p.name.back() == 'S')) continue;
    if (p.name == "dR" || p.name.rfind("S_", 0) == 0 || p.name.rfind("backlash_", 0) == 0 || p.name.rfind("lead_in_", 0) == 0)
      continue;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  return {"Reported only: " + names + ":",
          "  5axiskins has no pins for the axes' places and tilts (its C axis passes through the pivot, its B axis",
          "  crosses C there). Route: a kinematics module with the axes' geometry (REPORT.json's",
          "  kinematic_parameters by hand) or a mechanical adjustment; rotacal compensate rewrites table machines'",
          "  programs only. Held at 0 (one sphere cannot see them): the head's place X0C Y0C Z0B (read as the",
          "  sphere's), C0B (read with C0C) and dX_T (read with B0B)."};
}

}  // namespace

std::string linuxcncHeadCbHal(const OffsetRequest& r) {
  requirePlausibleHead(r);
  const MachineModel& m = r.plan->machine;
  const ParameterEstimate& dl = find(r, "dL");
  const auto previous = parseHalSetp(r.previous_text, kComponent);
  const auto it = previous.find("pivot-length");
  // Without a previous file the module holds what the plan assumed: MACHINE.json's length.
  const double old = it == previous.end() ? m.head->pivot_to_ball_mm : it->second;
  const bool inch = m.units == LengthUnit::Inch;
  const double k = inch ? 1.0 / kMmPerInch : 1.0;  // the pin is in the machine's linear unit
  std::string out;
  auto line = [&](const std::string& s) { out += s + "\n"; };
  line("# rotacal: pivot length of 5axiskins (LinuxCNC HAL file), a head_cb machine (C head carrying a B head)");
  line("# What it changes: 5axiskins.pivot-length, the pivot-to-tip length 5axiskins uses in TCP mode");
  line("#   (tip = pivot + pivot-length (sin B cos C, sin B sin C, -cos B)). Replace the same setp line of your");
  line(fmt::format("#   HAL file (or load this file after the kinematics module). Values in {}.", inch ? "inch" : "mm"));
  line(ctl::printableLine(fmt::format("# Provenance: {}; cycle {}, machine {}.",
                                      r.report_file.empty() ? "(no report)" : r.report_file, r.plan->cycle, m.name)));
  line("# Identified parameters (ISO 230-7, rotacal's head_cb chain, docs/conventions.md), value +- u (k = 1):");
  for (const auto& s : parameterLines(r)) line("#   " + s);
  line("# Mapping: pivot-length += dL (the ball's distance from the pivot along the spindle less nominal).");
  line("#   One sphere cannot tell the pivot's length from the probe's: where the pin is fed by the sum of a");
  line("#   mechanical length and motion.tooloffset.z (LinuxCNC's 5axisgui.hal), put the change into whichever");
  line("#   of the two is off (the constant, or the probe's tool length); this setp then fails (a fed pin).");
  line(fmt::format("# {:<12} {:>12} {:>12} {:>12}", "pin", "previous", "change", "new"));
  line(fmt::format("# {:<12} {:>12} {:>12} {:>12}{}", "pivot-length", ctl::fixed(old, 6), ctl::fixed(dl.value * k, 6),
                   ctl::fixed(old + dl.value * k, 6),
                   it == previous.end() ? "  (no previous value: MACHINE.json's pivot_to_ball_mm assumed)" : ""));
  line(fmt::format("setp {}.pivot-length {}", kComponent, ctl::fixed(old + dl.value * k, 6)));
  // Lines of the previous file that this file does not replace are kept as they were.
  std::vector<std::string> kept;
  for (const auto& l : ctl::splitLines(r.previous_text)) {
    const std::string s = ctl::trim(l.text);
    if (s.empty() || s[0] == '#') continue;
    const auto t = ctl::tokens(s);
    if (t.size() >= 2 && t[0] == "setp" && t[1] == std::string(kComponent) + ".pivot-length") continue;
    kept.push_back(s);
  }
  if (!kept.empty()) {
    line("# Kept unchanged from the previous file:");
    for (const auto& s : kept) line(s);
  }
  line("#");
  line("# B and C zeros (B0B, C0C): not HAL pins; the work offset holds them (an offsets file named *.ngc).");
  for (const auto& s : reportedOnly(r, {"dL", "B0B", "C0C"})) line("# " + s);
  return out;
}

std::string linuxcncHeadCbWorkOffsets(const OffsetRequest& r) {
  requirePlausibleHead(r);
  const MachineModel& m = r.plan->machine;
  // The head turns by +angle: commanding C' = C - C0C puts the head at C (the chain's Rz(C0C)
  // Rz(C')), likewise B. With machine = program + offset, the offset is -C0C, -B0B, in the
  // controller's count of each axis.
  std::map<char, double> change;
  for (const char axis : {'B', 'C'}) {
    const ParameterEstimate& zero = find(r, std::string(1, axis) + "0" + axis);
    change[axis] = m.controllerSign(axis, kDialect) * -radToDeg(zero.value);
  }
  const std::map<char, double> previous = previousWorkOffset(r.previous_text, "BC");
  std::string out;
  // rs274ngc comments: no parentheses inside, at most 200 characters each (dialect.cpp's limit),
  // never starting like an active comment (MSG, LOG, ...): each piece starts with "- ".
  auto line = [&](const std::string& s) {
    std::string c;
    for (char ch : ctl::printableLine(s)) c += ch == '(' ? '[' : ch == ')' ? ']' : ch;
    for (const auto& piece : ctl::wrap(c, 190)) out += "(- " + piece + ")\n";
  };
  out += "%\n";
  line("rotacal: the B and C zeros of a head_cb machine as the G54 work offset [LinuxCNC]");
  line(fmt::format("Provenance: {}; cycle {}, machine {}", r.report_file.empty() ? "no report" : r.report_file,
                   r.plan->cycle, m.name));
  line("Run it once before the cycle; it changes G54's B and C only. Identified, ISO 230-7, k = 1:");
  for (const auto& s : parameterLines(r)) line(s);
  line(fmt::format("Mapping: G54 B += {:+d} x -B0B, C += {:+d} x -C0C [deg, the controller's count]",
                   m.controllerSign('B', kDialect), m.controllerSign('C', kDialect)));
  line("B0B carries the ball's offset across the spindle [dX_T / L]: check the probe's run-out first");
  line("X Y Z unchanged: the head's place X0C Y0C Z0B reads as the sphere's, which one sphere cannot tell apart");
  line("dL: 5axiskins.pivot-length [a .hal file]; the axes' places and tilts: no LinuxCNC pin or offset holds them");
  const WorkOffsetChange w = workOffsetChange("BC", previous, change, [](char) { return 6; });
  for (const auto& s : w.steps) line(s);
  out += w.g10 + "\n";
  out += "M2\n%\n";
  return out;
}

}  // namespace rotacal
