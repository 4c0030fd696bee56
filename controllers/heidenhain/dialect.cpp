// Heidenhain TNC 640, Klartext (../shared/reference/controllers.md Sec. 5): every line starts
// with its block number, `0 BEGIN PGM NAME MM` ... `N END PGM NAME MM`, comments after ';'.
// Probing with touch-probe cycle 0 (REF. PLANE): `TCH PROBE 0.0 REF. PLANE Q10 X+` (result
// parameter, probing axis and direction) and `TCH PROBE 0.1 X.. Y.. Z..` (the pre-position, which
// is where the safe path already stands). Cycle 0 moves along one axis only, so the two other
// coordinates of the ball centre are those of the pre-position; the program stores the three in
// the nonvolatile QR1-QR4 (QR1 = point id) and prints them with FN 16: F-PRINT through format
// files, whose text is in the program's header comments (the control needs them as files).
//
// Results, as the format files print them (decimal commas with a German language setting; the
// parser accepts commas and points):
//   ROTACAL HEIDENHAIN CYCLE TOUCH154 POINTS 154 UNIT MM
//   P   17 X  123,4560 Y -200,0000 Z  173,0000
//   T20261122 014119
//   END
// T = YEAR4 MONTH DAY HOUR MIN SEC at the point (format-file keywords [H-426TM] 686): t_s =
// seconds since 2000-01-01, whole seconds (the control prints the current second, truncated).
// A point that does not trigger prints "NOT-TRIGGERED P   17" and the program stops.
//
// UNVERIFIED, and the conservative choice made for each:
// - The Klartext form of cycle 0 and that Q10 holds the ball-centre coordinate along the probing
//   axis in the active datum (not the surface): the parser takes it so; the lines printed are
//   the raw values, so a different convention can be corrected afterwards.
// - No-trigger reaction of cycle 0 (believed: error and stop): the program also checks that the
//   result lies short of the planned end point (FN 11/12 ... GOTO LBL) and then prints
//   NOT-TRIGGERED, shows it on the screen (F-PRINT / SCREEN:) and stops (STOP).
// - FN 16 format-file lines with Q parameters ("%10.4LF", QR2;) and that repeated F-PRINTs to
//   the same file within a run append: a leftover file from an earlier run shows up as a second
//   header line, which the parser rejects.
// - Inverse-time feed: never used. Inch: the program is always written in MM (Heidenhain inch
//   feeds are in 0.1 in/min), so the results are in mm whatever the machine's unit.
// - Probing feed and maximum travel of cycle 0 come from the touch-probe table, not from the
//   program: set them to the plan's probing feed and approach + overtravel.
// - Line length: 80 characters (Autodesk's Heidenhain post).
#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <stdexcept>

#include "controllers/clock.hpp"
#include "controllers/heidenhain/format_files.hpp"
#include "controllers/offsets.hpp"
#include "controllers/program_checking.hpp"
#include "controllers/program_writing.hpp"
#include "controllers/result_checks.hpp"
#include "controllers/results_lines.hpp"
#include "controllers/text.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

constexpr const char* kDialect = "heidenhain";
constexpr size_t kMaxLineChars = 80;
constexpr int kLabelBase = 1000;  // LBL 1000 + id: the no-trigger section of point id
constexpr const char* kDir = "TNC:\\ROTACAL\\";
/// Distance (mm) short of the end point below which a result counts as "not triggered": a
/// triggered probe stops the overtravel (mm) before the end, an untriggered one at or beyond it.
constexpr double kNoTriggerMm = 0.01;

/// Like parseNumber, also accepting a decimal comma instead of the point (Heidenhain prints
/// "-293,733" with a German language setting) and a trailing point or comma ("12." "12,").
std::optional<double> parseNumberComma(std::string_view token) {
  std::string t(token);
  if (std::count(t.begin(), t.end(), ',') + std::count(t.begin(), t.end(), '.') > 1) return std::nullopt;
  for (auto& c : t)
    if (c == ',') c = '.';
  return ctl::parseNumber(t);
}

