// LinuxCNC 2.9 (rs274ngc): G38.2 probing with an explicit #5070 check, results through
// (LOGOPEN,...)/(LOG,...), compensation as trt-kins HAL pins (../shared/reference/controllers.md
// Sec. 1) or, for an offsets file named *.ngc, as the G54 shift of 000 Sec. 4.5 (G10 L2 P1).
// With the machine's retract_mm > 0 each point is a double touch: G38.3 at the probing feed
// (checked by #5070), a relative back-off, and the recorded G38.2 at the slow feed. Both forms
// run unchanged on a real LinuxCNC in tests/e2e/linuxcnc (docs/e2e-linuxcnc.md).
//
// Results line per point, written by the program's LOG comment:
//   P<id> <#5061 %.6f> <#5062> <#5063> <rotary %.4f ...> <#5070 %d>
// in the current work coordinates (G54 = rotary-axis intersection) and program units.
// No time: LinuxCNC has no clock parameter unless HAL_PIN_VARS exposes
// #<_hal[motion-controller.time]>, which is not portable across configurations, so t_s = NaN.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <stdexcept>

#include "controllers/comp_table.hpp"
#include "controllers/linuxcnc/hal.hpp"
#include "controllers/offsets.hpp"
#include "controllers/program_checking.hpp"
#include "controllers/program_writing.hpp"
#include "controllers/result_checks.hpp"
#include "controllers/results_lines.hpp"
#include "controllers/text.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace ctl {
namespace {

constexpr int kLinuxcncMaxEntries = 256;  // EMCMOT_COMP_SIZE (ini-config: "256 triplets per joint")

/// Paper-convention angle of `axis` in a pose.
double poseAngle(const Pose& pose, char axis) {
  switch (axis) {
    case 'A': return pose.A;
    case 'B': return pose.B;
    default: return pose.C;
  }
}

// The rotary compensation table in this control's form (controllers/comp_table.hpp).
CompTable compTable(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  double lo = r.range_lo_deg, hi = r.range_hi_deg;
  if (!(lo < hi)) lo = -360.0, hi = 360.0;
  lo = std::floor(lo / step + 1e-9) * step;  // a grid point, not beyond the range it covers
  hi = std::ceil(hi / step - 1e-9) * step;
  const long count = std::lround((hi - lo) / step) + 1;
  if (count > kLinuxcncMaxEntries)
    throw std::invalid_argument(fmt::format("{} table lines from {} to {} deg every {} deg: LinuxCNC takes at most {} per joint (choose a larger "
                    "--step-deg)",
                    count, fixed(lo, 3), fixed(hi, 3), fixed(step, 4), kLinuxcncMaxEntries));
  const CompTableGrid g = compTableGrid(E, r.controller_sign, lo, step, static_cast<int>(count));
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  for (const auto& row : g.rows) {
    const std::string actual = fixed(row.controller_deg + row.error_deg, 6);
    t.text += fmt::format("{} {} {}\n", fixed(row.controller_deg, 6), actual, actual);
  }
  // After the data: LinuxCNC's loader stops at the first line that is not three numbers.
  for (const auto& l : compTableProvenance(r, E, step)) t.text += "# " + l + "\n";
  t.text += "# columns: nominal (commanded) joint position, actual position moving up, actual moving down (deg)\n";
  t.text += "# LinuxCNC commands nominal - actual more; COMP_FILE_TYPE = 0; BACKLASH is then ignored\n";
  t.text += "# after start-up turn the axis through one full revolution: the correction is then followed\n";
  t.setup = {fmt::format("INI, the [JOINT_n] section of axis {}: COMP_FILE = <this file> and COMP_FILE_TYPE = 0 "
                         "(BACKLASH of that joint is then not used)",
                         r.errors.axis),
             "after start-up turn the axis through one full revolution before measuring or cutting: LinuxCNC 2.9 "
             "applies the correction only while the joint moves, and from rest it did not take a step of 3 mdeg "
             "(observed); over a turn the correction passes zero and is followed from there on"};
  return t;
}

}  // namespace
}  // namespace ctl

namespace {

constexpr const char* kFormat = "rotacal-results/1";
constexpr const char* kDialect = "linuxcnc";
/// Rotary positions logged with a point must match its pose within this (deg): the log prints 4
/// decimals and the axes stand still while probing.
constexpr double kRotaryLogTolDeg = 1e-3;
/// LinuxCNC rejects a line of 253 characters or more ("Command too long"; LINELEN 255 in
/// src/emc/linuxcnc.h, verified with rs274: 252 accepted, 253 rejected).
constexpr size_t kMaxLineChars = 252;
constexpr size_t kMaxCommentChars = 200;  // a comment's text, with room for a "- " guard and code before it
constexpr int kOwordBase = 1000;
/// The second touch's check of a double touch: its own o-number (o-words label one if/endif).
constexpr int kSecondTouchOwordBase = 500000;
/// R-test (002): o-words of the repeat loops, the digital output that triggers the R-test
/// logger, and its pulse length (s).
constexpr int kRepeatOwordBase = 900000;
constexpr int kReadOutput = 0;
constexpr double kReadPulseS = 0.2;

int parameterOf(char axis) { return axis == 'A' ? 5064 : axis == 'B' ? 5065 : 5066; }

/// Comment text safe for rs274ngc: no parentheses, no control characters, and never an active
/// comment keyword (MSG, DEBUG, LOG, ...) by accident.
std::string comment(std::string_view text) {
  std::string s;
  for (char c : ctl::printableLine(text)) {
    if (c == '(') s += '[';
    else if (c == ')') s += ']';
    else s += c;
  }
  const std::string u = ctl::upper(ctl::trim(s));
  for (const char* kw : {"MSG", "DEBUG", "PRINT", "LOG", "PROBEOPEN", "PROBECLOSE", "ABORT", "PY"}) {
    const size_t n = std::string_view(kw).size();
    if (u.compare(0, n, kw) == 0 && (u.size() == n || u[n] == ',' || u[n] == ' ' || u[n] == '<')) {
      s = "- " + s;
      break;
    }
  }
  if (s.size() > kMaxCommentChars) s.resize(kMaxCommentChars);
  return "(" + s + ")";
}

std::string unitName(bool inch) { return inch ? "inch" : "mm"; }

DialectIdentity linuxcncIdentity() {
  DialectIdentity d;
  d.language = ProgramLanguage::IsoGcode;
  d.comp_table = ctl::compTable;  // G38.2 raises an error by itself: no end-point check
  return d;
}

class LinuxCncDialect final : public Dialect {
 public:
  LinuxCncDialect() : Dialect(linuxcncIdentity()) {}
  std::string_view name() const override { return kDialect; }
  std::string_view programExtension() const override { return ".ngc"; }
  std::string_view resultsExtension() const override { return ".txt"; }

