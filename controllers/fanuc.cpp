// Fanuc 0i/30i with Custom Macro B: G31 skip moves with an explicit no-trigger check (the skip
// ends silently at the end point without a signal), results through POPEN/DPRNT/PCLOS,
// compensation as an incremental G54 shift (../shared/reference/controllers.md Sec. 2).
//
// Results, as the program's DPRNTs print them (rotacal's rendering, see fanucDprntNumber):
//   ROTACAL-RESULTS DIALECT FANUC CYCLE TOUCH154 POINTS 154 UNIT MM
//   P17 X 123.4560 Y-200.0000 Z 173.0000 T    12345
//   END
// X Y Z = skip position #5061-#5063 in the work coordinates (G54 = rotary-axis intersection),
// program units, [44] = 4 integer + 4 decimal digits; T = ms timer #3001 (zeroed at the start,
// [90]), t_s = T / 1000.
#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "controllers/common.hpp"
#include "controllers/dialects.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

constexpr const char* kDialect = "fanuc";
constexpr size_t kMaxLineChars = 80;  // conservative: Autodesk's Fanuc posts keep to 80; limit UNVERIFIED
constexpr int kStoreBase = 700;       // retained #700.. (#500-#999 survive power-off)
constexpr int kMaxPointsPerPose = 70;  // #700 + 4 * 70 - 1 = #979 <= #999
constexpr int kLabelBase = 1000;       // N<1000 + id>: the no-trigger check jumps there
constexpr int kMaxLabel = 99999;
constexpr int kIntDigits = 4, kDecimals = 4;  // DPRNT [44] for X Y Z (mm and inch)
constexpr int kTimeDigits = 9;                // DPRNT [90] for T (ms)

/// Upper-case comment text in Fanuc's safe character set (letters, digits, space and . , - + /
/// : = *); anything else becomes a space; runs of spaces collapse.
std::string safeText(std::string_view text) {
  std::string s;
  for (char c : ctl::upper(text)) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == ' ' || c == '.' || c == ',' ||
                    c == '-' || c == '+' || c == '/' || c == ':' || c == '=' || c == '*';
    const char d = c == '_' ? '-' : (ok ? c : ' ');
    if (d == ' ' && (s.empty() || s.back() == ' ')) continue;
    s += d;
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

/// Comment lines of at most kMaxLineChars, split at spaces.
std::vector<std::string> comments(std::string_view text) {
  const std::string s = safeText(text);
  const size_t width = kMaxLineChars - 2;
  std::vector<std::string> out;
  size_t i = 0;
  while (i < s.size()) {
    size_t n = std::min(width, s.size() - i);
    if (i + n < s.size()) {
      const size_t sp = s.rfind(' ', i + n);
      if (sp != std::string::npos && sp > i) n = sp - i;
    }
    out.push_back("(" + ctl::trim(s.substr(i, n)) + ")");
    i += n;
    while (i < s.size() && s[i] == ' ') ++i;
  }
  if (out.empty()) out.push_back("()");
  return out;
}

/// DPRNT text: A-Z 0-9 and '-', '.', '/' ('*' prints a space).
std::string dprntText(std::string_view text) {
  std::string s;
  for (char c : ctl::upper(text)) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '.' || c == '/';
    s += ok ? c : '-';
  }
  return s;
}

std::string unitName(bool inch) { return inch ? "INCH" : "MM"; }

/// "#5061-12.3456" or "#5061+12.3456": the difference between a variable and a literal.
std::string minus(int var, double v, int decimals) {
  return v < 0 ? fmt::format("#{}+{}", var, ctl::fixed(-v, decimals)) : fmt::format("#{}-{}", var, ctl::fixed(v, decimals));
}

class FanucDialect final : public Dialect {
 public:
  std::string_view name() const override { return kDialect; }
  std::string_view programExtension() const override { return ".nc"; }
  std::string_view resultsExtension() const override { return ".txt"; }