/// Converts a program's text lines into neutral blocks for strokeProblems: each entry is a line
/// number and its X/Y/Z/A/B/C values (absolute, in the program's unit) of one motion endpoint.
struct MotionEndpoint {
  int line = 0;
  std::vector<std::pair<char, double>> axes;
};
std::vector<nc::Block> motionBlocks(const std::vector<MotionEndpoint>& endpoints, bool inch) {
  std::vector<nc::Block> blocks;
  nc::Block unit;
  unit.line = 0;
  unit.code = inch ? "G20" : "G21";
  unit.words.push_back({'G', inch ? "20" : "21", false, inch ? 20.0 : 21.0});
  blocks.push_back(unit);
  for (const auto& e : endpoints) {
    nc::Block b;
    b.line = e.line;
    b.code = "motion";
    for (const auto& [axis, v] : e.axes) b.words.push_back({axis, ctl::fixed(v, 6), true, v});
    blocks.push_back(std::move(b));
  }
  return blocks;
}

/// Unit direction of a probing move (from the nominal trigger toward the end point) when it is
/// along one machine axis: axis index 0..2 and sign +-1; nullopt when it is not axis-aligned
/// within 1e-9.
struct AxisDirection {
  int axis = 0;
  int sign = 1;
};
std::optional<AxisDirection> axisAligned(const Eigen::Vector3d& d) {
  const double n = d.norm();
  if (!(n > 0)) return std::nullopt;
  const Eigen::Vector3d u = d / n;
  for (int a = 0; a < 3; ++a)
    if (std::abs(std::abs(u[a]) - 1.0) < 1e-9) return AxisDirection{a, u[a] > 0 ? 1 : -1};
  return std::nullopt;
}

/// Signed Klartext number: "+51.0000", "-235.0000" (never "-0.0000").
std::string H(double v, int decimals = 4) {
  const std::string s = ctl::fixed(v, decimals);
  return s[0] == '-' ? s : "+" + s;
}