  // A named parameter local to the program (LinuxCNC: its scope ends with the program): read by
  // nothing, it changes nothing on the machine.
  std::string compensationMark() const override { return "#<rotacal_compensated> = 1"; }

  std::vector<std::string> commentLines(std::string_view text) const override {
    std::vector<std::string> out;
    // 2 characters spare for the "- " guard of comment().
    for (const auto& piece : ctl::wrap(ctl::printableLine(text), kMaxCommentChars - 2)) out.push_back(comment(piece));
    if (out.empty()) out.push_back("()");
    return out;
  }

  std::string writeProgram(const nc::Program& p) const override {
    const bool inch = p.unit == nc::Unit::Inch;
    const int dl = inch ? 5 : 4;                              // length decimals
    auto L = [&](double v) { return ctl::fixed(v, dl); };
    auto Ang = [](double v) { return ctl::fixed(v, 4); };     // degrees
    auto F = [&](double v) { return ctl::fixed(v, inch ? 3 : 1); };
    const int probes = ctl::probeCount(p);
    const std::string results = p.results_file.empty() ? std::string("rotacal_results") : p.results_file;
    if (results.find_first_of(" \t(),;") != std::string::npos)
      throw std::invalid_argument("results file name '" + results + "' must not contain spaces, parentheses, ',' or ';'");
    if (p.cycle.find_first_of(" \t()") != std::string::npos)
      throw std::invalid_argument("cycle name '" + p.cycle + "' must not contain spaces or parentheses");

    std::string out;
    auto line = [&](const std::string& s) { ctl::appendLine(out, s, kMaxLineChars); };
    line("%");
    line(comment(fmt::format("{}: generated by rotacal, dialect linuxcnc", p.name)));
    for (const auto& h : p.header) line(comment(h));
    line(comment("machine coordinates: run with identity [joint] kinematics, not TCP; G54 as the work offset line "
                 "above says, 0 for the rotary axes"));
    line(comment(fmt::format("results: {}.txt [a relative name lands next to the INI file], one LOG line per point, "
                             "no time",
                             results)));
    line(comment("an untriggered G38.2 raises an error; the o-if blocks below also ABORT with the point id"));
    line(inch ? "G20" : "G21");
    line("G17 G40 G49 G54 G61 G80 G90 G94");
    if (p.probe_tool > 0) {
      line(fmt::format("T{} M6", p.probe_tool));
      line(fmt::format("G43 H{}", p.probe_tool));
    }
    // LOGOPEN must be alone on its line: LinuxCNC acts only on the last comment of a line.
    line(fmt::format("(LOGOPEN,{}.txt)", results));
    line(fmt::format("(LOG,{} dialect={} cycle={} points={} unit={})", kFormat, kDialect, p.cycle, probes,
                     unitName(inch)));
    std::string log_rotary;
    for (char a : p.rotary_axes) log_rotary += fmt::format(" %.4f#{}", parameterOf(a));
    ctl::ModeGuard guard;
    std::vector<int> repeats;  // open o-word repeat blocks
    int next_repeat = 0;
    for (const auto& op : p.ops) {
      const Eigen::Vector3d& x = op.xyz;
      guard.apply(op);
      switch (op.kind) {
        case nc::Op::Kind::Comment: line(comment(op.text)); break;
        case nc::Op::Kind::Rapid:
          line(op.z_only ? fmt::format("G0 Z{}", L(x.z())) : fmt::format("G0 X{} Y{} Z{}", L(x.x()), L(x.y()), L(x.z())));
          break;
        case nc::Op::Kind::Linear:
          line(fmt::format("G1 X{} Y{} Z{} F{}", L(x.x()), L(x.y()), L(x.z()), F(op.feed)));
          break;
        case nc::Op::Kind::Index: {
          // feed > 0: a rotary move at that feed (deg/min under G94: the R-test reciprocation)
          std::string s = op.feed > 0 ? "G1" : "G0";
          for (const auto& [axis, deg] : op.rotary) s += fmt::format(" {}{}", axis, Ang(deg));
          if (op.feed > 0) s += " F" + ctl::fixed(op.feed, 1);
          line(s);
          break;
        }
        case nc::Op::Kind::Mode: line(ctl::isoModeBlock(op)); break;
        case nc::Op::Kind::RotaryLinear: line(ctl::rotaryLinearWords(op, p.unit, "")); break;
        case nc::Op::Kind::Pause:
          if (op.dwell_s > 0) line(fmt::format("G4 P{}", ctl::trimmed(op.dwell_s, 3)));  // P: seconds
          else line("M0 " + comment(op.text.empty() ? "program stop" : op.text));
          break;
        case nc::Op::Kind::Dwell:
          if (!(op.seconds >= 0)) throw std::invalid_argument("dwell must be >= 0 s");
          line("G4 P" + ctl::fixed(op.seconds, 3));
          break;
        case nc::Op::Kind::Read:
          // R-test reading: a pulse on motion.digital-out-00 (wired to the R-test logger's
          // trigger input) while the machine stands still after the dwell.
          if (!op.text.empty()) line(comment(op.text));
          line(fmt::format("M64 P{}", kReadOutput));
          line("G4 P" + ctl::fixed(kReadPulseS, 3));
          line(fmt::format("M65 P{}", kReadOutput));
          break;
        case nc::Op::Kind::RepeatBegin:
          if (op.count < 1) throw std::invalid_argument(fmt::format("repeat count {} must be >= 1", op.count));
          repeats.push_back(kRepeatOwordBase + next_repeat++);
          line(fmt::format("o{} repeat [{}]", repeats.back(), op.count));
          break;
        case nc::Op::Kind::RepeatEnd:
          if (repeats.empty()) throw std::invalid_argument("repeat end without a repeat");
          line(fmt::format("o{} endrepeat", repeats.back()));
          repeats.pop_back();
          break;
        case nc::Op::Kind::Probe: {
          if (op.point_id <= 0) throw std::invalid_argument("probing move without a point id");
          if (!(op.feed > 0)) throw std::invalid_argument(fmt::format("point {}: probing feed must be > 0", op.point_id));
          const int o = kOwordBase + op.point_id;
          if (!op.text.empty()) line(comment(op.text));
          if (op.retract_mm > 0) {
            // Double touch (fast, back off, slow; the slow one is recorded): LinuxCNC samples the
            // probe once per servo period, so a trigger lies up to feed x period past the contact.
            // The first touch is G38.3 so that a piece that is not there stops the program with
            // our ABORT naming the point (G38.2 would stop it with the controller's generic
            // "G38.2 move finished without making contact"); the #5070 check makes it as strict.
            if (!(op.slow_feed > 0))
              throw std::invalid_argument(fmt::format("point {}: double touch needs a slow feed > 0", op.point_id));
            const Eigen::Vector3d d = x - op.nominal_trigger;  // end = trigger + overtravel x approach
            if (!(d.norm() > 1e-9))
              throw std::invalid_argument(
                  fmt::format("point {}: double touch needs the nominal trigger before the end point", op.point_id));
            const Eigen::Vector3d back = -op.retract_mm * d.normalized();
            line(fmt::format("G38.3 X{} Y{} Z{} F{}", L(x.x()), L(x.y()), L(x.z()), F(op.feed)));
            line(fmt::format("o{} if [#5070 NE 1]", o));
            line(fmt::format("(ABORT, rotacal: point {} did not trigger)", op.point_id));
            line(fmt::format("o{} endif", o));
            // relative back-off from where the first touch stopped, against the approach
            line(fmt::format("G91 G0 X{} Y{} Z{}", L(back.x()), L(back.y()), L(back.z())));
            line("G90");
            line(fmt::format("G38.2 X{} Y{} Z{} F{}", L(x.x()), L(x.y()), L(x.z()), F(op.slow_feed)));
            line(fmt::format("o{} if [#5070 NE 1]", kSecondTouchOwordBase + op.point_id));
            line(fmt::format("(ABORT, rotacal: point {} did not trigger on the second touch)", op.point_id));
            line(fmt::format("o{} endif", kSecondTouchOwordBase + op.point_id));
          } else {
            line(fmt::format("G38.2 X{} Y{} Z{} F{}", L(x.x()), L(x.y()), L(x.z()), F(op.feed)));
            line(fmt::format("o{} if [#5070 NE 1]", o));
            line(fmt::format("(ABORT, rotacal: point {} did not trigger)", op.point_id));
            line(fmt::format("o{} endif", o));
          }
          line(fmt::format("(LOG,P{} %.6f#5061 %.6f#5062 %.6f#5063{} %d#5070)", op.point_id, log_rotary));
          break;
        }
      }
    }
    if (!repeats.empty()) throw std::invalid_argument("a repeat without its end");
    line("(LOGCLOSE)");
    line("M2");
    line("%");
    return out;
  }