  std::string writeProgram(const nc::Program& p) const override {
    const bool inch = p.unit == nc::Unit::Inch;
    auto L = [](double v) { return ctl::fixed(v, 4); };  // mm and inch: 4 decimals, always a point
    auto Ang = [](double v) { return ctl::fixed(v, 4); };
    auto F = [&](double v) { return ctl::fixed(v, inch ? 3 : 1); };
    if (p.number < 1 || p.number > 9999)
      throw std::invalid_argument(fmt::format("Fanuc program number O{} must be 1..9999", p.number));
    int probes = 0;
    for (const auto& op : p.ops) probes += op.kind == nc::Op::Kind::Probe;
    if (p.point_count != 0 && p.point_count != probes)
      throw std::invalid_argument(fmt::format("program has {} probing moves but point_count {}", probes, p.point_count));

    std::string out;
    auto line = [&](const std::string& s) {
      if (s.size() > kMaxLineChars)
        throw std::invalid_argument(fmt::format("line longer than {} characters: {}", kMaxLineChars, s));
      out += s;
      out += '\n';
    };
    auto commentLines = [&](std::string_view text) {
      for (const auto& c : comments(text)) line(c);
    };
    // Squared distance (program units^2) below which the skip position counts as "at the end
    // point", i.e. no trigger: (10 um)^2 in mm, (0.001 in)^2 in inch. A triggered move stops
    // the overtravel (mm, not um) before its end; an untriggered one stops at the end exactly.
    const std::string no_trigger_sq = inch ? "0.000001" : "0.0001";

    line("%");
    line(fmt::format("O{}({})", p.number, safeText("ROTACAL " + p.cycle)));
    commentLines(p.name + " GENERATED BY ROTACAL, DIALECT FANUC CUSTOM MACRO B");
    for (const auto& h : p.header) commentLines(h);
    commentLines("X Y Z = PROBE BALL CENTRE IN MACHINE COORDINATES: G54 AT THE INTERSECTION OF THE ROTARY AXES, "
                 "ROTARY OFFSETS 0, NO TCP OR TILTED PLANE ACTIVE");
    commentLines("RESULTS: POPEN AND DPRNT TO THE DEVICE OF PARAMETER 20 - UNVERIFIED PER MACHINE");
    commentLines(fmt::format("USES LOCAL VARIABLES 1 TO 3 AND RETAINED VARIABLES {} TO {}: THEY MUST BE FREE", kStoreBase,
                             kStoreBase + 4 * kMaxPointsPerPose - 1));
    commentLines("A POINT THAT DOES NOT TRIGGER RAISES ALARM 3001");
    line(inch ? "G20" : "G21");
    line("G17 G40 G49 G80 G90 G94");
    line("G54");
    if (p.probe_tool > 0) {
      commentLines("PROBE LENGTH COMPENSATION: CHECK WHETHER #5063 INCLUDES IT ON THIS CONTROL");
      line(fmt::format("T{} M06", p.probe_tool));
      line(fmt::format("G43 H{}", p.probe_tool));
    }
    line("POPEN");
    line(fmt::format("DPRNT[ROTACAL-RESULTS*DIALECT*FANUC*CYCLE*{}*POINTS*{}*UNIT*{}]", dprntText(p.cycle), probes,
                     unitName(inch)));
    line("#3001=0");

    std::vector<int> pose_points;  // ids probed at the current pose, in order
    auto flush = [&]() {
      for (size_t j = 0; j < pose_points.size(); ++j) {
        const int b = kStoreBase + 4 * static_cast<int>(j);
        line(fmt::format("DPRNT[P{}*X#{}[{}{}]*Y#{}[{}{}]*Z#{}[{}{}]*T#{}[{}0]]", pose_points[j], b, kIntDigits, kDecimals,
                         b + 1, kIntDigits, kDecimals, b + 2, kIntDigits, kDecimals, b + 3, kTimeDigits));
      }
      pose_points.clear();
    };
    for (const auto& op : p.ops) {
      const Eigen::Vector3d& x = op.xyz;
      switch (op.kind) {
        case nc::Op::Kind::Comment: commentLines(op.text); break;
        case nc::Op::Kind::Rapid:
          line(op.z_only ? fmt::format("G00 Z{}", L(x.z())) : fmt::format("G00 X{} Y{} Z{}", L(x.x()), L(x.y()), L(x.z())));
          break;
        case nc::Op::Kind::Linear:
          line(fmt::format("G01 X{} Y{} Z{} F{}", L(x.x()), L(x.y()), L(x.z()), F(op.feed)));
          break;
        case nc::Op::Kind::Index: {
          flush();
          std::string s = "G00";
          for (const auto& [axis, deg] : op.rotary) s += fmt::format(" {}{}", axis, Ang(deg));
          line(s);
          break;
        }
        case nc::Op::Kind::Probe: {
          const int id = op.point_id;
          if (id <= 0 || kLabelBase + id > kMaxLabel)
            throw std::invalid_argument(fmt::format("point id {} cannot be a Fanuc label (1..{})", id, kMaxLabel - kLabelBase));
          if (!(op.feed > 0)) throw std::invalid_argument(fmt::format("point {}: probing feed must be > 0", id));
          if (pose_points.size() >= static_cast<size_t>(kMaxPointsPerPose))
            throw std::invalid_argument(fmt::format(
                "pose {} has more than {} points: the Fanuc program stores them in #{}-#{}", op.pose_name,
                kMaxPointsPerPose, kStoreBase, kStoreBase + 4 * kMaxPointsPerPose - 1));
          const int b = kStoreBase + 4 * static_cast<int>(pose_points.size());
          const int label = kLabelBase + id;
          if (!op.text.empty()) commentLines(op.text);
          line(fmt::format("G31 X{} Y{} Z{} F{}", L(x.x()), L(x.y()), L(x.z()), F(op.feed)));
          line(fmt::format("#1={}", minus(5061, x.x(), 4)));
          line(fmt::format("#2={}", minus(5062, x.y(), 4)));
          line(fmt::format("#3={}", minus(5063, x.z(), 4)));
          line(fmt::format("IF[[#1*#1+#2*#2+#3*#3]GT{}]GOTO{}", no_trigger_sq, label));
          line(fmt::format("#3000=1(POINT {} NOT TRIGGERED)", id));
          line(fmt::format("N{}", label));
          line(fmt::format("#{}=#5061", b));
          line(fmt::format("#{}=#5062", b + 1));
          line(fmt::format("#{}=#5063", b + 2));
          line(fmt::format("#{}=#3001", b + 3));
          pose_points.push_back(id);
          break;
        }
      }
    }
    flush();
    line("DPRNT[END]");
    line("PCLOS");
    line("M30");
    line("%");
    return out;
  }