std::string safeName(std::string_view name) {
  std::string s;
  for (char c : ctl::upper(name)) s += ((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) ? c : '_';
  if (s.empty()) s = "ROTACAL";
  if (s.size() > 24) s.resize(24);
  return s;
}

std::string commentText(std::string_view text) {
  std::string s;
  for (char c : text) {
    const char d = (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? ' ' : c;
    if (d == ' ' && (s.empty() || s.back() == ' ')) continue;
    s += d;
  }
  return ctl::trim(s);
}

/// "; text" comment lines, printable ASCII only, of at most `width` characters of text: with
/// "NNNN ; " in front (block numbers up to 4 digits) they stay within kMaxLineChars. A line that
/// fits keeps its blanks (aligned tables).
std::vector<std::string> commentLinesOf(std::string_view text, size_t width = kMaxLineChars - 7) {
  std::string s = ctl::printableLine(text);
  while (!s.empty() && s.back() == ' ') s.pop_back();
  if (s.size() <= width) return {"; " + s};
  std::vector<std::string> out;
  for (const auto& piece : ctl::wrap(s, width)) out.push_back("; " + piece);
  return out;
}

std::string headerText(const std::string& cycle, int points) {
  return fmt::format("ROTACAL HEIDENHAIN CYCLE {} POINTS {} UNIT MM", safeName(cycle), points);
}

DialectIdentity heidenhainIdentity() {
  DialectIdentity d;
  d.language = ProgramLanguage::Klartext;  // cycle 0's check is written around the pre-position
  d.inverse_time_refusal = "inverse-time feed is not verified for Klartext (controllers.md Sec. 5.5)";
  d.rewrite_refusal = "Klartext programs are not rewritten; enter the kinematics values of `analyze --offsets` "
                      "instead (docs/compensation.md)";
  d.comp_table_refusal = "no compensation table form is given by the sources (the TNC's axis-error compensation "
                         "tables are machine configuration, OEM-protected: docs/dialects.md); give the table of "
                         "--dialect csv to the machine builder";
  return d;
}

class HeidenhainDialect final : public Dialect {
 public:
  HeidenhainDialect() : Dialect(heidenhainIdentity()) {}
  std::string_view name() const override { return kDialect; }
  std::string_view programExtension() const override { return ".h"; }
  std::string_view resultsExtension() const override { return ".txt"; }

  std::vector<std::string> commentLines(std::string_view text) const override { return commentLinesOf(text); }

  std::string writeProgram(const nc::Program& p) const override {
    const double k = p.unit == nc::Unit::Inch ? kMmPerInch : 1.0;  // always MM programs
    const int probes = ctl::probeCount(p);
    ctl::requireInverseTimeAllowed(p, kDialect);  // the tool-tip cycle: refused with the reason, not the probe count
    if (probes == 0)  // the result format files below are built per probing move
      throw std::invalid_argument("the heidenhain program records probing moves and this one has none (use linuxcnc)");
    const std::string name = safeName(p.name.empty() ? "ROTACAL" : p.name);
    const std::string results = std::string(kDir) + safeName(p.results_file.empty() ? "ROTACAL" : p.results_file) + ".TXT";
    double safe_z = -std::numeric_limits<double>::infinity();
    for (const auto& op : p.ops)
      if (op.kind == nc::Op::Kind::Rapid) safe_z = std::max(safe_z, op.xyz.z() * k);
    if (!std::isfinite(safe_z)) throw std::invalid_argument("the heidenhain program needs a rapid move to a safe height");

    std::vector<std::string> body;
    auto line = [&](const std::string& s) { body.push_back(s); };
    auto commentLines = [&](std::string_view text) {
      const std::string s = commentText(text);
      if (s.empty()) return;
      for (const auto& l : commentLinesOf(s, kMaxLineChars - 8)) line(l);  // up to 5-digit block numbers
    };
    auto print = [&](const std::string& format_file) { line(fmt::format("FN 16: F-PRINT {}{} / {}", kDir, format_file, results)); };

    line(fmt::format("BEGIN PGM {} MM", name));
    commentLines(p.name + " generated by rotacal, dialect heidenhain (TNC 640 Klartext)");
    for (const auto& h : p.header) commentLines(h);
    commentLines("machine coordinates: the datum as the work offset line above says, no PLANE function, no M128 / "
                 "TCPM active");
    commentLines("touch probe table: probing feed and maximum travel of this cycle come from there");
    commentLines(fmt::format("results: FN 16 to {}; uses QR1-QR4", results));
    commentLines(fmt::format("format files: save the text after each '=' below as the named file in {}", kDir));
    for (const auto& [file, text] : heidenhainFormatFiles(p.cycle, probes)) line(fmt::format("; {}={}", file, text));
    if (p.probe_tool > 0) line(fmt::format("TOOL CALL {} Z", p.probe_tool));
    else commentLines("activate the touch probe (TOOL CALL) before the start");
    print("RCH.A");
    Eigen::Vector3d cur(0, 0, 0);
    bool cur_known = false;
    std::vector<int> ids;
    ctl::ModeGuard guard;
    for (const auto& op : p.ops) {
      const Eigen::Vector3d x = op.xyz * k;
      guard.apply(op);
      switch (op.kind) {
        case nc::Op::Kind::Comment: commentLines(op.text); break;
        case nc::Op::Kind::Rapid:
          if (op.z_only) {
            line(fmt::format("L Z{} R0 FMAX", H(x.z())));
            cur.z() = x.z();
          } else {
            line(fmt::format("L X{} Y{} Z{} R0 FMAX", H(x.x()), H(x.y()), H(x.z())));
            cur = x;
            cur_known = true;
          }
          break;
        case nc::Op::Kind::Linear:
          line(fmt::format("L X{} Y{} Z{} R0 F{}", H(x.x()), H(x.y()), H(x.z()), ctl::fixed(op.feed * k, 0)));
          cur = x;
          cur_known = true;
          break;
        case nc::Op::Kind::Index: {
          if (op.feed > 0)
            throw std::invalid_argument(fmt::format("the {} program indexes at rapid only; a rotary move at a feed "
                                                    "(R-test reciprocation) is written for linuxcnc only", "heidenhain"));
          std::string s = "L";
          for (const auto& [axis, deg] : op.rotary) s += fmt::format(" {}{}", axis, H(deg));
          line(s + " R0 FMAX");
          break;
        }
        case nc::Op::Kind::Mode:
          // Absolute, per-minute is Klartext's default; inverse time was refused above.
          if (op.incremental)
            throw std::invalid_argument("heidenhain: incremental (G91) moves are not written for Klartext");
          break;
        case nc::Op::Kind::RotaryLinear:
          throw std::invalid_argument("heidenhain: simultaneous rotary-linear moves with inverse-time feed are refused "
                                      "(inverse time not verified, controllers.md Sec. 5)");
        case nc::Op::Kind::Pause:
          if (op.dwell_s > 0) {
            line("CYCL DEF 9.0 DWELL TIME");
            line(fmt::format("CYCL DEF 9.1 DWELL {}", ctl::fixed(op.dwell_s, 1)));
          } else {
            line("STOP");
          }
          break;
        case nc::Op::Kind::Dwell:
        case nc::Op::Kind::Read:
        case nc::Op::Kind::RepeatBegin:
        case nc::Op::Kind::RepeatEnd: ctl::refuseRtestOps(kDialect);
        case nc::Op::Kind::Probe: {
          const int id = op.point_id;
          if (id <= 0 || kLabelBase + id > 65535) throw std::invalid_argument(fmt::format("point id {} out of range", id));
          if (op.retract_mm > 0)
            throw std::invalid_argument(fmt::format(
                "point {}: cycle 0 records a single touch and has no double-touch form; set the machine's probe "
                "retract_mm to 0 for this dialect",
                id));
          if (!cur_known) throw std::invalid_argument(fmt::format("point {}: probing before any positioning move", id));
          const auto dir = axisAligned(x - cur);
          if (!dir)
            throw std::invalid_argument(fmt::format(
                "point {}: cycle 0 probes along one machine axis; this approach is not axis-aligned", id));
          const char axis = "XYZ"[dir->axis];
          const double end = x[dir->axis];
          if (!op.text.empty()) commentLines(op.text);
          line(fmt::format("TCH PROBE 0.0 REF. PLANE Q10 {}{}", axis, dir->sign > 0 ? '+' : '-'));
          line(fmt::format("TCH PROBE 0.1 X{} Y{} Z{}", H(cur.x()), H(cur.y()), H(cur.z())));
          // Not triggered: the result is not at least kNoTriggerMm short of the end point.
          const double limit = end - dir->sign * kNoTriggerMm;
          line(fmt::format("FN {}: IF +Q10 {} {} GOTO LBL {}", dir->sign > 0 ? 11 : 12, dir->sign > 0 ? "GT" : "LT",
                           H(limit), kLabelBase + id));
          line(fmt::format("FN 0: QR1 = +{}", id));
          for (int a = 0; a < 3; ++a)
            line(a == dir->axis ? fmt::format("FN 0: QR{} = +Q10", 2 + a) : fmt::format("FN 0: QR{} = {}", 2 + a, H(cur[a])));
          print("RCP.A");
          print("RCT.A");
          ids.push_back(id);
          break;
        }
      }
    }
    print("RCE.A");
    line(fmt::format("L Z{} R0 FMAX M30", H(safe_z)));
    for (int id : ids) {
      line(fmt::format("LBL {}", kLabelBase + id));
      line(fmt::format("FN 0: QR1 = +{}", id));
      print("RCN.A");
      line(fmt::format("FN 16: F-PRINT {}RCN.A / SCREEN:", kDir));
      line("STOP");
      line(fmt::format("L Z{} R0 FMAX M30", H(safe_z)));
    }
    std::string out;
    int n = 0;
    for (const auto& s : body) ctl::appendLine(out, fmt::format("{} {}", n++, s), kMaxLineChars);
    out += fmt::format("{} END PGM {} MM\n", n, name);
    return out;
  }

  std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const override {
    auto comma = [](std::string s) {
      for (auto& c : s)
        if (c == '.') c = ',';
      return s;
    };
    std::string out = headerText(plan.cycle, static_cast<int>(plan.points.size())) + "\n";
    for (const auto& t : run.points) {
      if (!plan.findPoint(t.point_id)) throw std::invalid_argument(fmt::format("run point {} is not in the plan", t.point_id));
      if (std::isnan(t.t_s))
        throw std::invalid_argument(fmt::format("point {} has no time: the heidenhain program prints the clock", t.point_id));
      const Eigen::Vector3d& x = t.position_m_mm;
      out += fmt::format("P{:>5} X{:>10} Y{:>10} Z{:>10}\n", t.point_id, comma(ctl::fixed(x.x(), 4)),
                         comma(ctl::fixed(x.y(), 4)), comma(ctl::fixed(x.z(), 4)));
      const ctl::ClockStamp c = ctl::clockStamp(t.t_s);
      out += fmt::format("T{:08d} {:06d}\n", c.yyyymmdd, c.hhmmss);
    }
    out += "END\n";
    return out;
  }

  MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const override {
    ctl::requireText(text, file);
    const std::string expected_header = headerText(plan.cycle, static_cast<int>(plan.points.size()));
    ctl::PointCollector points(plan, file);
    ctl::ResultLines in(text, file, "ROTACAL", expected_header, " (delete the old file)");
    struct Pending {
      int line = 0;
      long id = 0;
      Eigen::Vector3d x;
    };
    std::optional<Pending> pending;  // a P line waiting for its T line
    while (in.next()) {
      const std::string& s = in.s;
      const auto& t = in.t;
      const int line = in.number;
      if (in.isHeader()) {
        if (t.size() != 8 || t[1] != "HEIDENHAIN" || t[2] != "CYCLE" || t[4] != "POINTS" || t[6] != "UNIT" || t[7] != "MM")
          ctl::fail(file, line, fmt::format("expected the header '{}', got '{}'", expected_header, s));
        if (t[3] != safeName(plan.cycle))
          ctl::fail(file, line, fmt::format("results of cycle '{}', the plan is '{}'", t[3], safeName(plan.cycle)));
        const auto n = ctl::parseDigits(t[5]);
        if (!n) ctl::fail(file, line, fmt::format("POINTS '{}' is not a number", t[5]));
        if (static_cast<size_t>(*n) != plan.points.size())
          ctl::fail(file, line, fmt::format("header says POINTS {} but the plan has {} points", *n, plan.points.size()));
        continue;
      }
      in.refuseNotTriggered();
      if (s[0] == 'T' && s != "END") {
        if (!pending) ctl::fail(file, line, fmt::format("time line '{}' without a point line before it", s));
        const auto date = t.size() == 2 ? ctl::parseDigits(t[0].substr(1)) : std::nullopt;
        const auto time = t.size() == 2 ? ctl::parseDigits(t[1]) : std::nullopt;
        const auto secs = date && time ? ctl::clockSeconds(*date, *time) : std::nullopt;
        if (!secs)
          ctl::fail(file, line,
                    fmt::format("time of point {} '{}' is not 'TYYYYMMDD HHMMSS'", pending->id, s));
        points.add(pending->line, static_cast<int>(pending->id), pending->x, *secs);
        pending.reset();
        continue;
      }
      if (pending) ctl::fail(file, line, fmt::format("point {} (line {}) has no time line", pending->id, pending->line));
      if (in.isEnd()) continue;
      const auto f = ctl::letteredFields(s, "XYZ", file, line);
      Eigen::Vector3d x;
      for (int i = 0; i < 3; ++i) {
        const auto v = parseNumberComma(f.fields[static_cast<size_t>(i)]);
        if (!v)
          ctl::fail(file, line,
                    fmt::format("{} '{}' of point {} is not a number", "XYZ"[i], f.fields[static_cast<size_t>(i)], f.id));
        x[i] = *v;
      }
      pending = Pending{line, f.id, x};
    }
    if (pending) ctl::fail(file, in.last(), fmt::format("point {} (line {}) has no time line", pending->id, pending->line));
    in.finish(points);
    return points.finish(in.last());
  }

  std::string writeOffsets(const OffsetRequest& r) const override {
    const ctl::OffsetBasis b(r, kDialect);
    const auto& [plan, m, e, ac, inch, k, tilt] = b;
    const Eigen::Vector3d pivot = b.pivot();
    const Eigen::Vector3d second = b.second();
    const double zero_deg = b.zeroDeg(kDialect);
    std::vector<std::string> body;
    auto c = [&](const std::string& s) {
      // Block numbers up to 2 digits (a few dozen lines): "NN ; " leaves 75 characters of text.
      for (auto& l : commentLinesOf(s, kMaxLineChars - 5)) body.push_back(std::move(l));
    };
    c(fmt::format("rotacal kinematics / preset correction, table {}/C, TNC 640", tilt));
    c(fmt::format("provenance: {}; cycle {}, machine {}", r.report_file.empty() ? "(no report)" : r.report_file,
                  plan.cycle, m.name));
    c("identified (papers' convention), value +- u (k = 1):");
    for (const auto& s : ctl::identifiedLines(r)) c("  " + s);
    c("what it changes: nothing by itself. Direct writes of the kinematics");
    c("description from NC are OEM-protected (UNVERIFIED): enter by hand or let");
    c("KinematicsOpt (cycle 451) optimize. Old values are on the control;");
    c("new = old + change. Lengths mm, machine coordinates, rotaries at 0 deg.");
    c(fmt::format("kinematics, transformation to the {} axis: X {} Y {} Z {}", tilt, H(pivot.x()), H(pivot.y()),
                  H(pivot.z())));
    c(fmt::format("kinematics, transformation {} axis to C axis: X {} Y {} Z {}", tilt, H(second.x()), H(second.y()),
                  H(second.z())));
    c(fmt::format("preset table, {} axis of the active preset: {} deg", tilt, H(zero_deg)));
    c(ac ? "reported only (axis directions): b_AY, c_AY, b_CA" : "reported only (axis directions): a_BY, c_BY, a_CB");
    std::string out = "0 BEGIN PGM ROTACAL_KIN MM\n";
    int n = 1;
    for (const auto& s : body) ctl::appendLine(out, fmt::format("{} {}", n++, s), kMaxLineChars);
    out += fmt::format("{} END PGM ROTACAL_KIN MM\n", n);
    return out;
  }

  std::vector<std::string> check(const std::string& text, const ProbePlan& plan, const nc::Shape& shape) const override {
    ctl::TextCheck chk(text);
    // chk.code: each line without its block number and its ';' comment
    static const std::regex numbered(R"(^(\d+) (.*)$)");
    long expect = 0;
    for (size_t i = 0; i < chk.lines.size(); ++i) {
      const std::string& raw = chk.lines[i].text;
      const int n = chk.lines[i].number;
      chk.lineLength(i, kMaxLineChars);
      std::smatch mt;
      if (!std::regex_match(raw, mt, numbered)) {
        chk.problem(n, "line does not start with a block number");
        continue;
      }
      if (std::stol(mt[1].str()) != expect)
        chk.problem(n, fmt::format("block number {} where {} was expected", mt[1].str(), expect));
      expect = std::stol(mt[1].str()) + 1;
      const std::string rest = mt[2].str();
      const size_t sc = rest.find(';');
      chk.code[i] = ctl::trim(sc == std::string::npos ? rest : rest.substr(0, sc));
    }
    static const std::regex begin(R"(^BEGIN PGM (\w+) (MM|INCH)$)");
    static const std::regex endpgm(R"(^END PGM (\w+) (MM|INCH)$)");
    std::smatch bm, em;
    if (chk.code.empty() || !std::regex_match(chk.code.front(), bm, begin))
      chk.problem(1, "the program does not start with BEGIN PGM NAME MM");
    if (chk.code.empty() || !std::regex_match(chk.code.back(), em, endpgm) || (!bm.empty() && bm[1].str() != em[1].str()))
      chk.problem(chk.lastLine(), "the program does not end with END PGM and the name of its BEGIN PGM");
    const bool inch = !bm.empty() && bm[2].str() == "INCH";
    static const std::regex word(R"(([XYZABC])([+-]?)(\d+(\.\d*)?))");
    static const std::regex probe0(R"(^TCH PROBE 0\.0 REF\. PLANE Q10 ([XYZ])([+-])$)");
    static const std::regex check(R"(^FN (11|12): IF \+Q10 (GT|LT) ([+-]\d+\.\d+) GOTO LBL (\d+)$)");
    std::vector<MotionEndpoint> moves;
    int probes = 0;
    for (size_t i = 0; i < chk.lines.size(); ++i) {
      const std::string& s = chk.code[i];
      const int n = chk.lines[i].number;
      if (s.find("M128") != std::string::npos || s.find("TCPM") != std::string::npos || s.rfind("PLANE ", 0) == 0)
        chk.problem(n, "TCP or a tilted plane: the probe positions are machine coordinates");
      const bool positioning = s.rfind("L ", 0) == 0 || s.rfind("TCH PROBE 0.1 ", 0) == 0;
      if (positioning) {
        MotionEndpoint e{n, {}};
        for (auto it = std::sregex_iterator(s.begin(), s.end(), word); it != std::sregex_iterator(); ++it) {
          const auto& w = *it;
          if (w[2].str().empty() || w[4].str().empty())
            chk.problem(n, fmt::format("{}{}{} needs an explicit sign and a decimal point", w[1].str(), w[2].str(), w[3].str()));
          e.axes.emplace_back(w[1].str()[0], std::stod(w[2].str() + w[3].str()));
        }
        if (s.rfind("L ", 0) == 0 && s.find(" R0") == std::string::npos) chk.problem(n, "L block without R0");
        if (s.rfind("L ", 0) == 0 && s.find(" FMAX") == std::string::npos && s.find(" F") == std::string::npos)
          chk.problem(n, "L block without a feed");
        moves.push_back(e);
      }
      std::smatch pm;
      if (!std::regex_match(s, pm, probe0)) continue;
      ++probes;
      // Next code lines: TCH PROBE 0.1 <pre-position>, FN 11|12 IF +Q10 GT|LT v GOTO LBL n,
      // with a label section that stops (STOP).
      auto next = [&](size_t j) {
        for (++j; j < chk.lines.size(); ++j)
          if (!chk.code[j].empty() && chk.code[j][0] != ';') return j;
        return chk.lines.size();
      };
      const size_t a = next(i);
      const size_t b = a < chk.lines.size() ? next(a) : chk.lines.size();
      std::smatch cm;
      bool ok = a < chk.lines.size() && chk.code[a].rfind("TCH PROBE 0.1 ", 0) == 0 && b < chk.lines.size() &&
                std::regex_match(chk.code[b], cm, check);
      if (ok) {
        const bool plus = pm[2].str() == "+";
        ok = (plus && cm[1].str() == "11" && cm[2].str() == "GT") || (!plus && cm[1].str() == "12" && cm[2].str() == "LT");
        bool stops = false;
        const std::string label = cm[4].str();
        for (size_t q = 0; ok && q < chk.lines.size(); ++q) {
          if (chk.code[q] != "LBL " + label) continue;
          // As the control runs the section: a jump, a call or an end before its STOP never stops.
          for (size_t r = next(q); r < chk.lines.size() && chk.code[r].rfind("LBL ", 0) != 0; r = next(r)) {
            const std::string& t = chk.code[r];
            if (t == "STOP") {
              stops = true;
              break;
            }
            if (t.find("GOTO") != std::string::npos || t.find("CALL ") != std::string::npos ||
                t.find(" M30") != std::string::npos || t.find(" M2") != std::string::npos || t.rfind("END PGM", 0) == 0)
              break;
          }
        }
        ok = ok && stops;
      }
      if (!ok)
        chk.problem(n, "TCH PROBE 0 is not followed by TCH PROBE 0.1 and the no-trigger check "
                       "(FN 11/12: IF +Q10 GT/LT end GOTO LBL n, LBL n ... STOP)");
    }
    std::map<std::string, int> label_line;
    for (size_t i = 0; i < chk.lines.size(); ++i)
      if (chk.code[i].rfind("LBL ", 0) == 0) label_line.emplace(chk.code[i].substr(4), chk.lines[i].number);
    static const std::regex call(R"((^|\s)(CALL (LBL|PGM)|SEL PGM|CYCL CALL|PGM CALL)\b)");
    for (size_t i = 0; i < chk.lines.size(); ++i) {
      const int n = chk.lines[i].number;
      const size_t g = chk.code[i].find("GOTO LBL ");
      if (g != std::string::npos) {
        const auto it = label_line.find(chk.code[i].substr(g + 9));
        if (it == label_line.end())
          chk.problem(n, fmt::format("jump to the undefined label {}", chk.code[i].substr(g + 9)));
        // rotacal jumps forward only, to a section that stops: a jump back may never end.
        else if (it->second <= n)
          chk.problem(n, fmt::format("GOTO LBL {} jumps back to line {}: a loop the verifier cannot bound", it->first,
                                     it->second));
      }
      std::smatch cm;
      if (std::regex_search(chk.code[i], cm, call))
        chk.problem(n, fmt::format("{}: a subprogram or label call the verifier cannot follow", cm[2].str()));
    }
    chk.probeCount(probes, shape.probes, "TCH PROBE 0 cycles");
    if (shape.inverse_time) chk.problem(1, ctl::inverseTimeRefusal(kDialect));
    for (auto& s : ctl::strokeProblems(motionBlocks(moves, inch), plan, kDialect)) chk.problems.push_back(std::move(s));
    return std::move(chk.problems);
  }
};

}  // namespace

std::vector<std::pair<std::string, std::string>> heidenhainFormatFiles(const std::string& cycle, int points) {
  return {
      {"RCH.A", fmt::format("\"{}\\n\";", headerText(cycle, points))},
      {"RCP.A", "\"P%5.0LF X%10.4LF Y%10.4LF Z%10.4LF\\n\",QR1,QR2,QR3,QR4;"},
      {"RCT.A", "\"T%4d%02.2d%02.2d %02.2d%02.2d%02.2d\\n\",YEAR4,MONTH,DAY,HOUR,MIN,SEC;"},
      {"RCE.A", "\"END\\n\";"},
      {"RCN.A", "\"NOT-TRIGGERED P%5.0LF\\n\",QR1;"},
  };
}

const Dialect& heidenhainDialect() { return singleton<HeidenhainDialect>(); }

}  // namespace rotacal