  std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const override {
    const MachineModel& m = plan.machine;
    const bool inch = m.units == LengthUnit::Inch;
    const double k = inch ? 1.0 / kMmPerInch : 1.0;
    std::string out = fmt::format("{} dialect={} cycle={} points={} unit={}\n", kFormat, kDialect, plan.cycle,
                                  plan.points.size(), unitName(inch));
    for (const auto& t : run.points) {
      const ProbePoint* p = plan.findPoint(t.point_id);
      if (!p) throw std::invalid_argument(fmt::format("run point {} is not in the plan", t.point_id));
      const Eigen::Vector3d x = t.position_m_mm * k;
      out += fmt::format("P{} {} {} {}", t.point_id, ctl::fixed(x.x(), 6), ctl::fixed(x.y(), 6), ctl::fixed(x.z(), 6));
      for (const auto& r : m.rotary)
        out += " " + ctl::fixed(m.controllerSign(r.name, kDialect) * ctl::poseAngle(p->pose, r.name), 4);
      out += " 1\n";
    }
    return out;
  }

  MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const override {
    const size_t n_rot = plan.machine.rotary.size();
    const size_t n_fields = 4 + n_rot + 1;
    std::string expected_line = "P<id> x y z";
    for (const auto& r : plan.machine.rotary) expected_line += std::string(" ") + static_cast<char>(std::tolower(r.name));
    expected_line += " ok";
    const std::string expected_header =
        fmt::format("{} dialect={} cycle={} points={} unit=mm|inch", kFormat, kDialect, plan.cycle, plan.points.size());

    ctl::requireText(text, file);
    ctl::PointCollector points(plan, file);
    bool header = false;
    double k = 1.0;
    int last = 1;
    for (const auto& l : ctl::splitLines(text)) {
      const auto t = ctl::tokens(l.text);
      if (t.empty()) continue;
      last = l.number;
      if (t[0] == kFormat) {
        if (header) ctl::fail(file, l.number, "a second header line: one run per results file");
        header = true;
        std::map<std::string, std::string> kv;
        for (size_t i = 1; i < t.size(); ++i) {
          const size_t eq = t[i].find('=');
          if (eq == std::string::npos || eq == 0)
            ctl::fail(file, l.number, fmt::format("header field '{}' is not key=value", t[i]));
          kv[t[i].substr(0, eq)] = t[i].substr(eq + 1);
        }
        for (const auto& [key, value] : kv)
          if (key != "dialect" && key != "cycle" && key != "points" && key != "unit")
            ctl::fail(file, l.number, fmt::format("unknown header field '{}'", key));
        for (const char* key : {"dialect", "cycle", "points", "unit"})
          if (!kv.count(key))
            ctl::fail(file, l.number, fmt::format("header lacks '{}=': expected '{}'", key, expected_header));
        if (kv["dialect"] != kDialect)
          ctl::fail(file, l.number, fmt::format("results of dialect '{}', expected '{}'", kv["dialect"], kDialect));
        if (kv["cycle"] != plan.cycle)
          ctl::fail(file, l.number, fmt::format("results of cycle '{}', the plan is '{}'", kv["cycle"], plan.cycle));
        const auto n = ctl::parseDigits(kv["points"]);
        if (!n) ctl::fail(file, l.number, fmt::format("points='{}' is not a number", kv["points"]));
        if (static_cast<size_t>(*n) != plan.points.size())
          ctl::fail(file, l.number,
                    fmt::format("header says points={} but the plan has {} points", *n, plan.points.size()));
        if (kv["unit"] == "mm") k = 1.0;
        else if (kv["unit"] == "inch") k = kMmPerInch;
        else ctl::fail(file, l.number, fmt::format("unit '{}' must be mm or inch", kv["unit"]));
        continue;
      }
      if (!header)
        ctl::fail(file, l.number, fmt::format("expected the header '{}', got '{}'", expected_header, ctl::trim(l.text)));
      if (t[0].size() < 2 || t[0][0] != 'P')
        ctl::fail(file, l.number, fmt::format("expected '{}', got '{}'", expected_line, ctl::trim(l.text)));
      const auto id = ctl::parseDigits(std::string_view(t[0]).substr(1));
      if (!id || *id == 0) ctl::fail(file, l.number, fmt::format("'{}' is not a point id P<n>", t[0]));
      if (t.size() != n_fields)
        ctl::fail(file, l.number,
                  fmt::format("expected {} fields '{}', got {}", n_fields, expected_line, t.size()));
      Eigen::Vector3d x;
      for (size_t i = 0; i < 3 + n_rot; ++i) {
        const auto v = ctl::parseNumber(t[1 + i]);
        if (!v) ctl::fail(file, l.number, fmt::format("'{}' (field {} of point {}) is not a number", t[1 + i], i + 2, *id));
        if (i < 3) {
          x[static_cast<int>(i)] = *v * k;
          continue;
        }
        // The logged rotary position must be the point's planned pose (in the controller's
        // sign): a line of another plan or pose would otherwise pass on its coordinates alone.
        // 1 mdeg covers the 4 printed decimals; a continuous axis may log any turn.
        const RotaryAxis& r = plan.machine.rotary[i - 3];
        const ProbePoint* p = plan.findPoint(static_cast<int>(*id));
        if (!p) continue;  // PointCollector names the unknown id
        const double planned = plan.machine.controllerSign(r.name, kDialect) * ctl::poseAngle(p->pose, r.name);
        double diff = *v - planned;
        if (r.continuous) diff = std::remainder(diff, 360.0);
        if (!(std::abs(diff) <= kRotaryLogTolDeg))
          ctl::fail(file, l.number,
                    fmt::format("point {} was logged at {} = {} deg, but its pose commands {} = {} deg", *id, r.name,
                                t[1 + i], r.name, ctl::fixed(planned, 4)));
      }
      const std::string& ok = t[n_fields - 1];
      if (ok == "0") ctl::fail(file, l.number, fmt::format("point {} was not triggered (#5070 = 0)", *id));
      if (ok != "1")
        ctl::fail(file, l.number, fmt::format("trigger flag '{}' of point {} must be 1 (or 0: not triggered)", ok, *id));
      points.add(l.number, static_cast<int>(*id), x, std::numeric_limits<double>::quiet_NaN());
    }
    if (!header) ctl::fail(file, 1, fmt::format("empty results file: expected the header '{}'", expected_header));
    return points.finish(last);
  }

