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
#include <cstdlib>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <stdexcept>

#include "controllers/dialect.hpp"
#include "controllers/end_point_check.hpp"
#include "controllers/offsets.hpp"
#include "controllers/program_checking.hpp"
#include "controllers/program_writing.hpp"
#include "controllers/tagged_results.hpp"
#include "controllers/text.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

constexpr const char* kDialect = "okuma";
constexpr size_t kMaxLineChars = 80;
constexpr int kLabelBase = 1000;  // label N<1000 + id> after each point's check

std::string unitName(bool inch) { return inch ? "INCH" : "MM"; }

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

DialectIdentity okumaIdentity() {
  DialectIdentity d;
  d.language = ProgramLanguage::IsoGcode;
  d.numbers_programs = true;
  d.end_point_check = EndPointCheck{{"VC4", "VC5", "VC6"}, {"VC1", "VC2", "VC3"}};
  d.inverse_time_refusal = "inverse-time feed (G93) is UNVERIFIED for OSP (controllers.md Sec. 6.5)";
  d.comp_table_refusal = "no source gives the OSP's pitch / rotary compensation table form (docs/dialects.md); give "
                         "the table of --dialect csv to the machine builder";
  return d;
}

class OkumaDialect final : public ctl::TaggedResultsDialect {
 public:
  // FWRITC appends: an old run stays in the file unless it is deleted.
  OkumaDialect()
      : TaggedResultsDialect({kDialect, ".min", "OKUMA", safeName, 0, "\r\n", " (FWRITC appends: delete the old file)"},
                             okumaIdentity()) {}
  std::vector<std::string> commentLines(std::string_view text) const override { return comments(text); }

  std::string writeProgram(const nc::Program& p) const override {
    const bool inch = p.unit == nc::Unit::Inch;
    ctl::requireInverseTimeAllowed(p, kDialect);
    const int probes = ctl::probeCount(p);
    const std::string file = safeName(p.results_file.empty() ? "ROTACAL" : p.results_file);
    const std::string no_trigger_sq = inch ? "0.000001" : "0.0001";
    ctl::LineWriter w(comments, kMaxLineChars);
    auto put = [&](const std::string& text) {
      w.line(fmt::format("PUT '{}'", text));
      w.line("WRITE C");
    };
    w.line(fmt::format("O{} (ROTACAL)", ctl::programNumber(p)));
    w.provenance(p, "okuma OSP-P300 user task");
    w.comment("machine coordinates: the work offset as the line above says, no TCP or tilted plane active");
    w.comment(fmt::format("results: FWRITC to MD1:{}.TXT - output commands UNVERIFIED; uses VC1 to VC7", file));
    w.comment("a point that does not trigger raises a user alarm");
    w.line(inch ? "G20" : "G21");
    w.line("G17 G40 G80 G90 G94");
    w.line("G15 H1");
    if (p.probe_tool > 0) {
      w.line(fmt::format("T{} M06", p.probe_tool));
      w.line(fmt::format("G56 H{}", p.probe_tool));
    }
    w.line(fmt::format("FWRITC MD1:{}.TXT;A", file));
    put(fmt::format("ROTACAL-RESULTS DIALECT OKUMA CYCLE {} POINTS {} UNIT {}", safeName(p.cycle), probes, unitName(inch)));
    ctl::writeOps(p, {kDialect, "G00", "G01", 4, " "}, w, [&](const nc::Op& op) {
      const Eigen::Vector3d& x = op.xyz;
      switch (op.kind) {
        case nc::Op::Kind::Comment: w.comment(op.text); break;
        case nc::Op::Kind::Mode:  // never G93: refused above (ctl::inverseTimeRefusal)
          w.line(fmt::format("{} G94", op.incremental ? "G91" : "G90"));
          break;
        case nc::Op::Kind::Pause:
          if (op.dwell_s > 0) w.line(fmt::format("G04 F{}", ctl::trimmed(op.dwell_s, 3)));  // UNVERIFIED: F seconds
          else w.line("M00");
          break;
        case nc::Op::Kind::Probe: {
          const int id = op.point_id;
          if (id <= 0 || id > 8999) throw std::invalid_argument(fmt::format("point id {} out of range 1..8999", id));
          ctl::requireSingleTouch(op, kDialect);
          if (!op.text.empty()) w.comment(op.text);
          w.line(ctl::linearBlock("G31", op, 4, inch));
          w.line("VC1=VSKPX");
          w.line("VC2=VSKPY");
          w.line("VC3=VSKPZ");
          for (int a = 0; a < 3; ++a) w.line(ctl::endPointCheckStatement(*endPointCheck(), a, x[a], 4));
          w.line(fmt::format("IF [VC4*VC4+VC5*VC5+VC6*VC6 GT {}] N{}", no_trigger_sq, kLabelBase + id));
          put(fmt::format("NOT-TRIGGERED P{}", id));
          w.line("CLOSE C");
          w.line(fmt::format("VUACM[1]='PT{} NO TRIGGER'", id));
          w.line(fmt::format("VDOUT[992]={}", kLabelBase + id));
          w.line(fmt::format("N{} PUT 'P{} X'", kLabelBase + id, id));
          w.line(fmt::format("PUT VC1,{}", resultDecimals(inch)));
          w.line("PUT ' Y'");
          w.line(fmt::format("PUT VC2,{}", resultDecimals(inch)));
          w.line("PUT ' Z'");
          w.line(fmt::format("PUT VC3,{}", resultDecimals(inch)));
          w.line("WRITE C");
          break;
        }
        default: break;  // written by ctl::writeOps
      }
    });
    put("END");
    w.line("CLOSE C");
    w.line("M02");
    return w.text;
  }