  std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const override {
    const bool inch = plan.machine.units == LengthUnit::Inch;
    const double k = inch ? 1.0 / kMmPerInch : 1.0;
    std::string out = fmt::format("ROTACAL-RESULTS DIALECT FANUC CYCLE {} POINTS {} UNIT {}\r\n", dprntText(plan.cycle),
                                  plan.points.size(), unitName(inch));
    for (const auto& t : run.points) {
      if (!plan.findPoint(t.point_id)) throw std::invalid_argument(fmt::format("run point {} is not in the plan", t.point_id));
      if (std::isnan(t.t_s))
        throw std::invalid_argument(fmt::format("point {} has no time: the Fanuc program always prints #3001", t.point_id));
      const Eigen::Vector3d x = t.position_m_mm * k;
      out += fmt::format("P{} X{} Y{} Z{} T{}\r\n", t.point_id, fanucDprntNumber(x.x(), kIntDigits, kDecimals),
                         fanucDprntNumber(x.y(), kIntDigits, kDecimals), fanucDprntNumber(x.z(), kIntDigits, kDecimals),
                         fanucDprntNumber(std::round(t.t_s * 1000.0), kTimeDigits, 0));
    }
    out += "END\r\n";
    return out;
  }

  MeasurementRun parseResults(const std::string& raw, const std::string& file, const ProbePlan& plan) const override {
    // Punch control codes (DC2/DC4 from POPEN/PCLOS, NUL feed) are dropped; '%' lines skipped.
    std::string text;
    for (char c : raw)
      if (c == '\n' || c == '\r' || c == '\t' || (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f)) text += c;
    const std::string expected_header = fmt::format("ROTACAL-RESULTS DIALECT FANUC CYCLE {} POINTS {} UNIT MM|INCH",
                                                    dprntText(plan.cycle), plan.points.size());
    ctl::PointCollector points(plan, file);
    bool header = false;
    int end_line = 0;
    double k = 1.0;
    int last = 1;
    for (const auto& l : ctl::splitLines(text)) {
      const std::string s = ctl::trim(l.text);
      if (s.empty() || s == "%") continue;
      last = l.number;
      if (end_line) ctl::fail(file, l.number, fmt::format("text after END (line {}): '{}'", end_line, s));
      const auto t = ctl::tokens(s);
      if (t[0] == "ROTACAL-RESULTS") {
        if (header) ctl::fail(file, l.number, "a second header line: one run per results file");
        header = true;
        if (t.size() != 9 || t[1] != "DIALECT" || t[3] != "CYCLE" || t[5] != "POINTS" || t[7] != "UNIT")
          ctl::fail(file, l.number, fmt::format("expected the header '{}', got '{}'", expected_header, s));
        if (t[2] != "FANUC") ctl::fail(file, l.number, fmt::format("results of dialect '{}', expected FANUC", t[2]));
        if (t[4] != dprntText(plan.cycle))
          ctl::fail(file, l.number, fmt::format("results of cycle '{}', the plan is '{}'", t[4], dprntText(plan.cycle)));
        const auto n = ctl::parseDigits(t[6]);
        if (!n) ctl::fail(file, l.number, fmt::format("POINTS '{}' is not a number", t[6]));
        if (static_cast<size_t>(*n) != plan.points.size())
          ctl::fail(file, l.number, fmt::format("header says POINTS {} but the plan has {} points", *n, plan.points.size()));
        if (t[8] == "MM") k = 1.0;
        else if (t[8] == "INCH") k = kMmPerInch;
        else ctl::fail(file, l.number, fmt::format("UNIT '{}' must be MM or INCH", t[8]));
        continue;
      }
      if (!header) ctl::fail(file, l.number, fmt::format("expected the header '{}', got '{}'", expected_header, s));
      if (s == "END") {
        end_line = l.number;
        continue;
      }
      parsePoint(s, l.number, file, k, points);
    }
    if (!header) ctl::fail(file, 1, fmt::format("empty results file: expected the header '{}'", expected_header));
    if (!end_line) {
      if (const int missing = points.firstMissing())
        ctl::fail(file, last,
                  fmt::format("point {} is missing and there is no END line: the program stopped early (a point that "
                              "does not trigger raises alarm 3001)",
                              missing));
      ctl::fail(file, last, "no END line after the last point: the file is incomplete");
    }
    return points.finish(last);
  }