  std::string writeOffsets(const OffsetRequest& r) const override {
    if (r.identified.kinematics == Kinematics::HeadTable)
      return endsWithNgc(r.path) ? writeHeadWorkOffsetProgram(r) : writeMaxkinsHal(r);
    if (r.identified.kinematics == Kinematics::HeadCB)
      return endsWithNgc(r.path) ? linuxcncHeadCbWorkOffsets(r) : linuxcncHeadCbHal(r);
    if (endsWithNgc(r.path)) return writeWorkOffsetProgram(r);
    ctl::requirePlausible(r);
    const ProbePlan& plan = *r.plan;
    const MachineModel& m = plan.machine;
    const bool ac = r.identified.kinematics == Kinematics::TableAC;
    const bool ab = r.identified.kinematics == Kinematics::TableAB;
    const std::string comp = linuxcncKinsComponent(r.identified.kinematics);
    const auto changes = linuxcncKinsChanges(r.identified);
    const auto previous = parseHalSetp(r.previous_text, comp);
    const char tilt = tableTiltAxis(r.identified.kinematics);
    const std::string zero_param = ac ? "a_AY" : "b_BY";
    const double zero_deg = m.hasRotary(tilt) ? m.controllerSign(tilt, kDialect) * radToDeg(r.identified.get(zero_param))
                                              : 0.0;

    std::string out;
    auto line = [&](const std::string& s) { out += s + "\n"; };
    line(fmt::format("# rotacal: rotary-axis geometry of {} (LinuxCNC HAL file)", comp));
    line(ab ? std::string("# What it changes: the rotation point of the B axis and the A axis's offset from it used by the")
            : "# What it changes: the rotation point of the C axis and the offset of the " + std::string(1, tilt) +
                  " pivot used by the");
    line(fmt::format("#   {} kinematics in TCP mode. Replace the same setp lines of your HAL file (or load this", comp));
    line("#   file after the kinematics module) and restart LinuxCNC. Values in mm, machine coordinates.");
    // A '#' comment ends at the line end: outside names must not carry one.
    line(ctl::printableLine(fmt::format("# Provenance: {}; cycle {}, machine {}.",
                                        r.report_file.empty() ? "(no report)" : r.report_file, plan.cycle, m.name)));
    line("# Identified location errors (papers' convention), value +- standard uncertainty (k = 1):");
    for (const auto& s : ctl::identifiedLines(r)) line("#   " + s);
    if (ab) {
      // xyzab_tdr_kins (type 1) turns a table point p to R + Ry(-B) (D + Rx(-A) (p - R - D)), R the
      // rot-point and D = (x-offset, 0, z-offset): the B line through R, the A line through R + D
      // in B's frame. x-offset lies along A's own line and moves nothing.
      line("# Mapping (mm): x-rot-point += dx_BY, y-rot-point += dy_AB, z-rot-point += dz_BY,");
      line("#   z-offset += dz_AB: the B axis passes through rot-point, the A axis through rot-point +");
      line("#   (x-offset, 0, z-offset) in the B axis's frame.");
    } else if (ac) {
      line("# Mapping (mm): x-rot-point += dx_AY, y-rot-point += dy_AY + dy_CA, z-rot-point += dz_AY,");
      line("#   y-offset += -dy_CA, z-offset += 0: A pivot = rot-point + offset = (dx_AY, dy_AY, dz_AY),");
      line("#   the C axis passes through rot-point.");
    } else {
      line("# Mapping (mm): x-rot-point += dx_BY + dx_CB, y-rot-point += dy_CB, z-rot-point += dz_BY,");
      line("#   x-offset += -dx_CB, z-offset += 0: B pivot = rot-point + offset = (dx_BY, dy_CB, dz_BY),");
      line("#   the C axis passes through rot-point. (B/C mapping by analogy with A/C: UNVERIFIED on a machine.)");
    }
    line(fmt::format("# {:<12} {:>12} {:>12} {:>12}", "pin", "previous", "change", "new"));
    std::set<std::string> written;
    std::vector<std::string> setp;
    for (const auto& [pin, delta] : changes) {
      const auto it = previous.find(pin);
      const double old = it == previous.end() ? 0.0 : it->second;
      line(fmt::format("# {:<12} {:>12} {:>12} {:>12}{}", pin, ctl::fixed(old, 6), ctl::fixed(delta, 6),
                       ctl::fixed(old + delta, 6), it == previous.end() ? "  (no previous value: 0 assumed)" : ""));
      setp.push_back(fmt::format("setp {}.{} {}", comp, pin, ctl::fixed(old + delta, 6)));
      written.insert(pin);
    }
    for (const auto& s : setp) line(s);
    // Lines of the previous file that this file does not replace are kept as they were.
    std::vector<std::string> kept;
    for (const auto& l : ctl::splitLines(r.previous_text)) {
      const std::string s = ctl::trim(l.text);
      if (s.empty() || s[0] == '#') continue;
      const auto t = ctl::tokens(s);
      if (t.size() >= 2 && t[0] == "setp" && t[1].rfind(comp + ".", 0) == 0 && written.count(t[1].substr(comp.size() + 1)))
        continue;
      kept.push_back(s);
    }
    if (!kept.empty()) {
      line("# Kept unchanged from the previous file:");
      for (const auto& s : kept) line(s);
    }
    line("#");
    line(fmt::format("# {} zero ({}): not a HAL pin. Shift the {} axis work offset by MDI:", tilt, zero_param, tilt));
    line(fmt::format("#   G10 L2 P1 {}{}", tilt, ctl::fixed(zero_deg, 6)));
    line(fmt::format("#   (value for a G54 {} offset that is 0 now; if it already holds a correction use", tilt));
    line(fmt::format("#   G10 L2 P1 {}[#{} + {}] instead). Controller sign of {} for linuxcnc: {:+d}.", tilt,
                     5221 + (tilt - 'A') + 3, ctl::fixed(zero_deg, 6), tilt,
                     m.hasRotary(tilt) ? m.controllerSign(tilt, kDialect) : 1));
    if (ab) {
      line("# Reported only: a_BY, c_BY (orientation of the B axis) and c_AB (squareness of A to B about Z) cannot be");
      line("#   held by xyzab_tdr_kins: it has no pins for tilted axes. Route: rotacal compensate (the program");
      line("#   rewritten for all eight), or a mechanical adjustment.");
      return out;
    }
    line(ac ? "# Reported only: b_AY, c_AY (orientation of the A axis) and b_CA (squareness of C to A) cannot be"
            : "# Reported only: a_BY, c_BY (orientation of the B axis) and a_CB (squareness of C to B) cannot be");
    line("#   applied by shifting a pivot or a zero: trt-kins has no pins for tilted axes. They need a mechanical");
    line("#   adjustment or a kinematics module with axis directions.");
    return out;
  }

