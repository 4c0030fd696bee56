// Okuma OSP-P300 (user task) (../shared/reference/controllers.md Sec. 6, mostly from real
// code, not manuals): G31 skip moves, skip position read from VSKPX/VSKPY/VSKPZ, storage in
// common variables VC1-VC7, a no-trigger check that raises a user alarm (VUACM[1] text +
// VDOUT[992]), results written with FWRITC/PUT/WRITE/CLOSE, compensation as a work-offset shift
// (VZOFX[n]... writable from the program).
//
// Results, as the program's PUT/WRITE lines write them:
//   ROTACAL-RESULTS DIALECT OKUMA CYCLE TOUCH154 POINTS 154 UNIT MM
//   P17 X123.4560 Y-200.0000 Z173.0000
//   END
// and "NOT-TRIGGERED P17" before the alarm when a point does not trigger. No time: Okuma's time
// variables are UNVERIFIED; t_s = NaN (the analysis then uses the plan's times).
//
// UNVERIFIED, and the conservative choice made for each:
// - VSKPX/Y/Z as the skip position in work coordinates, and the no-trigger behaviour of G31:
//   the check tests the distance to the end point (an untriggered skip ends there), so a control
//   whose VSKP* hold the end point, or that ignores G31's signal, raises the alarm.
// - File output (no documented form; Autodesk's Okuma post writes no results file): the
//   user-task I/O commands FWRITC <file>;A (open for append), PUT 'text' and PUT VCn,4 (value
//   with 4 decimals; VCn,5 on an inch machine) into the line buffer, WRITE C (write the buffer
//   as one line), CLOSE C. The
//   parser reads exactly that text and tolerates spaces, '+' signs and leading zeros in numbers.
// - Line length: 80 characters. G93 itself is UNVERIFIED for OSP: never written, so a program
//   that moves under inverse time (004's fixed-tool-tip test) is refused (ctl::inverseTimeRefusal).
// - VC1-VC7 free for this program (standard: VC1-VC200).
#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <regex>
#include <set>
#include <stdexcept>

#include "controllers/common.hpp"
#include "controllers/dialects.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

constexpr const char* kDialect = "okuma";
constexpr size_t kMaxLineChars = 80;
constexpr int kLabelBase = 1000;  // label N<1000 + id> after each point's check

std::string unitName(bool inch) { return inch ? "INCH" : "MM"; }
// Decimals of the printed trigger coordinates (PUT VCn,d): 4 in mm, 5 in inch (4 inch decimals
// would round by up to 1.27 um and move the identified errors by up to 3.1 um, docs/dialects.md).
int resultDecimals(bool inch) { return inch ? 5 : 4; }

std::string safeName(std::string_view name) {
  std::string s;
  for (char c : ctl::upper(name)) s += ((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) ? c : '-';
  return s.empty() ? "ROTACAL" : s;
}

/// "(...)" comment lines: upper case, no parentheses inside, at most 80 characters.
std::vector<std::string> comments(std::string_view text) {
  std::string s;
  for (char c : ctl::upper(text)) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == ' ' || c == '.' || c == ',' || c == '-' ||
                    c == '+' || c == '/' || c == ':' || c == '=';
    const char d = c == '_' ? '-' : (ok ? c : ' ');
    if (d == ' ' && (s.empty() || s.back() == ' ')) continue;
    s += d;
  }
  std::vector<std::string> out;
  for (const auto& piece : ctl::wrap(s, kMaxLineChars - 2)) out.push_back("(" + piece + ")");
  if (out.empty()) out.push_back("()");
  return out;
}

class OkumaDialect final : public Dialect {
 public:
  std::string_view name() const override { return kDialect; }
  std::string_view programExtension() const override { return ".min"; }
  std::string_view resultsExtension() const override { return ".txt"; }

  std::vector<std::string> commentLines(std::string_view text) const override { return comments(text); }