  std::string writeOffsets(const OffsetRequest& r) const override {
    ctl::requirePlausible(r);
    const ProbePlan& plan = *r.plan;
    const MachineModel& m = plan.machine;
    const bool ac = r.identified.kinematics == Kinematics::TableAC;
    const bool inch = m.units == LengthUnit::Inch;
    const double k = inch ? 1.0 / kMmPerInch : 1.0;
    const std::string u = inch ? "INCH" : "MM";
    const LocationErrors& e = r.identified;
    const char tilt = ac ? 'A' : 'B';
    const Eigen::Vector3d shift = ac ? Eigen::Vector3d(e.get("dx_AY"), e.get("dy_AY"), e.get("dz_AY"))
                                     : Eigen::Vector3d(e.get("dx_BY"), e.get("dy_CB"), e.get("dz_BY"));
    const double zero_deg = (m.hasRotary(tilt) ? m.controllerSign(tilt, kDialect) : 1) *
                            radToDeg(e.get(ac ? "a_AY" : "b_BY"));
    const Eigen::Vector3d second = ac ? Eigen::Vector3d(0, e.get("dy_CA"), 0) : Eigen::Vector3d(e.get("dx_CB"), 0, 0);

    std::string out;
    auto line = [&](const std::string& s) { out += s + "\n"; };
    auto commentLines = [&](std::string_view text) {
      for (const auto& c : comments(text)) line(c);
    };
    line("%");
    commentLines(fmt::format("ROTACAL G54 CORRECTION, TABLE {}/C, FANUC. RUN IN MDI OR A SETUP PROGRAM.", tilt));
    commentLines(fmt::format("PROVENANCE: {} CYCLE {} MACHINE {}", r.report_file.empty() ? "NO REPORT" : r.report_file,
                             plan.cycle, m.name));
    commentLines("IDENTIFIED, PAPERS CONVENTION, VALUE +- STANDARD UNCERTAINTY K=1:");
    for (const auto& s : ctl::identifiedLines(r)) commentLines(s);
    commentLines(fmt::format("SHIFTS G54 BY THE {} PIVOT AND THE {} ZERO ERROR. G10 L2 UNDER G91 ADDS TO THE OFFSET - "
                             "UNVERIFIED: CHECK THE G54 PAGE BEFORE AND AFTER.",
                             tilt, tilt));
    line(fmt::format("G91 G10 L2 P1 X{} Y{} Z{} {}{}", ctl::fixed(shift.x() * k, 4), ctl::fixed(shift.y() * k, 4),
                     ctl::fixed(shift.z() * k, 4), tilt, ctl::fixed(zero_deg, 4)));
    line("G90");
    commentLines(ac ? "NOT APPLIED BY THE SHIFT, REPORTED ONLY: DY-CA, B-AY, C-AY, B-CA."
                    : "NOT APPLIED BY THE SHIFT, REPORTED ONLY: DX-CB, A-BY, C-BY, A-CB.");
    commentLines(fmt::format(
        "WITH TCP: PARAMETERS 19700-19702 ROTARY TABLE POSITION, ADD X {} Y {} Z {} {} - OLD VALUES NOT KNOWN HERE, "
        "PARAMETER NUMBERS AND UNITS UNVERIFIED.",
        ctl::fixed(shift.x() * k, 4), ctl::fixed(shift.y() * k, 4), ctl::fixed(shift.z() * k, 4), u));
    commentLines(fmt::format("PARAMETERS 19703-19705 OFFSET 1ST TO 2ND TABLE AXIS, ADD X {} Y {} Z {} {} - UNVERIFIED.",
                             ctl::fixed(second.x() * k, 4), ctl::fixed(second.y() * k, 4), ctl::fixed(second.z() * k, 4),
                             u));
    line("%");
    return out;
  }