  /// A B head over a C table on maxkins (a .hal file): its one pin, pivot-length, the distance from
  /// the B head's pivot to the point its TCP kinematics controls, += dL. Read back from the running
  /// module (tests/e2e/linuxcnc, docs/e2e-linuxcnc.md): joint 0 = x' - L sin B, joint 2 = z' + L cos B
  /// - L, (x', y', z') the tip turned by -C, L = pivot-length (tool length 0).
  std::string writeMaxkinsHal(const OffsetRequest& r) const {
    const HeadWriteBack h(r);
    const auto previous = parseHalSetp(r.previous_text, "maxkins");
    const auto it = previous.find("pivot-length");
    const double old = it == previous.end() ? h.m.head->pivot_to_ball_mm : it->second;
    const double dl = h.value("dL");
    std::string out;
    auto line = [&](const std::string& s) { out += s + "\n"; };
    line("# rotacal: the B head's pivot length of maxkins (LinuxCNC HAL file)");
    line("# What it changes: maxkins.pivot-length, the distance from the B head's pivot to the point its TCP");
    line("#   kinematics controls (the ball centre, tool length 0), which maxkins turns about the pivot. Replace");
    line("#   the same setp line of your HAL file (or load this file after maxkins) and restart LinuxCNC. mm.");
    line(ctl::printableLine(fmt::format("# Provenance: {}; cycle {}, machine {}.",
                                        r.report_file.empty() ? "(no report)" : r.report_file, h.plan.cycle,
                                        h.m.name)));
    line("# Identified kinematic parameters (head_table, ISO 230-7), value +- standard uncertainty (k = 1):");
    for (const auto& s : ctl::identifiedLines(r)) line("#   " + s);
    line("# Mapping (mm): pivot-length += dL (the ball dL farther from the pivot than nominal). maxkins' Z reads");
    line("#   the tip at B = 0 (joint 2 = z + L cos B - L): a Z set by touching the ball off at B = 0 already holds");
    line("#   its height there; a Z counted from the pivot, as rotacal's machine file counts it, moves by dL too");
    line("#   (G54 Z += dL).");
    line(fmt::format("# {:<12} {:>12} {:>12} {:>12}", "pin", "previous", "change", "new"));
    line(fmt::format("# {:<12} {:>12} {:>12} {:>12}{}", "pivot-length", ctl::fixed(old, 6), ctl::fixed(dl, 6),
                     ctl::fixed(old + dl, 6),
                     it == previous.end() ? "  (no previous value: MACHINE.json's pivot_to_ball_mm assumed)" : ""));
    line(fmt::format("setp maxkins.pivot-length {}", ctl::fixed(old + dl, 6)));
    std::vector<std::string> kept;
    for (const auto& l : ctl::splitLines(r.previous_text)) {
      const std::string s = ctl::trim(l.text);
      if (s.empty() || s[0] == '#') continue;
      const auto t = ctl::tokens(s);
      if (t.size() >= 2 && t[0] == "setp" && t[1] == "maxkins.pivot-length") continue;
      kept.push_back(s);
    }
    if (!kept.empty()) {
      line("# Kept unchanged from the previous file:");
      for (const auto& s : kept) line(s);
    }
    line("#");
    line("# Not HAL pins: the C axis's place (X0C, Y0C) and the B axis's zero (B0B). The work offset holds them");
    line("#   (an offsets file named *.ngc), by MDI for a G54 that is 0 now:");
    line(fmt::format("#   G10 L2 P1 X{} Y{} B{}", ctl::fixed(h.work('X'), 6), ctl::fixed(h.work('Y'), 6),
                     ctl::fixed(h.work('B'), 6)));
    line(fmt::format("#   (B = {:+d} x B0B: the controller sign of B for linuxcnc is {:+d}, the head turns by +B)",
                     -h.sign_b, h.sign_b));
    line("# Reported only: A0C, B0C (orientation of the C axis) and A0B, C0B (orientation of the B head) cannot be");
    line("#   held by maxkins: it has no pins for tilted axes. Route: a mechanical adjustment, or a kinematics");
    line("#   with axis directions (rotacal compensate rewrites table machines' programs only).");
    line("# dX_S, dY_S, dZ_S: the sphere's set-up on the table, the artefact's place, not the machine's.");
    line("# Held at nominal, one sphere cannot separate them (REPORT.json unseparable): " + h.heldList() +
         "; X0C reads relative to X0B.");
    return out;
  }