  std::string writeOffsets(const OffsetRequest& r) const override {
    const ctl::OffsetBasis b(r, kDialect);
    const auto& [plan, m, e, ac, inch, k, tilt] = b;
    const Eigen::Vector3d shift = b.pivot();
    const double zero_deg = b.zeroDeg(kDialect);
    ctl::LineWriter w(comments);
    auto add = [&](const std::string& var, double v, int decimals) {
      w.line(fmt::format("{0}[1]={0}[1]{1}{2}", var, v < 0 ? "-" : "+", ctl::fixed(std::abs(v), decimals)));
    };
    w.line("O9001 (ROTACAL OFFSET)");
    w.comment(fmt::format("ROTACAL WORK OFFSET CORRECTION, TABLE {}/C, OKUMA OSP-P300. PROVENANCE: {} CYCLE {} "
                          "MACHINE {}",
                          tilt, r.report_file.empty() ? "NO REPORT" : r.report_file, plan.cycle, m.name));
    w.identified(r, "IDENTIFIED, PAPERS CONVENTION, VALUE +- STANDARD UNCERTAINTY K=1:");
    w.comment(fmt::format("WHAT IT CHANGES: WORK OFFSET 1 (G15 H1) X Y Z SHIFTED BY THE {} PIVOT, {} BY THE ZERO "
                          "ERROR. NEW = OLD + CHANGE; OLD VALUES ARE ON THE CONTROL. {} - UNVERIFIED SIGN: CHECK "
                          "THE WORK OFFSET PAGE BEFORE AND AFTER.",
                          tilt, tilt, inch ? "INCH" : "MM"));
    add("VZOFX", shift.x() * k, 4);
    add("VZOFY", shift.y() * k, 4);
    add("VZOFZ", shift.z() * k, 4);
    add(ac ? "VZOFA" : "VZOFB", zero_deg, 4);
    w.comment(ac ? "REPORTED ONLY: DY-CA, B-AY, C-AY, B-CA." : "REPORTED ONLY: DX-CB, A-BY, C-BY, A-CB.");
    w.line("M02");
    return w.text;
  }