  std::string writeProgram(const nc::Program& p) const override {
    const bool inch = p.unit == nc::Unit::Inch;
    auto L = [](double v) { return ctl::fixed(v, 4); };
    auto F = [&](double v) { return ctl::fixed(v, inch ? 3 : 1); };
    ctl::requireInverseTimeAllowed(p, kDialect);
    int probes = 0;
    for (const auto& op : p.ops) probes += op.kind == nc::Op::Kind::Probe;
    if (p.point_count != 0 && p.point_count != probes)
      throw std::invalid_argument(fmt::format("program has {} probing moves but point_count {}", probes, p.point_count));
    const std::string file = safeName(p.results_file.empty() ? "ROTACAL" : p.results_file);
    const std::string no_trigger_sq = inch ? "0.000001" : "0.0001";
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
    auto put = [&](const std::string& text) {
      line(fmt::format("PUT '{}'", text));
      line("WRITE C");
    };
    line(fmt::format("O{} (ROTACAL)", ctl::programNumber(p)));
    commentLines(p.name + " generated by rotacal, dialect okuma OSP-P300 user task");
    for (const auto& h : p.header) commentLines(h);
    commentLines("X Y Z = probe ball centre in machine coordinates: work offset at the intersection of the rotary "
                 "axes, no TCP or tilted plane active");
    commentLines(fmt::format("results: FWRITC to MD1:{}.TXT - output commands UNVERIFIED; uses VC1 to VC7", file));
    commentLines("a point that does not trigger raises a user alarm");
    line(inch ? "G20" : "G21");
    line("G17 G40 G80 G90 G94");
    line("G15 H1");
    if (p.probe_tool > 0) {
      line(fmt::format("T{} M06", p.probe_tool));
      line(fmt::format("G56 H{}", p.probe_tool));
    }
    line(fmt::format("FWRITC MD1:{}.TXT;A", file));
    put(fmt::format("ROTACAL-RESULTS DIALECT OKUMA CYCLE {} POINTS {} UNIT {}", safeName(p.cycle), probes, unitName(inch)));
    ctl::ModeGuard guard;
    for (const auto& op : p.ops) {
      const Eigen::Vector3d& x = op.xyz;
      guard.apply(op);
      switch (op.kind) {
        case nc::Op::Kind::Comment: commentLines(op.text); break;
        case nc::Op::Kind::Rapid: line(ctl::rapidBlock("G00", op, 4)); break;
        case nc::Op::Kind::Linear: line(ctl::linearBlock("G01", op, 4, inch)); break;
        case nc::Op::Kind::Index: {
          ctl::requireRapidIndex(op, "okuma");
          std::string s = "G00";
          for (const auto& [axis, deg] : op.rotary) s += fmt::format(" {}{}", axis, L(deg));
          line(s);
          break;
        }
        case nc::Op::Kind::Mode:  // never G93: refused above (ctl::inverseTimeRefusal)
          line(fmt::format("{} G94", op.incremental ? "G91" : "G90"));
          break;
        case nc::Op::Kind::RotaryLinear: line(ctl::rotaryLinearWords(op, p.unit, " ")); break;
        case nc::Op::Kind::Pause:
          if (op.dwell_s > 0) line(fmt::format("G04 F{}", ctl::trimmed(op.dwell_s, 3)));  // UNVERIFIED: F seconds
          else line("M00");
          break;
        case nc::Op::Kind::Dwell:
        case nc::Op::Kind::Read:
        case nc::Op::Kind::RepeatBegin:
        case nc::Op::Kind::RepeatEnd:
          // The R-test program (002): dwell, logger trigger and loops are spelled for linuxcnc only so far.
          throw std::invalid_argument(fmt::format("the {} program cannot express an R-test dwell, logger trigger or loop "
                                                  "in this version: generate this program for linuxcnc", "okuma"));
        case nc::Op::Kind::Probe: {
          const int id = op.point_id;
          if (id <= 0 || id > 8999) throw std::invalid_argument(fmt::format("point id {} out of range 1..8999", id));
          if (!(op.feed > 0)) throw std::invalid_argument(fmt::format("point {}: probing feed must be > 0", id));
          if (op.retract_mm > 0)
            throw std::invalid_argument(fmt::format(
                "point {}: the okuma program records a single touch; a double touch (retract_mm > 0) is not implemented",
                id));
          if (!op.text.empty()) commentLines(op.text);
          line(fmt::format("G31 X{} Y{} Z{} F{}", L(x.x()), L(x.y()), L(x.z()), F(op.feed)));
          line("VC1=VSKPX");
          line("VC2=VSKPY");
          line("VC3=VSKPZ");
          for (int a = 0; a < 3; ++a) line(ctl::endPointCheckStatement(*ctl::endPointCheck(kDialect), a, x[a], 4));
          line(fmt::format("IF [VC4*VC4+VC5*VC5+VC6*VC6 GT {}] N{}", no_trigger_sq, kLabelBase + id));
          put(fmt::format("NOT-TRIGGERED P{}", id));
          line("CLOSE C");
          line(fmt::format("VUACM[1]='PT{} NO TRIGGER'", id));
          line(fmt::format("VDOUT[992]={}", kLabelBase + id));
          line(fmt::format("N{} PUT 'P{} X'", kLabelBase + id, id));
          line(fmt::format("PUT VC1,{}", resultDecimals(inch)));
          line("PUT ' Y'");
          line(fmt::format("PUT VC2,{}", resultDecimals(inch)));
          line("PUT ' Z'");
          line(fmt::format("PUT VC3,{}", resultDecimals(inch)));
          line("WRITE C");
          break;
        }
      }
    }
    put("END");
    line("CLOSE C");
    line("M02");
    return out;
  }