  /// A B head over a C table (an offsets file named *.ngc): the work offset, which acts in every
  /// kinematics, holds what is a shift of the program: the C axis's place (X0C, Y0C: the table,
  /// and the sphere on it, displaced by d is seen at d - offset, machine = program + offset) and
  /// the B head's zero (the head turns by +(B* + B0B) and B* = sign x B: B += -sign x B0B).
  std::string writeHeadWorkOffsetProgram(const OffsetRequest& r) const {
    const HeadWriteBack h(r);
    const bool inch = h.m.units == LengthUnit::Inch;
    const double k = inch ? 1.0 / kMmPerInch : 1.0;
    const int dl = inch ? 7 : 6;
    const std::map<char, double> previous = previousWorkOffset(r.previous_text, "XYB");
    const std::map<char, double> change{{'X', h.work('X') * k}, {'Y', h.work('Y') * k}, {'B', h.work('B')}};
    std::string out;
    auto line = [&](const std::string& s) { out += s + "\n"; };
    line("%");
    line(comment("rotacal: the work-offset route of a B head over a C table, G54 [LinuxCNC]"));
    line(comment(fmt::format("Provenance: {}; cycle {}, machine {}",
                             r.report_file.empty() ? "no report" : r.report_file, h.plan.cycle, h.m.name)));
    line(comment("Run it once before the cycle; it changes G54 only. Identified, head_table ISO 230-7, k = 1:"));
    for (const auto& s : ctl::identifiedLines(r)) line(comment(s));
    line(comment(
        fmt::format("Mapping: G54 X += X0C, Y += Y0C [{}], B += {:+d} x B0B [deg]", unitName(inch), -h.sign_b)));
    line(comment("Not applied [no shift expresses them]: dL [maxkins' pivot-length, a .hal file], A0C, B0C, A0B, C0B "
                 "[a mechanical adjustment]; the sphere's set-up dX_S dY_S dZ_S is the artefact's"));
    line(comment("Held at nominal [one sphere cannot separate them]: " + h.heldList() + "; X0C reads relative to X0B"));
    const WorkOffsetChange w = workOffsetChange("XYB", previous, change, [dl](char axis) { return axis == 'B' ? 6 : dl; });
    for (const auto& s : w.steps) line(comment(s));
    line(inch ? "G20" : "G21");
    line(w.g10);
    line("M2");
    line("%");
    return out;
  }

  /// What both head_table forms read: the request checked (plausible, a B head over a C table)
  /// and the identified values by name.
  struct HeadWriteBack {
    explicit HeadWriteBack(const OffsetRequest& r)
        : req((ctl::requirePlausible(r), r)), plan(*r.plan), m(plan.machine),
          sign_b(m.hasRotary('B') ? m.controllerSign('B', kDialect) : 1) {
      if (!m.head || m.head->axis != 'B' || !m.hasRotary('B') || !m.hasRotary('C'))
        throw std::invalid_argument("LinuxCNC's maxkins is a B head over a C table: rotacal writes its offsets for "
                                    "that head_table machine only (head.axis B, rotary axes B and C)");
      for (const char* n : {"X0C", "Y0C", "B0B", "dL"})
        if (!ctl::kinematicParameter(r, n))
          throw std::invalid_argument(fmt::format("head_table offsets without {}", n));
    }
    double value(const char* name) const {
      const ParameterEstimate* p = ctl::kinematicParameter(req, name);
      return p && !p->held ? p->value : 0.0;
    }
    /// The work offset's change of axis X, Y (mm) or B (deg, the controller's count).
    double work(char axis) const {
      if (axis == 'X') return value("X0C");
      if (axis == 'Y') return value("Y0C");
      return -sign_b * radToDeg(value("B0B"));
    }
    std::string heldList() const {
      std::string out;
      for (const auto& p : req.parameters)
        if (p.held) out += (out.empty() ? "" : ", ") + p.name;
      return out.empty() ? std::string("none") : out;
    }
    const OffsetRequest& req;
    const ProbePlan& plan;
    const MachineModel& m;
    int sign_b;
  };

  static bool endsWithNgc(const std::string& path) {
    return path.size() >= 4 && ctl::upper(path.substr(path.size() - 4)) == ".NGC";
  }

  /// The shift route of 000 Sec. 4.5 as an NGC program (an offsets file named *.ngc): the G54
  /// work offset moves by (dx_AY, dy_AY, dz_AY) and the A axis zero by a_AY. Why this form: the
  /// generated cycle runs in identity (joint) kinematics, where the xyzac-trt-kins pins do
  /// nothing; a work offset acts in every kinematics, and it is what 000 applies. With
  /// machine = program + offset, a table displaced by d is seen at d - offset; the A zero shift
  /// o_A turns the table by the controller's sign times o_A, so o_A = sign x a_AY cancels a_AY
  /// (exactly for the translations, to second order in the small angles for a_AY).
  std::string writeWorkOffsetProgram(const OffsetRequest& r) const {
    ctl::requirePlausible(r);
    const MachineModel& m = r.plan->machine;
    // The A/C table's route, and the A/B and B/C tables': their B axis sits on the bed as A does
    // there, so the work offset moves B's place (X, Z) and B's zero alike (with machine = program +
    // offset); a shift along B's own line (Y) moves only the axis it carries: A's (dy_AB), C's (dy_CB).
    const Kinematics kin = r.identified.kinematics;
    const bool ab = kin == Kinematics::TableAB;
    const bool bc = kin == Kinematics::TableBC;
    const char tilt = tableTiltAxis(kin);
    if ((kin != Kinematics::TableAC && !ab && !bc) || !m.hasRotary(tilt))
      throw std::invalid_argument(
          "the G10 work-offset form (.ngc) is written for A/C, A/B and B/C tables only; use a .hal file");
    const char* px = ab || bc ? "dx_BY" : "dx_AY";
    const char* py = ab ? "dy_AB" : bc ? "dy_CB" : "dy_AY";
    const char* pz = ab || bc ? "dz_BY" : "dz_AY";
    const char* pzero = ab || bc ? "b_BY" : "a_AY";
    const bool inch = m.units == LengthUnit::Inch;
    const double k = inch ? 1.0 / kMmPerInch : 1.0;  // mm -> program units
    const int dl = inch ? 5 : 4;
    // Previous offsets: the G10 L2 P1 line of the file this one replaces (the loop accumulates).
    const std::map<char, double> previous = previousWorkOffset(r.previous_text, std::string("XYZ") + tilt);
    const int sign_a = m.controllerSign(tilt, kDialect);
    const std::map<char, double> change{{'X', r.identified.get(px) * k},
                                        {'Y', r.identified.get(py) * k},
                                        {'Z', r.identified.get(pz) * k},
                                        {tilt, sign_a * radToDeg(r.identified.get(pzero))}};
    std::string out;
    auto line = [&](const std::string& s) { out += s + "\n"; };
    line("%");
    line(comment("rotacal: 000 Sec. 4.5 shift route as the G54 work offset [LinuxCNC]"));
    line(comment(fmt::format("Provenance: {}; cycle {}, machine {}", r.report_file.empty() ? "no report" : r.report_file,
                             r.plan->cycle, m.name)));
    line(comment("Run it once before the cycle; it changes G54 only. Identified, papers' convention, k = 1:"));
    for (const auto& s : ctl::identifiedLines(r)) line(comment(s));
    line(comment(fmt::format("Mapping: G54 X += {}, Y += {}, Z += {} [{}], {} += {:+d} x {} [deg]", px, py, pz,
                             unitName(inch), tilt, sign_a, pzero)));
    line(comment(ab   ? "Not applied [no shift expresses them]: dz_AB, a_BY, c_BY, c_AB: xyzab_tdr_kins' z-offset "
                        "[a .hal file] holds dz_AB, rotacal compensate all four"
                 : bc ? "Not applied [no shift expresses them]: dx_CB, a_BY, c_BY, a_CB: rotacal compensate holds "
                        "all four"
                      : "Not applied [no shift expresses them]: dy_CA, b_AY, c_AY, b_CA"));
    const WorkOffsetChange w = workOffsetChange(std::string("XYZ") + tilt, previous, change,
                                                [dl, tilt](char axis) { return axis == tilt ? 6 : dl + 2; });
    for (const auto& s : w.steps) line(comment(s));
    line(inch ? "G20" : "G21");
    line(w.g10);
    line("M2");
    line("%");
    return out;
  }

