// Siemens Sinumerik 840D sl / ONE (../shared/reference/controllers.md Sec. 4): measuring moves
// `MEAS=1 G1 ...` (probe 1, the move's distance-to-go deleted at the trigger), `STOPRE` before
// reading the measured values `$AA_MW[X]` (work coordinates), a no-trigger check on both
// `$AC_MEA[1]` and the distance to the end point, storage in R parameters, output with
// `SPRINT` + `WRITE` (one line per call, LF appended by the control).
//
// Results, as the program's WRITE calls produce them:
//   ROTACAL-RESULTS DIALECT SIEMENS CYCLE TOUCH154 POINTS 154 UNIT MM
//   P17 X  123.4560 Y -200.0000 Z  173.0000
//   END
// or, when a point did not trigger, its last line is "NOT-TRIGGERED P17" (the program then stops
// with a message). No time: the clock variables $A_YEAR..$A_MSECOND / $AC_TIME are UNVERIFIED and
// the documented ones ($AC_OPERATING_TIME, ...) are run-time counters that need MD27860 and do
// not share an epoch between repeats; t_s = NaN (the analysis then uses the plan's times).
//
// UNVERIFIED, and the conservative choice made for each:
// - $AC_MEA[1] staying 0 without a trigger: the check also tests the distance of the measured
//   position to the end point (an untriggered move ends there exactly), like the Fanuc check.
// - Block length: lines kept within 80 characters (Autodesk's limit for its other posts).
// - R parameters retained and at least R90-R99 available (MD28050): only R90-R95 are used.
// - WRITE error codes: ERR <> 0 is treated as a failure that stops the program.
// - Number form of SPRINT "%10.4F" (inch: "%10.5F"): read as C's %10.4f; the parser accepts any
//   spacing and sign.
// - G93: only where the neutral program switches to inverse time (004), F on every block; probing and positioning run under G94.
#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <stdexcept>

#include "controllers/comp_table.hpp"
#include "controllers/end_point_check.hpp"
#include "controllers/offsets.hpp"
#include "controllers/program_checking.hpp"
#include "controllers/program_writing.hpp"
#include "controllers/siemens/toolcarrier.hpp"
#include "controllers/tagged_results.hpp"
#include "controllers/text.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"