  std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const override {
    const bool inch = plan.machine.units == LengthUnit::Inch;
    const double k = inch ? 1.0 / kMmPerInch : 1.0;
    std::string out = fmt::format("ROTACAL-RESULTS DIALECT OKUMA CYCLE {} POINTS {} UNIT {}\r\n", safeName(plan.cycle),
                                  plan.points.size(), unitName(inch));
    for (const auto& t : run.points) {
      if (!plan.findPoint(t.point_id)) throw std::invalid_argument(fmt::format("run point {} is not in the plan", t.point_id));
      const Eigen::Vector3d x = t.position_m_mm * k;
      const int d = resultDecimals(inch);
      out += fmt::format("P{} X{} Y{} Z{}\r\n", t.point_id, ctl::fixed(x.x(), d), ctl::fixed(x.y(), d), ctl::fixed(x.z(), d));
    }
    out += "END\r\n";
    return out;
  }

  MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const override {
    return ctl::parseTaggedResults(text, file, plan, "OKUMA", safeName(plan.cycle), " (FWRITC appends: delete the old file)");
  }

  std::string writeOffsets(const OffsetRequest& r) const override {
    ctl::requirePlausible(r);
    const ProbePlan& plan = *r.plan;
    const MachineModel& m = plan.machine;
    const bool ac = r.identified.kinematics == Kinematics::TableAC;
    const bool inch = m.units == LengthUnit::Inch;
    const double k = inch ? 1.0 / kMmPerInch : 1.0;
    const LocationErrors& e = r.identified;
    const char tilt = ac ? 'A' : 'B';
    const Eigen::Vector3d shift = ac ? Eigen::Vector3d(e.get("dx_AY"), e.get("dy_AY"), e.get("dz_AY"))
                                     : Eigen::Vector3d(e.get("dx_BY"), e.get("dy_CB"), e.get("dz_BY"));
    const double zero_deg = (m.hasRotary(tilt) ? m.controllerSign(tilt, kDialect) : 1) *
                            radToDeg(e.get(ac ? "a_AY" : "b_BY"));
    std::string out;
    auto line = [&](const std::string& s) { out += s + "\n"; };
    auto commentLines = [&](std::string_view text) {
      for (const auto& c : comments(text)) line(c);
    };
    auto add = [&](const std::string& var, double v, int decimals) {
      line(fmt::format("{0}[1]={0}[1]{1}{2}", var, v < 0 ? "-" : "+", ctl::fixed(std::abs(v), decimals)));
    };
    line("O9001 (ROTACAL OFFSET)");
    commentLines(fmt::format("ROTACAL WORK OFFSET CORRECTION, TABLE {}/C, OKUMA OSP-P300. PROVENANCE: {} CYCLE {} "
                             "MACHINE {}",
                             tilt, r.report_file.empty() ? "NO REPORT" : r.report_file, plan.cycle, m.name));
    commentLines("IDENTIFIED, PAPERS CONVENTION, VALUE +- STANDARD UNCERTAINTY K=1:");
    for (const auto& s : ctl::identifiedLines(r)) commentLines(s);
    commentLines(fmt::format("WHAT IT CHANGES: WORK OFFSET 1 (G15 H1) X Y Z SHIFTED BY THE {} PIVOT, {} BY THE ZERO "
                             "ERROR. NEW = OLD + CHANGE; OLD VALUES ARE ON THE CONTROL. {} - UNVERIFIED SIGN: CHECK "
                             "THE WORK OFFSET PAGE BEFORE AND AFTER.",
                             tilt, tilt, inch ? "INCH" : "MM"));
    add("VZOFX", shift.x() * k, 4);
    add("VZOFY", shift.y() * k, 4);
    add("VZOFZ", shift.z() * k, 4);
    add(ac ? "VZOFA" : "VZOFB", zero_deg, 4);
    commentLines(ac ? "REPORTED ONLY: DY-CA, B-AY, C-AY, B-CA." : "REPORTED ONLY: DX-CB, A-BY, C-BY, A-CB.");
    line("M02");
    return out;
  }