  std::vector<std::string> check(const std::string& text, const ProbePlan& plan, const nc::Shape& shape) const override {
    const auto blocks = nc::readProgram(text);
    std::vector<std::string> out = ctl::readerIssues(blocks);
    auto problem = [&](int line, const std::string& what) { out.push_back(fmt::format("{}: {}", line, what)); };
    int probes = 0;
    bool logopen = false;
    for (size_t i = 0; i < blocks.size(); ++i) {
      const nc::Block& b = blocks[i];
      if (b.raw.size() > kMaxLineChars)
        problem(b.line, fmt::format("line has {} characters; LinuxCNC rejects more than {} ('Command too long')",
                                    b.raw.size(), kMaxLineChars));
      for (const auto& c : b.comments) {
        const std::string u = ctl::upper(ctl::trim(c));
        if (u.rfind("LOG", 0) == 0) {
          if (b.comments.size() > 1)
            problem(b.line, "a LOG comment shares its line with another comment (only the last comment is acted on)");
          if (u.rfind("LOGOPEN", 0) == 0 || u.rfind("LOGAPPEND", 0) == 0) {
            const size_t n = u.rfind("LOGOPEN", 0) == 0 ? 7 : 9;
            if (u.size() <= n || u[n] != ',') problem(b.line, "LOGOPEN needs a comma: (LOGOPEN,file)");
            logopen = true;
          } else if (u.rfind("LOG,", 0) == 0 && !logopen) {
            problem(b.line, "LOG before LOGOPEN");
          }
        }
      }
      // What the verifier cannot follow is not passed (docs/safety.md): a subroutine's moves are
      // never seen, and a loop may never end (rotacal writes o-word IFs only).
      if (b.control && !b.oword.empty()) {
        const std::string& k = b.keyword;
        if (k == "CALL" || k == "SUB" || k == "ENDSUB" || k == "RETURN")
          problem(b.line, fmt::format("o{} {}: a subroutine the verifier cannot follow", b.oword, ctl::lower(k)));
        else if (k == "WHILE" || k == "ENDWHILE" || k == "DO" || k == "BREAK" || k == "CONTINUE")
          problem(b.line, fmt::format("o{} {}: a loop the verifier cannot bound", b.oword, ctl::lower(k)));
        else if (k == "REPEAT") {
          // An R-test's repeat [n] with a literal count ends; its body returns to where it started.
          static const std::regex counted(R"(^O\s*\S+\s+REPEAT\s*\[\s*\d+\s*\]\s*$)");
          if (!std::regex_match(ctl::upper(b.code), counted))
            problem(b.line,
                    fmt::format("o{} repeat without a literal count: a loop the verifier cannot bound", b.oword));
        }
      }
      if (!b.control)
        for (const auto& [letter, code] : {std::pair{'M', 98}, {'M', 99}})
          if (b.hasWord(letter, code))
            problem(b.line, fmt::format("{}{}: a subprogram call the verifier cannot follow", letter, code));
      if (b.control || b.words.empty()) continue;
      // G38.4/G38.5 probe away from the piece; G38.3 does not stop the program by itself, which
      // the #5070 check below makes up for (the double touch's first touch uses it).
      for (double g : {38.4, 38.5})
        if (b.hasWord('G', g)) problem(b.line, fmt::format("G{} does not stop the program without contact: use G38.2", g));
      const bool g382 = b.hasWord('G', 38.2), g383 = b.hasWord('G', 38.3);
      if (!g382 && !g383) continue;
      const std::string g = g382 ? "G38.2" : "G38.3";
      // A recorded touch: a probing move whose position is LOGged before the next probing move.
      for (size_t k = i + 1; k < blocks.size(); ++k) {
        const nc::Block& d = blocks[k];
        if (!d.control && (d.hasWord('G', 38.2) || d.hasWord('G', 38.3))) break;
        bool logged = false;
        for (const auto& cm : d.comments)
          if (ctl::upper(ctl::trim(cm)).rfind("LOG,P", 0) == 0) logged = true;
        if (logged) {
          ++probes;
          break;
        }
      }
      if (!b.find('X') && !b.find('Y') && !b.find('Z')) problem(b.line, g + " without an axis word");
      // The next 3 blocks must open "o<n> if [#5070 NE 1]" whose body has an (ABORT, ...).
      bool checked = false;
      for (const size_t j : ctl::nextBlocks(blocks, i, 3)) {
        const nc::Block& c = blocks[j];
        if (!c.control || c.keyword != "IF") continue;
        std::string cond;
        for (char ch : ctl::upper(c.code))
          if (ch != ' ' && ch != '\t') cond += ch;
        // The whole condition: one joined to it ([[#5070 NE 1] AND [0]]) may never be true.
        const size_t kw = cond.rfind("IF[");
        if (kw == std::string::npos || cond.substr(kw + 2) != "[#5070NE1]") continue;
        for (size_t k = j + 1; k < blocks.size(); ++k) {
          const nc::Block& d = blocks[k];
          if (d.control && d.keyword == "ENDIF" && ctl::upper(d.oword) == ctl::upper(c.oword)) break;
          if (d.control && d.keyword == "IF") break;
          for (const auto& cm : d.comments)
            if (ctl::upper(ctl::trim(cm)).rfind("ABORT,", 0) == 0) checked = true;
        }
        break;
      }
      if (!checked) problem(b.line, g + " is not followed by 'o<n> if [#5070 NE 1]' with an (ABORT, ...)");
    }
    const int last_line = blocks.empty() ? 1 : blocks.back().line;
    if (shape.reads > 0) {
      // External readings (an R-test logger): every trigger (M64 P0) after a dwell, each cycle's poses all read.
      size_t reads = 0;
      const nc::Block* prev = nullptr;
      for (const auto& b : blocks) {
        if (b.control || b.words.empty()) continue;
        if (b.hasWord('M', 64)) {
          ++reads;
          if (!prev || !prev->hasWord('G', 4)) problem(b.line, "R-test reading (M64) without a dwell (G4) before it");
        }
        prev = &b;
      }
      if (reads != shape.reads)
        problem(last_line, fmt::format("{} R-test readings [M64 P{}] written, the program has {} (each cycle: the plan's "
                                       "{} poses, and the reset before and after them when the plan reads it)",
                                       reads, kReadOutput, shape.reads, plan.points.size()));
    } else if (static_cast<size_t>(probes) != shape.probes)
      problem(last_line, fmt::format("{} recorded touches [G38.2/G38.3 moves whose position is LOGged], the plan "
                                     "has {} points",
                                     probes, shape.probes));
    for (auto& s : ctl::blockProblems(blocks, plan, kDialect)) out.push_back(std::move(s));
    // The end: M2 or M30 as the last block with code; a leading '%' needs a closing one, after
    // which LinuxCNC reads nothing.
    const size_t first = ctl::nextNonBlank(blocks, static_cast<size_t>(-1));
    const bool wrapped = first < blocks.size() && blocks[first].percent;
    bool closed = false;
    const nc::Block* last_code = nullptr;
    for (size_t i = wrapped ? first + 1 : 0; i < blocks.size(); ++i) {
      if (blocks[i].percent) {
        closed = true;
        break;
      }
      if (!blocks[i].code.empty()) last_code = &blocks[i];
    }
    if (!last_code || !(last_code->hasWord('M', 2) || last_code->hasWord('M', 30)))
      problem(last_code ? last_code->line : last_line, "the program does not end with M2 or M30");
    if (wrapped && !closed) problem(last_line, "the program starts with '%' but has no closing '%'");
    return out;
  }
};

}  // namespace