namespace rotacal {
const Dialect& siemensDialect();

namespace ctl {
namespace {

constexpr int kSiemensMaxPoints = 10000;  // sanity bound only: MD38000 sets the real one

// The rotary compensation table in this control's form (controllers/comp_table.hpp).
CompTable compTable(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  const int n = compTableStepsPerTurn(step);
  if (n + 1 > kSiemensMaxPoints) throw std::invalid_argument(fmt::format("{} interpolation points are too many", n + 1));
  const CompTableGrid g = compTableGrid(E, r.controller_sign, 0.0, step, n + 1);
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  const std::string ax = std::string(1, r.errors.axis) + "1";  // machine axis name as in K3's example X1: UNVERIFIED
  std::string& s = t.text;
  s += "%_N_AX_EEC_INI\n";
  std::string comment;
  for (const auto& l : compTableProvenance(r, E, step)) comment += l + ". ";
  comment += fmt::format("Value = positioning error (actual - commanded, deg): a positive value moves the axis in the "
                         "negative direction. Load with MD32700 ENC_COMP_ENABLE = 0, MD38000 MM_ENC_COMP_MAX_POINTS >= {}, "
                         "then MD32700 = 1.",
                         n + 1);
  for (const auto& l : siemensDialect().commentLines(comment)) s += l + "\n";
  s += "CHANDATA(1)\n";
  for (int k = 0; k <= n; ++k) {
    const double v = k == n ? g.rows[0].error_deg : g.rows[k].error_deg;  // modulo: 360 = 0
    s += fmt::format("$AA_ENC_COMP[0,{},{}]={}\n", k, ax, fixed(v, 6));
  }
  s += fmt::format("$AA_ENC_COMP_STEP[0,{}]={}\n", ax, fixed(step, 4));
  s += fmt::format("$AA_ENC_COMP_MIN[0,{}]=0.0\n", ax);
  s += fmt::format("$AA_ENC_COMP_MAX[0,{}]=360.0\n", ax);
  s += fmt::format("$AA_ENC_COMP_IS_MODULO[0,{}]=1\n", ax);
  s += "M17\n";
  t.setup = {fmt::format("MD32700 $MA_ENC_COMP_ENABLE[0] = 0 for axis {0}, MD38000 $MA_MM_ENC_COMP_MAX_POINTS[0] >= {1} "
                         "(memory reorganised at the next start-up), load the file, MD32700 = 1, reference the axis",
                         ax, n + 1)};
  return t;
}

}  // namespace
}  // namespace ctl

namespace {

constexpr const char* kDialect = "siemens";
constexpr size_t kMaxLineChars = 80;  // UNVERIFIED for Sinumerik: conservative
constexpr int kDecimals = 4;          // SPRINT %10.4F and program coordinates

std::string unitName(bool inch) { return inch ? "INCH" : "MM"; }

/// Comment text for ';' comments: printable ASCII without '"', upper-cased (the control's
/// editor shows lower case, but some transfer tools do not keep it), at most the line length.
std::vector<std::string> comments(std::string_view text) {
  std::string s;
  for (char c : ctl::upper(ctl::printableLine(text))) {
    const char d = c == '"' ? ' ' : c;
    if (d == ' ' && (s.empty() || s.back() == ' ')) continue;
    s += d;
  }
  std::vector<std::string> out;
  for (const auto& piece : ctl::wrap(s, kMaxLineChars - 2)) out.push_back("; " + piece);
  if (out.empty()) out.push_back(";");
  return out;
}

/// Program / file name: A-Z 0-9 '_' only, starting with a letter (Sinumerik name rules are
/// UNVERIFIED: this is the common subset).
std::string safeName(std::string_view name) {
  std::string s;
  for (char c : ctl::upper(name)) s += ((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) ? c : '_';
  if (s.empty() || !(s[0] >= 'A' && s[0] <= 'Z')) s = "R_" + s;
  if (s.size() > 24) s.resize(24);
  return s;
}

DialectIdentity siemensIdentity() {
  DialectIdentity d;
  d.language = ProgramLanguage::Sinumerik;
  d.end_point_check = EndPointCheck{{"R93", "R94", "R95"}, {"R90", "R91", "R92"}};
  d.comp_table = ctl::compTable;
  return d;
}

class SiemensDialect final : public ctl::TaggedResultsDialect {
 public:
  // SPRINT's %10.4F (inch %10.5F): right-aligned in 10 characters.
  SiemensDialect() : TaggedResultsDialect({kDialect, ".mpf", "SIEMENS", safeName, 10, "\n", ""}, siemensIdentity()) {}
  std::vector<std::string> commentLines(std::string_view text) const override { return comments(text); }

  std::string writeProgram(const nc::Program& p) const override {
    const bool inch = p.unit == nc::Unit::Inch;
    const int probes = ctl::probeCount(p);
    const std::string prog = safeName(p.name.empty() ? "ROTACAL" : p.name);
    const std::string file = safeName(p.results_file.empty() ? "ROTACAL_RESULTS" : p.results_file);
    const std::string write = fmt::format("WRITE(ERR,\"{}\",TXT)", file);
    // An untriggered move ends at its end point: (10 um)^2 in mm, (0.001 in)^2 in inch.
    const std::string no_trigger_sq = inch ? "0.000001" : "0.0001";

    ctl::LineWriter w(comments, kMaxLineChars);
    auto writeText = [&](const std::string& text) {
      w.line(fmt::format("TXT=\"{}\"", text));
      w.line(write);
      w.line("IF ERR<>0 GOTOF WRFAIL");
    };
    w.line(fmt::format("; %_N_{}_MPF", prog));
    w.provenance(p, "siemens (Sinumerik 840D sl / ONE)");
    w.comment("machine coordinates: G54 as the work offset line above says, no TRAORI, no CYCLE800 plane, no "
              "toolcarrier active");
    w.comment(fmt::format("results: WRITE to file {} next to this program (one line per call); no time", file));
    w.comment("uses R90-R95; a point that does not trigger writes NOT-TRIGGERED and stops with a message");
    w.line("DEF INT ERR");
    w.line("DEF STRING[120] TXT");
    w.line(inch ? "G70" : "G71");
    w.line("G17 G40 G90 G94");
    w.line("G54");
    if (p.probe_tool > 0) {
      w.line(fmt::format("T{} M6", p.probe_tool));
      w.line("D1");
    }
    writeText(fmt::format("ROTACAL-RESULTS DIALECT SIEMENS CYCLE {} POINTS {} UNIT {}", safeName(p.cycle), probes,
                          unitName(inch)));
    std::vector<int> ids;
    ctl::writeOps(p, {kDialect, "G0", "G1", kDecimals, " "}, w, [&](const nc::Op& op) {
      const Eigen::Vector3d& x = op.xyz;
      switch (op.kind) {
        case nc::Op::Kind::Comment: w.comment(op.text); break;
        case nc::Op::Kind::Mode:
          // G93 inverse time (F = 1/min): the F-every-block rule is UNVERIFIED for Sinumerik;
          // F on every block is the safe form.
          w.line(fmt::format("{} {}", op.incremental ? "G91" : "G90", op.inverse_time ? "G1 G93" : "G94"));
          break;
        case nc::Op::Kind::Pause:
          if (op.dwell_s > 0) w.line(fmt::format("G4 F{}", ctl::trimmed(op.dwell_s, 3)));  // F: seconds, own block
          else w.line("M0");
          break;
        case nc::Op::Kind::Probe: {
          const int id = op.point_id;
          if (id <= 0) throw std::invalid_argument("probing move without a point id");
          ctl::requireSingleTouch(op, kDialect);
          if (!op.text.empty()) w.comment(op.text);
          w.line(ctl::linearBlock("MEAS=1 G1", op, kDecimals, inch));
          w.line("STOPRE");
          w.line("R90=$AA_MW[X]");
          w.line("R91=$AA_MW[Y]");
          w.line("R92=$AA_MW[Z]");
          for (int a = 0; a < 3; ++a)
            w.line(ctl::endPointCheckStatement(*endPointCheck(), a, x[a], kDecimals));
          w.line(fmt::format("IF ($AC_MEA[1]==0) OR (R93*R93+R94*R94+R95*R95<{}) GOTOF NOHIT{}", no_trigger_sq, id));
          w.line(fmt::format("TXT=SPRINT(\"P{0} X%10.{1}F Y%10.{1}F Z%10.{1}F\",R90,R91,R92)", id, resultDecimals(inch)));
          w.line(write);
          w.line("IF ERR<>0 GOTOF WRFAIL");
          ids.push_back(id);
          break;
        }
        default: break;  // written by ctl::writeOps
      }
    });
    writeText("END");
    w.line("GOTOF FINISH");
    for (int id : ids) {
      w.line(fmt::format("NOHIT{}:", id));
      w.line(fmt::format("TXT=\"NOT-TRIGGERED P{}\"", id));
      w.line(write);
      w.line(fmt::format("MSG(\"ROTACAL: POINT {} NOT TRIGGERED\")", id));
      w.line("M0");
      w.line("GOTOF FINISH");
    }
    w.line("WRFAIL:");
    w.line(fmt::format("MSG(\"ROTACAL: WRITE TO {} FAILED\")", file));
    w.line("M0");
    w.line("FINISH:");
    w.line("M30");
    return w.text;
  }

  std::string writeOffsets(const OffsetRequest& r) const override {
    const ctl::OffsetBasis b(r, kDialect);
    const auto& [plan, m, e, ac, inch, k, tilt] = b;
    const auto c = siemensToolcarrierChanges(e);
    ctl::LineWriter w(comments);
    w.line("; %_N_ROTACAL_TCARR_MPF");
    w.comment(fmt::format("rotacal toolcarrier correction, table {}/C, Sinumerik 840D sl / ONE. Provenance: {}, "
                          "cycle {}, machine {}.",
                          tilt, r.report_file.empty() ? "(no report)" : r.report_file, plan.cycle, m.name));
    w.identified(r, "identified location errors (papers' convention), value +- standard uncertainty (k = 1):");
    w.comment("what it changes: toolcarrier 1 (edit the index if yours differs): fine offsets of l2 "
              "($TC_CARR44-46, pivot of the tilting axis) and l3 ($TC_CARR55-57, second axis to first) are "
              "increased by the changes below; the axis vectors v1 ($TC_CARR7-9) and v2 ($TC_CARR10-12) "
              "are set to the identified directions; the angle offset of axis 1 ($TC_CARR24) is increased.");
    w.comment("old values: on the control (this program adds to them); new = old + change. Fine offsets need "
              "the fine correction enabled, and the mapping and the axis order are UNVERIFIED: check the "
              "toolcarrier data before and after, then activate with TCARR=1.");
    w.comment(fmt::format("units: {} and degrees", inch ? "inch" : "mm"));
    for (const auto& [name, v] : c.add_length)
      w.line(fmt::format("{0}[1]={0}[1]{1}{2}", name, v < 0 ? "-" : "+", ctl::fixed(std::abs(v * k), 4)));
    for (const auto& [name, v] : c.set_vector) w.line(fmt::format("{}[1]={}", name, ctl::fixed(v, 6)));
    w.line(fmt::format("$TC_CARR24[1]=$TC_CARR24[1]{}{}", c.add_angle_deg < 0 ? "-" : "+",
                       ctl::fixed(std::abs(c.add_angle_deg), 4)));
    w.line("M30");
    return w.text;
  }

  std::vector<std::string> check(const std::string& text, const ProbePlan& plan, const nc::Shape& shape) const override {
    ctl::TextCheck chk(text);
    // Code of each line without its ';' comment.
    for (size_t i = 0; i < chk.lines.size(); ++i) {
      const size_t sc = chk.lines[i].text.find(';');
      chk.code[i] = ctl::trim(sc == std::string::npos ? chk.lines[i].text : chk.lines[i].text.substr(0, sc));
    }
    std::map<std::string, int> labels;  // label -> its line
    for (size_t i = 0; i < chk.lines.size(); ++i)
      if (!chk.code[i].empty() && chk.code[i].back() == ':')
        labels.emplace(chk.code[i].substr(0, chk.code[i].size() - 1), chk.lines[i].number);
    static const std::regex motion(R"(^(MEAS=1 )?G[01]( [XYZABC]-?\d+(\.\d+)?)+( F\d+(\.\d+)?)?$)");
    static const std::regex axis_word(R"(\b([XYZABCF])(-?\d+(\.\d*)?)\b)");
    std::string motion_text;  // X/Y/Z/A/B/C motion lines for the stroke check, same line numbers
    bool statements = false, inch = false;
    int probes = 0;
    const std::string meas_check = "IF ($AC_MEA[1]==0) OR (R93*R93+R94*R94+R95*R95<";
    for (size_t i = 0; i < chk.lines.size(); ++i) {
      const std::string& s = chk.code[i];
      const int n = chk.lines[i].number;
      chk.lineLength(i, kMaxLineChars);
      int depth = 0;
      bool quote = false;
      for (char ch : s) {
        if (ch == '"') quote = !quote;
        if (quote) continue;
        if (ch == '(' || ch == '[') ++depth;
        if (ch == ')' || ch == ']') --depth;
      }
      if (depth != 0 || quote) chk.problem(n, "unbalanced ( ), [ ] or quotes");
      std::string m = s;
      if (s == "G71" || s == "G70") inch = s == "G70";
      if (s.rfind("DEF ", 0) == 0) {
        if (statements) chk.problem(n, "DEF after the first statement (definitions must come first)");
      } else if (!s.empty()) {
        statements = true;
      }
      static const std::regex g93(R"(\bG93\b)");
      if (!shape.inverse_time && std::regex_search(s, g93)) chk.problem(n, "G93 inverse time: rotacal probes and positions under G94 only");
      // GOTOF searches forward, GOTOB back, GOTO both: rotacal's programs jump forward only, past
      // an alarm; a jump back may never end.
      for (const std::string kw : {"GOTOF ", "GOTOB ", "GOTO "}) {
        const size_t g = s.find(kw);
        if (g == std::string::npos || (g > 0 && s[g - 1] != ' ')) continue;
        const std::string label = ctl::trim(s.substr(g + kw.size()));
        const auto it = labels.find(label);
        if (it == labels.end() || (kw == "GOTOF " && it->second <= n))
          chk.problem(n, fmt::format("jump to the undefined label '{}'", label));
        else if (it->second <= n)
          chk.problem(n, fmt::format("{}{} jumps back to line {}: a loop the verifier cannot bound", kw, label,
                                     it->second));
      }
      {
        static const std::regex loop(R"(^(WHILE|ENDWHILE|LOOP|ENDLOOP|FOR|ENDFOR|REPEAT|UNTIL)\b)");
        static const std::regex call(R"(^(CALL|PCALL|MCALL|EXTCALL|L\d+|M98|M17|RET)\b)");
        std::smatch km;
        if (std::regex_search(s, km, loop))
          chk.problem(n, fmt::format("{}: a loop the verifier cannot bound", km[1].str()));
        if (std::regex_search(s, km, call))
          chk.problem(n, fmt::format("{}: a subprogram call the verifier cannot follow", km[1].str()));
      }
      const bool is_motion = s.rfind("G0 ", 0) == 0 || s.rfind("G1 ", 0) == 0 || s.rfind("MEAS=", 0) == 0;
      if (is_motion) {
        if (!std::regex_match(s, motion)) chk.problem(n, fmt::format("motion block '{}' is not of the generated form", s));
        for (auto it = std::sregex_iterator(s.begin(), s.end(), axis_word); it != std::sregex_iterator(); ++it)
          if ((*it)[2].str().find('.') == std::string::npos)
            chk.problem(n, fmt::format("{}{} has no decimal point", (*it)[1].str(), (*it)[2].str()));
        m = s.rfind("MEAS=1 ", 0) == 0 ? s.substr(7) : s;
        motion_text += m;
      }
      motion_text += '\n';
      if (s.rfind("MEAS=", 0) != 0) continue;
      ++probes;
      if (s.rfind("MEAS=1 G1 ", 0) != 0) chk.problem(n, "measuring move must be 'MEAS=1 G1 ...'");
      if (s.find(" F") == std::string::npos) chk.problem(n, "measuring move without F on its block");
      // Then: STOPRE, the three $AA_MW reads, the distances, the IF ... GOTOF NOHIT<id>, whose
      // label section writes NOT-TRIGGERED and stops with M0.
      std::vector<std::string> next;
      int check_line = n;  // the line of the IF
      size_t j = i;
      for (int c = 0; c < 8; ++c) {
        j = chk.nextCode(j);
        next.push_back(j < chk.lines.size() ? chk.code[j] : "");
        if (j < chk.lines.size()) check_line = chk.lines[j].number;
      }
      const bool ok = next[0] == "STOPRE" && next[1] == "R90=$AA_MW[X]" && next[2] == "R91=$AA_MW[Y]" &&
                      next[3] == "R92=$AA_MW[Z]" && next[4].rfind("R93=R90", 0) == 0 && next[5].rfind("R94=R91", 0) == 0 &&
                      next[6].rfind("R95=R92", 0) == 0 && next[7].rfind(meas_check, 0) == 0;
      bool stops = false;
      if (ok) {
        // The alarm on the squared distance below a positive tolerance: at or below zero that half
        // is never true, and the alarm rests on $AC_MEA alone.
        const double tol = std::strtod(next[7].c_str() + meas_check.size(), nullptr);
        if (!(tol > 0.0))
          chk.problem(check_line, "the no-trigger check must alarm on the squared distance below a positive "
                                  "tolerance: as written that half of it is never true");
        const size_t g = next[7].find("GOTOF ");
        const std::string label = g == std::string::npos ? "" : ctl::trim(next[7].substr(g + 6));
        for (size_t q = 0; q < chk.lines.size(); ++q) {
          if (chk.code[q] != label + ":") continue;
          // As the control runs the section: a jump or an end before its M0 never stops.
          for (size_t r = chk.nextCode(q); r < chk.lines.size() && chk.code[r].back() != ':'; r = chk.nextCode(r)) {
            const std::string& t = chk.code[r];
            if (t == "M0") {
              stops = true;
              break;
            }
            if (t.find("GOTO") != std::string::npos || t == "M30" || t == "M2" || t == "M17" || t == "RET") break;
          }
        }
      }
      if (!ok || !stops)
        chk.problem(n, "MEAS=1 is not followed by STOPRE, the $AA_MW reads and the no-trigger check "
                       "(IF ($AC_MEA[1]==0) OR (distance) GOTOF label, label: ... M0)");
    }
    chk.probeCount(probes, shape.probes, "MEAS=1 moves");
    return chk.finish("M30", motion_text, inch, plan, kDialect);
  }
};

}  // namespace

SiemensToolcarrierChanges siemensToolcarrierChanges(const LocationErrors& e) {
  SiemensToolcarrierChanges c;
  if (e.kinematics == Kinematics::TableAC) {
    c.add_length = {{"$TC_CARR44", e.get("dx_AY")}, {"$TC_CARR45", e.get("dy_AY")}, {"$TC_CARR46", e.get("dz_AY")},
                    {"$TC_CARR55", 0.0},            {"$TC_CARR56", e.get("dy_CA")}, {"$TC_CARR57", 0.0}};
    // A axis nominally +X, turned by b_AY about Y and c_AY about Z; C axis nominally +Z turned by
    // b_CA about Y (small angles, then normalized).
    const Eigen::Vector3d v1 = Eigen::Vector3d(1.0, e.get("c_AY"), -e.get("b_AY")).normalized();
    const Eigen::Vector3d v2 = Eigen::Vector3d(e.get("b_CA"), 0.0, 1.0).normalized();
    c.set_vector = {{"$TC_CARR7", v1.x()},  {"$TC_CARR8", v1.y()},  {"$TC_CARR9", v1.z()},
                    {"$TC_CARR10", v2.x()}, {"$TC_CARR11", v2.y()}, {"$TC_CARR12", v2.z()}};
    c.add_angle_deg = radToDeg(e.get("a_AY"));
  } else {
    c.add_length = {{"$TC_CARR44", e.get("dx_BY")}, {"$TC_CARR45", e.get("dy_CB")}, {"$TC_CARR46", e.get("dz_BY")},
                    {"$TC_CARR55", e.get("dx_CB")}, {"$TC_CARR56", 0.0},            {"$TC_CARR57", 0.0}};
    // B axis nominally +Y, turned by a_BY about X and c_BY about Z; C axis +Z turned by a_CB about X.
    const Eigen::Vector3d v1 = Eigen::Vector3d(-e.get("c_BY"), 1.0, e.get("a_BY")).normalized();
    const Eigen::Vector3d v2 = Eigen::Vector3d(0.0, -e.get("a_CB"), 1.0).normalized();
    c.set_vector = {{"$TC_CARR7", v1.x()},  {"$TC_CARR8", v1.y()},  {"$TC_CARR9", v1.z()},
                    {"$TC_CARR10", v2.x()}, {"$TC_CARR11", v2.y()}, {"$TC_CARR12", v2.z()}};
    c.add_angle_deg = radToDeg(e.get("b_BY"));
  }
  return c;
}

const Dialect& siemensDialect() { return singleton<SiemensDialect>(); }

}  // namespace rotacal