  std::vector<std::string> check(const std::string& text, const ProbePlan& plan, const nc::Shape& shape) const override {
    std::vector<std::string> out;
    auto problem = [&](int line, const std::string& what) { out.push_back(fmt::format("{}: {}", line, what)); };
    const auto ls = ctl::splitLines(text);
    std::vector<std::string> code(ls.size());
    for (size_t i = 0; i < ls.size(); ++i) {
      std::string c;
      int depth = 0;
      bool quote = false;
      for (char ch : ls[i].text) {
        if (ch == '\'' && depth == 0) quote = !quote;
        if (!quote && ch == '(') ++depth;
        if (depth == 0) c += ch;
        if (!quote && ch == ')') {
          if (--depth < 0) problem(ls[i].number, "')' without '('");
        }
      }
      if (depth > 0) problem(ls[i].number, "comment not closed");
      if (quote) problem(ls[i].number, "quote not closed");
      code[i] = ctl::trim(c);
    }
    auto nextCode = [&](size_t i) {
      for (size_t j = i + 1; j < ls.size(); ++j)
        if (!code[j].empty()) return j;
      return ls.size();
    };
    std::set<std::string> labels;
    static const std::regex label_re(R"(^(N\d+) )");
    for (const auto& c : code) {
      std::smatch m;
      if (std::regex_search(c, m, label_re)) labels.insert(m[1].str());
    }
    static const std::regex motion(R"(^G(00|01|31)( [XYZABC]-?\d+\.\d+)+( F\d+\.\d+)?$)");
    std::string motion_text;
    bool inch = false, open = false;
    int probes = 0;
    for (size_t i = 0; i < ls.size(); ++i) {
      const std::string& s = code[i];
      const int n = ls[i].number;
      if (ls[i].text.size() > kMaxLineChars)
        problem(n, fmt::format("line has {} characters, more than {}", ls[i].text.size(), kMaxLineChars));
      if (s == "G20" || s == "G21") inch = s == "G20";
      if (s.rfind("FWRITC ", 0) == 0) open = true;
      if ((s.rfind("PUT ", 0) == 0 || s.find(" PUT ") != std::string::npos || s == "WRITE C") && !open)
        problem(n, "output before FWRITC (or after CLOSE C)");
      // The CLOSE C of a no-trigger branch (followed by the alarm) does not end the main output.
      if (s == "CLOSE C" && !(nextCode(i) < ls.size() && code[nextCode(i)].rfind("VUACM", 0) == 0)) open = false;
      static const std::regex g93(R"(\bG93\b)");
      if (std::regex_search(s, g93))
        problem(n, shape.inverse_time ? ctl::inverseTimeRefusal(kDialect)
                                           : "G93 inverse time: rotacal probes and positions under G94 only");
      const bool is_motion = s.rfind("G00 ", 0) == 0 || s.rfind("G01 ", 0) == 0 || s.rfind("G31 ", 0) == 0;
      if (is_motion && !std::regex_match(s, motion))
        problem(n, fmt::format("motion block '{}' is not of the generated form (decimal point on every word)", s));
      motion_text += (is_motion ? s : std::string()) + "\n";
      const size_t g = s.find("] N");
      if (s.rfind("IF ", 0) == 0 && (g == std::string::npos || !labels.count(ctl::trim(s.substr(g + 2)))))
        problem(n, "IF without a defined label to jump to");
      if (s.rfind("G31 ", 0) != 0) continue;
      ++probes;
      if (s.find(" F") == std::string::npos) problem(n, "G31 without F on its block");
      std::vector<std::string> next;
      size_t j = i;
      for (int c = 0; c < 13; ++c) {
        j = nextCode(j);
        next.push_back(j < ls.size() ? code[j] : "");
      }
      bool ok = next[0] == "VC1=VSKPX" && next[1] == "VC2=VSKPY" && next[2] == "VC3=VSKPZ" &&
                next[3].rfind("VC4=VC1", 0) == 0 && next[4].rfind("VC5=VC2", 0) == 0 && next[5].rfind("VC6=VC3", 0) == 0 &&
                next[6].rfind("IF [VC4*VC4+VC5*VC5+VC6*VC6 GT ", 0) == 0 && next[10].rfind("VUACM[1]=", 0) == 0 &&
                next[11].rfind("VDOUT[992]=", 0) == 0;
      if (ok) {
        const std::string label = ctl::trim(next[6].substr(next[6].find("] N") + 2));
        ok = next[12].rfind(label + " ", 0) == 0;
      }
      if (!ok)
        problem(n, "G31 is not followed by the no-trigger check (VSKPX-Z read, IF [distance GT ..] N.., "
                   "VUACM and VDOUT[992] alarm, then the label)");
    }
    if (open) problem(ls.empty() ? 1 : ls.back().number, "FWRITC without CLOSE C");
    if (static_cast<size_t>(probes) != shape.probes)
      problem(ls.empty() ? 1 : ls.back().number, fmt::format("{} G31 moves, the plan has {} points", probes, shape.probes));
    for (auto& s : ctl::inverseTimeProblems(nc::readProgram(text), ctl::isProbingBlock)) out.push_back(std::move(s));
    const auto blocks = nc::readProgram(std::string(inch ? "G20" : "G21") + "\n" + motion_text);
    std::vector<nc::Block> shifted;
    for (size_t i = 0; i < blocks.size(); ++i) {
      nc::Block b = blocks[i];
      b.line = static_cast<int>(i);  // line 0: the unit; then the program's own numbering
      shifted.push_back(std::move(b));
    }
    for (auto& s : ctl::strokeProblems(shifted, plan, kDialect)) out.push_back(std::move(s));
    size_t last = ls.size();
    for (size_t i = 0; i < ls.size(); ++i)
      if (!code[i].empty()) last = i;
    if (last == ls.size() || code[last] != "M02") problem(last == ls.size() ? 1 : ls[last].number, "the program does not end with M02");
    return out;
  }
};

}  // namespace

const Dialect& okumaDialect() {
  static const OkumaDialect d;
  return d;
}

}  // namespace rotacal