std::string linuxcncKinsComponent(Kinematics k) {
  if (k == Kinematics::TableAB) return "xyzab_tdr_kins";
  if (k == Kinematics::HeadTable) return "maxkins";
  if (k == Kinematics::HeadCB) return "5axiskins";
  return k == Kinematics::TableAC ? "xyzac-trt-kins" : "xyzbc-trt-kins";
}

std::vector<std::pair<std::string, double>> linuxcncKinsChanges(const LocationErrors& e) {
  if (e.kinematics == Kinematics::TableAC) {
    const double dx = e.get("dx_AY"), dy = e.get("dy_AY"), dz = e.get("dz_AY"), dyc = e.get("dy_CA");
    return {{"x-rot-point", dx}, {"y-rot-point", dy + dyc}, {"z-rot-point", dz}, {"y-offset", -dyc}, {"z-offset", 0.0}};
  }
  if (e.kinematics == Kinematics::TableAB)
    return {{"x-rot-point", e.get("dx_BY")}, {"y-rot-point", e.get("dy_AB")}, {"z-rot-point", e.get("dz_BY")},
            {"z-offset", e.get("dz_AB")}};
  const double dx = e.get("dx_BY"), dyc = e.get("dy_CB"), dz = e.get("dz_BY"), dxc = e.get("dx_CB");
  return {{"x-rot-point", dx + dxc}, {"y-rot-point", dyc}, {"z-rot-point", dz}, {"x-offset", -dxc}, {"z-offset", 0.0}};
}

std::map<std::string, double> parseHalSetp(const std::string& text, const std::string& component) {
  std::map<std::string, double> pins;
  const std::string prefix = component + ".";
  for (const auto& l : ctl::splitLines(text)) {
    std::string s = l.text;
    const size_t hash = s.find('#');
    if (hash != std::string::npos) s.resize(hash);
    const auto t = ctl::tokens(s);
    if (t.size() < 2 || t[0] != "setp" || t[1].rfind(prefix, 0) != 0) continue;
    if (t.size() != 3)
      throw std::invalid_argument(fmt::format("previous offsets file, line {}: expected 'setp {}<pin> <value>'",
                                              l.number, prefix));
    const auto v = ctl::parseNumber(t[2]);
    if (!v)
      throw std::invalid_argument(
          fmt::format("previous offsets file, line {}: value '{}' of {} is not a number", l.number, t[2], t[1]));
    pins[t[1].substr(prefix.size())] = *v;
  }
  return pins;
}

std::map<char, double> previousWorkOffset(const std::string& text, std::string_view axes) {
  std::map<char, double> previous;
  for (const char axis : axes) previous[axis] = 0.0;
  std::string listed;
  for (const char axis : axes) listed += fmt::format("{} ", axis);
  bool had_line = false;
  for (const auto& l : ctl::splitLines(text)) {
    std::string code = l.text;
    for (size_t open; (open = code.find('(')) != std::string::npos;) {
      const size_t close = code.find(')', open);
      code.erase(open, close == std::string::npos ? std::string::npos : close - open + 1);
    }
    const auto t = ctl::tokens(ctl::upper(code));
    if (t.size() < 3 || t[0] != "G10" || t[1] != "L2" || t[2] != "P1") continue;
    had_line = true;
    for (size_t i = 3; i < t.size(); ++i) {
      const auto v = t[i].size() > 1 ? ctl::parseNumber(t[i].substr(1)) : std::nullopt;
      if (!v || !previous.count(t[i][0]))
        throw std::invalid_argument(
            fmt::format("previous offsets file, line {}: '{}' is not one of {}<number>", l.number, t[i], listed));
      previous[t[i][0]] = *v;
    }
  }
  if (!text.empty() && !had_line)
    throw std::invalid_argument("previous offsets file has no 'G10 L2 P1' line: not a rotacal work-offset file");
  return previous;
}

WorkOffsetChange workOffsetChange(std::string_view axes, const std::map<char, double>& previous,
                                  const std::map<char, double>& change, const std::function<int(char)>& decimals) {
  WorkOffsetChange w;
  w.g10 = "G10 L2 P1";
  for (const char axis : axes) {
    const int dec = decimals(axis);
    const double was = previous.at(axis), by = change.at(axis);
    w.steps.push_back(fmt::format("{}: previous {} change {} new {}", axis, ctl::fixed(was, dec), ctl::fixed(by, dec),
                                  ctl::fixed(was + by, dec)));
    w.g10 += fmt::format(" {}{}", axis, ctl::fixed(was + by, dec));
  }
  return w;
}

const Dialect& linuxcncDialect() { return singleton<LinuxCncDialect>(); }

}  // namespace rotacal