  std::vector<std::string> check(const std::string& text, const ProbePlan& plan) const override {
    const auto blocks = nc::readProgram(text);
    std::vector<std::string> out = ctl::readerIssues(blocks);
    auto problem = [&](int line, const std::string& what) { out.push_back(fmt::format("{}: {}", line, what)); };
    int probes = 0;
    // The program number O.... may only be the first block (after the opening '%').
    const size_t first = ctl::nextNonBlank(blocks, static_cast<size_t>(-1));
    const size_t o_block = first < blocks.size() && blocks[first].percent ? ctl::nextNonBlank(blocks, first) : first;
    for (size_t i = 0; i < blocks.size(); ++i) {
      const nc::Block& b = blocks[i];
      if (b.raw.size() > kMaxLineChars)
        problem(b.line, fmt::format("line has {} characters, more than {}", b.raw.size(), kMaxLineChars));
      for (char c : b.code)
        if (c >= 'a' && c <= 'z') {
          problem(b.line, "lower-case letters outside comments");
          break;
        }
      for (const auto& c : b.comments)
        if (c.find_first_of("abcdefghijklmnopqrstuvwxyz") != std::string::npos) {
          problem(b.line, "lower-case letters in a comment (not accepted by every Fanuc)");
          break;
        }
      if (b.control) {
        if (!b.oword.empty()) problem(b.line, "o-word control ('o.. if') is LinuxCNC, not Fanuc Macro B");
        if (b.code.find("#<") != std::string::npos) problem(b.line, "named parameters #<..> are not Fanuc Macro B");
        if (b.keyword == "DPRNT") {
          // DPRNT[text #v[ab] ...]: text of A-Z 0-9 * - . / only.
          const size_t open = b.code.find('[');
          const size_t close = b.code.rfind(']');
          if (open == std::string::npos || close == std::string::npos || close < open) {
            problem(b.line, "DPRNT without [ ]");
          } else {
            const std::string body = b.code.substr(open + 1, close - open - 1);
            for (size_t k = 0; k < body.size(); ++k) {
              const char c = body[k];
              if (c == '#') {
                ++k;
                while (k < body.size() && body[k] >= '0' && body[k] <= '9') ++k;
                if (k < body.size() && body[k] == '[') {
                  const size_t e = body.find(']', k);
                  if (e == std::string::npos || e - k != 3) problem(b.line, "DPRNT format must be #v[ab]");
                  k = e == std::string::npos ? body.size() : e;
                } else {
                  --k;
                }
                continue;
              }
              const bool ok = (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '*' || c == '-' || c == '.' ||
                              c == '/';
              if (!ok) {
                problem(b.line, fmt::format("DPRNT text has '{}' (only A-Z 0-9 * - . /)", c));
                break;
              }
            }
          }
        }
        continue;
      }
      for (const auto& w : b.words) {
        if (w.letter == 'O' && i != o_block) problem(b.line, "O word (program number) after the start of the program");
        const bool needs_point = w.letter == 'X' || w.letter == 'Y' || w.letter == 'Z' || w.letter == 'A' ||
                                 w.letter == 'B' || w.letter == 'C' || w.letter == 'F';
        if (needs_point && w.value && !w.has_decimal_point)
          problem(b.line, fmt::format("{}{} has no decimal point (read in least input increments)", w.letter, w.text));
      }
      if (!b.hasWord('G', 31)) continue;
      ++probes;
      if (!b.find('X') && !b.find('Y') && !b.find('Z')) problem(b.line, "G31 without an axis word");
      if (!b.find('F')) problem(b.line, "G31 without F on its block");
      // Within the next 8 blocks: #5061-#5063 read, IF[...]GOTO n, then #3000 alarm, then N n.
      bool reads[3] = {false, false, false};
      bool ok = false;
      size_t j = i;
      for (int n = 0; n < 8 && !ok; ++n) {
        j = ctl::nextNonBlank(blocks, j);
        if (j >= blocks.size()) break;
        const nc::Block& c = blocks[j];
        if (!c.control) break;
        for (int a = 0; a < 3; ++a)
          if (c.code.find(fmt::format("#{}", 5061 + a)) != std::string::npos) reads[a] = true;
        if (c.keyword != "IF") continue;
        const size_t g = c.code.find("GOTO");
        const auto label = g == std::string::npos ? std::nullopt : ctl::parseDigits(ctl::trim(c.code.substr(g + 4)));
        const size_t alarm = ctl::nextNonBlank(blocks, j);
        const size_t target = alarm < blocks.size() ? ctl::nextNonBlank(blocks, alarm) : blocks.size();
        ok = label && reads[0] && reads[1] && reads[2] && alarm < blocks.size() &&
             blocks[alarm].code.rfind("#3000=", 0) == 0 && target < blocks.size() && !blocks[target].control &&
             blocks[target].hasWord('N', static_cast<double>(*label));
        break;
      }
      if (!ok)
        problem(b.line, "G31 is not followed by the no-trigger check (#5061-#5063 vs the end point, IF[..]GOTO n, "
                        "#3000 alarm, N n)");
    }
    const int last_line = blocks.empty() ? 1 : blocks.back().line;
    if (static_cast<size_t>(probes) != plan.points.size())
      problem(last_line, fmt::format("{} G31 moves, the plan has {} points", probes, plan.points.size()));
    for (auto& s : ctl::strokeProblems(blocks, plan, kDialect)) out.push_back(std::move(s));
    // Starts with '%', ends with M30 then '%'.
    std::vector<const nc::Block*> nonblank;
    for (const auto& b : blocks)
      if (!b.empty()) nonblank.push_back(&b);
    if (nonblank.empty() || !nonblank.front()->percent) problem(1, "the program does not start with '%'");
    if (nonblank.size() < 2 || !nonblank.back()->percent) problem(last_line, "the program does not end with '%'");
    const nc::Block* last_code = nullptr;
    for (size_t i = 0; i + 1 < nonblank.size(); ++i)
      if (!nonblank[i]->code.empty() && !nonblank[i]->percent) last_code = nonblank[i];
    if (!last_code || !last_code->hasWord('M', 30))
      problem(last_code ? last_code->line : last_line, "the program does not end with M30 before the closing '%'");
    return out;
  }

 private:
  /// "P17 X 123.4560 Y-200.0000 Z 173.0000 T    12345": letters in order, any spaces, numbers
  /// with optional sign, leading zeros or spaces, optional trailing point.
  static void parsePoint(const std::string& s, int line, const std::string& file, double k, ctl::PointCollector& points) {
    size_t i = 0;
    auto skip = [&]() {
      while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    };
    if (s[0] != 'P')
      ctl::fail(file, line, fmt::format("expected 'P<id> X.. Y.. Z.. T..', END or the header, got '{}'", s));
    ++i;
    const size_t id_begin = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    const auto id = ctl::parseDigits(s.substr(id_begin, i - id_begin));
    if (!id || *id == 0 || (i < s.size() && s[i] != ' ' && s[i] != '\t'))
      ctl::fail(file, line, fmt::format("'{}' does not start with a point id P<n>", s));
    const char letters[] = {'X', 'Y', 'Z', 'T'};
    double v[4] = {0, 0, 0, 0};
    for (int n = 0; n < 4; ++n) {
      skip();
      if (i >= s.size() || s[i] != letters[n])
        ctl::fail(file, line, fmt::format("point {}: expected '{}' at column {}", *id, letters[n], i + 1));
      ++i;
      skip();
      const size_t b = i;
      while (i < s.size() && s[i] != ' ' && s[i] != '\t' && (n == 3 || s[i] != letters[n + 1])) ++i;
      const std::string token = s.substr(b, i - b);
      const auto value = ctl::parseNumber(token);
      if (!value) ctl::fail(file, line, fmt::format("{} '{}' of point {} is not a number", letters[n], token, *id));
      v[n] = *value;
    }
    skip();
    if (i != s.size()) ctl::fail(file, line, fmt::format("point {}: unexpected text '{}' after T", *id, s.substr(i)));
    points.add(line, static_cast<int>(*id), Eigen::Vector3d(v[0], v[1], v[2]) * k, v[3] / 1000.0);
  }
};

}  // namespace

std::string fanucDprntNumber(double value, int integer_digits, int decimals) {
  const std::string s = ctl::fixed(value, decimals);
  const int width = integer_digits + (decimals > 0 ? decimals + 1 : 0);
  return fmt::format("{:>{}}", s, width);
}

const Dialect& fanucDialect() {
  static const FanucDialect d;
  return d;
}

}  // namespace rotacal