  std::vector<std::string> check(const std::string& text, const ProbePlan& plan, const nc::Shape& shape) const override {
    ctl::TextCheck chk(text);
    for (size_t i = 0; i < chk.lines.size(); ++i) {
      std::string c;
      int depth = 0;
      bool quote = false;
      for (char ch : chk.lines[i].text) {
        if (ch == '\'' && depth == 0) quote = !quote;
        if (!quote && ch == '(') ++depth;
        if (depth == 0) c += ch;
        if (!quote && ch == ')') {
          if (--depth < 0) chk.problem(chk.lines[i].number, "')' without '('");
        }
      }
      if (depth > 0) chk.problem(chk.lines[i].number, "comment not closed");
      if (quote) chk.problem(chk.lines[i].number, "quote not closed");
      chk.code[i] = ctl::trim(c);
    }
    std::map<std::string, int> labels;  // label -> its line
    static const std::regex label_re(R"(^(N\d+) )");
    for (size_t i = 0; i < chk.code.size(); ++i) {
      std::smatch m;
      if (std::regex_search(chk.code[i], m, label_re)) labels.emplace(m[1].str(), chk.lines[i].number);
    }
    static const std::regex motion(R"(^G(00|01|31)( [XYZABC]-?\d+\.\d+)+( F\d+\.\d+)?$)");
    std::string motion_text;
    bool inch = false, open = false;
    int probes = 0;
    for (size_t i = 0; i < chk.lines.size(); ++i) {
      const std::string& s = chk.code[i];
      const int n = chk.lines[i].number;
      chk.lineLength(i, kMaxLineChars);
      if (s == "G20" || s == "G21") inch = s == "G20";
      if (s.rfind("FWRITC ", 0) == 0) open = true;
      if ((s.rfind("PUT ", 0) == 0 || s.find(" PUT ") != std::string::npos || s == "WRITE C") && !open)
        chk.problem(n, "output before FWRITC (or after CLOSE C)");
      // The CLOSE C of a no-trigger branch (followed by the alarm) does not end the main output.
      if (s == "CLOSE C" && !(chk.nextCode(i) < chk.lines.size() && chk.code[chk.nextCode(i)].rfind("VUACM", 0) == 0)) open = false;
      static const std::regex g93(R"(\bG93\b)");
      if (std::regex_search(s, g93))
        chk.problem(n, shape.inverse_time ? ctl::inverseTimeRefusal(kDialect)
                                           : "G93 inverse time: rotacal probes and positions under G94 only");
      const bool is_motion = s.rfind("G00 ", 0) == 0 || s.rfind("G01 ", 0) == 0 || s.rfind("G31 ", 0) == 0;
      if (is_motion && !std::regex_match(s, motion))
        chk.problem(n, fmt::format("motion block '{}' is not of the generated form (decimal point on every word)", s));
      motion_text += (is_motion ? s : std::string()) + "\n";
      const size_t g = s.find("] N");
      if (s.rfind("IF ", 0) == 0 && (g == std::string::npos || !labels.count(ctl::trim(s.substr(g + 2)))))
        chk.problem(n, "IF without a defined label to jump to");
      // rotacal's programs jump forward only, past an alarm: a jump back may never end, and a
      // subprogram runs moves the verifier never sees.
      {
        static const std::regex jump(R"((^|\s|\])(GOTO\s+)?(N\d+)$)");
        std::smatch jm;
        const bool is_goto = s.rfind("GOTO", 0) == 0;
        if ((s.rfind("IF ", 0) == 0 || is_goto) && std::regex_search(s, jm, jump)) {
          const auto it = labels.find(jm[3].str());
          if (it != labels.end() && it->second <= n)
            chk.problem(n, fmt::format("jump to {} back at line {}: a loop the verifier cannot bound", jm[3].str(),
                                       it->second));
          else if (it == labels.end() && is_goto)
            chk.problem(n, fmt::format("GOTO {}: no block {} in the program", jm[3].str(), jm[3].str()));
        } else if (is_goto) {
          chk.problem(n, "GOTO without a label N..");
        }
        static const std::regex call(R"((^|\s)(CALL|RTS|MODIN|M98)\b)");
        if (std::regex_search(s, jm, call))
          chk.problem(n, fmt::format("{}: a subprogram call the verifier cannot follow", jm[2].str()));
      }
      if (s.rfind("G31 ", 0) != 0) continue;
      ++probes;
      if (s.find(" F") == std::string::npos) chk.problem(n, "G31 without F on its block");
      std::vector<std::string> next;
      std::vector<int> next_line;
      size_t j = i;
      for (int c = 0; c < 13; ++c) {
        j = chk.nextCode(j);
        next.push_back(j < chk.lines.size() ? chk.code[j] : "");
        next_line.push_back(j < chk.lines.size() ? chk.lines[j].number : n);
      }
      bool ok = next[0] == "VC1=VSKPX" && next[1] == "VC2=VSKPY" && next[2] == "VC3=VSKPZ" &&
                next[3].rfind("VC4=VC1", 0) == 0 && next[4].rfind("VC5=VC2", 0) == 0 && next[5].rfind("VC6=VC3", 0) == 0 &&
                next[6].rfind("IF [VC4*VC4+VC5*VC5+VC6*VC6 GT ", 0) == 0 && next[7].rfind("PUT '", 0) == 0 &&
                next[8] == "WRITE C" && next[9] == "CLOSE C" && next[10].rfind("VUACM[1]=", 0) == 0 &&
                next[11].rfind("VDOUT[992]=", 0) == 0;
      if (ok) {
        const std::string label = ctl::trim(next[6].substr(next[6].find("] N") + 2));
        ok = next[12].rfind(label + " ", 0) == 0;
        // The jump past the alarm on the squared distance GT a positive tolerance: at or below
        // zero it is always taken, and the alarm can never be raised.
        const double tol = std::strtod(next[6].c_str() + next[6].find(" GT ") + 4, nullptr);
        if (ok && !(tol > 0.0))
          chk.problem(next_line[6],
                      "the no-trigger check must jump past its alarm on the squared distance GT a positive tolerance: "
                      "as written the alarm can never be raised");
      }
      if (!ok)
        chk.problem(n, "G31 is not followed by the no-trigger check (VSKPX-Z read, IF [distance GT ..] N.., "
                       "VUACM and VDOUT[992] alarm, then the label)");
    }
    if (open) chk.problem(chk.lastLine(), "FWRITC without CLOSE C");
    chk.probeCount(probes, shape.probes, "G31 moves");
    return chk.finish("M02", motion_text, inch, plan, kDialect);
  }
};

}  // namespace

const Dialect& okumaDialect() { return singleton<OkumaDialect>(); }

}  // namespace rotacal
