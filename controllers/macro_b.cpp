// The Custom Macro B program, results and checker shared by fanuc and haas (see macro_b.hpp).
#include "controllers/macro_b.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <stdexcept>

#include "controllers/clock.hpp"
#include "controllers/end_point_check.hpp"
#include "controllers/program_checking.hpp"
#include "controllers/program_writing.hpp"
#include "controllers/result_checks.hpp"
#include "controllers/results_lines.hpp"
#include "controllers/tagged_results.hpp"
#include "controllers/text.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

constexpr size_t kMaxLineChars = 80;  // conservative: Autodesk's Fanuc and Haas posts keep to 80; limit UNVERIFIED
constexpr int kLabelBase = 1000;       // N<1000 + id>: the no-trigger check jumps there
constexpr int kMaxLabel = 99999;
// DPRNT fields of the trigger X Y Z: [44] in mm, [35] in inch. With [44] an inch result is rounded
// by up to 1.27 um per coordinate, which moves the identified errors by up to 3.1 um
// (docs/dialects.md, digits bound); the fifth inch decimal brings that to 0.31 um (a control that
// holds #5061 only to 0.0001 in prints a trailing 0). a + b = 8 suits older Haas controls.
// DPRNT #v[ab] with a + b <= 8: "older controls: w + f must be 1-8" (controllers.md Sec. 3.4,
// Haas 96-8000); Fanuc shares the format and no source gives it more, so both keep to 8 - the
// checker flags a wider field and the parser a wider value. T (#3001 in ms) is [80]: 27.7 h.
constexpr int kMaxDprntDigits = 8;
constexpr int kTimeDigits = 8;
constexpr double kMaxTimerMs = 99999999.0;  // kTimeDigits nines
constexpr int kIntDigits = 4, kDecimals = 4;
constexpr int kIntDigitsInch = 3, kDecimalsInch = 5;
int xyzIntDigits(bool inch) { return inch ? kIntDigitsInch : kIntDigits; }
int xyzDecimals(bool inch) { return inch ? kDecimalsInch : kDecimals; }

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

std::string unitName(bool inch) { return inch ? "INCH" : "MM"; }

}  // namespace

namespace macro_b {

std::vector<std::string> comments(std::string_view text) {
  std::vector<std::string> out;
  for (const auto& piece : ctl::wrap(safeText(text), kMaxLineChars - 2)) out.push_back("(" + piece + ")");
  if (out.empty()) out.push_back("()");
  return out;
}

std::string dprntText(std::string_view text) {
  std::string s;
  for (char c : ctl::upper(text)) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '.' || c == '/';
    s += ok ? c : '-';
  }
  return s;
}

std::string dprntNumber(double value, int integer_digits, int decimals) {
  const std::string s = ctl::fixed(value, decimals);
  const int width = integer_digits + (decimals > 0 ? decimals + 1 : 0);
  return fmt::format("{:>{}}", s, width);
}

}  // namespace macro_b

using macro_b::comments;
using macro_b::dprntText;

std::vector<std::string> MacroBDialect::commentLines(std::string_view text) const { return comments(text); }

std::string MacroBDialect::writeProgram(const nc::Program& p) const {
  const bool inch = p.unit == nc::Unit::Inch;
  const int number = ctl::programNumber(p);
  const int max_number = f_.program_digits == 5 ? 99999 : 9999;
  if (number < 1 || number > max_number)
    throw std::invalid_argument(fmt::format("{} program number O{} must be 1..{}", f_.tag, number, max_number));
  const int probes = ctl::probeCount(p);
  const int store_top = f_.store_base + 4 * f_.max_points_per_pose - 1;

  ctl::LineWriter w(comments, kMaxLineChars);
  // Squared distance (program units^2) below which the skip position counts as "at the end
  // point", i.e. no trigger: (10 um)^2 in mm, (0.001 in)^2 in inch. A triggered move stops
  // the overtravel (mm, not um) before its end; an untriggered one stops at the end exactly.
  const std::string no_trigger_sq = inch ? "0.000001" : "0.0001";
  const auto end_check = endPointCheck();
  if (!end_check) throw std::invalid_argument(fmt::format("{}: no no-trigger check form", f_.name));

  w.line("%");
  w.line(fmt::format("O{:0{}}({})", number, f_.program_digits, safeText("ROTACAL " + p.cycle)));
  w.provenance(p, f_.title);  // upper case, as every Macro B comment
  w.comment("MACHINE COORDINATES: G54 AS THE WORK OFFSET LINE ABOVE SAYS, ROTARY OFFSETS 0, NO TCP OR TILTED PLANE "
            "ACTIVE");
  for (const auto& n : f_.notes) w.comment(n);
  w.comment(fmt::format("USES LOCAL VARIABLES 1 TO 3 AND RETAINED VARIABLES {} TO {}: THEY MUST BE FREE",
                        f_.store_base, store_top));
  w.comment("TIME: DATE 3011 AND TIME 3012 AT THE START, MS TIMER 3001 ZEROED THERE AND READ AT EACH POINT");
  w.comment("A POINT THAT DOES NOT TRIGGER RAISES ALARM 3000");
  w.line(inch ? "G20" : "G21");
  w.line("G17 G40 G49 G80 G90 G94");
  w.line("G54");
  if (f_.lookahead_g103) w.line("G103 P1");
  if (p.probe_tool > 0) {
    w.comment("PROBE LENGTH COMPENSATION: CHECK WHETHER 5063 INCLUDES IT ON THIS CONTROL");
    w.line(fmt::format("T{} M06", p.probe_tool));
    w.line(fmt::format("G43 H{}", p.probe_tool));
  }
  w.line("POPEN");
  // Date and time first, then zero the timer in the next block: T counts from that second.
  w.line("#1=#3011");
  w.line("#2=#3012");
  w.line("#3001=0");
  w.line(fmt::format("DPRNT[ROTACAL-RESULTS*DIALECT*{}*CYCLE*{}*POINTS*{}*UNIT*{}]", f_.tag, dprntText(p.cycle),
                     probes, unitName(inch)));
  w.line("DPRNT[DATE*#1[80]*TIME*#2[60]]");

  std::vector<int> pose_points;  // ids probed at the current pose, in order
  auto flush = [&]() {
    for (size_t j = 0; j < pose_points.size(); ++j) {
      const int b = f_.store_base + 4 * static_cast<int>(j);
      const int a = xyzIntDigits(inch), d = xyzDecimals(inch);
      w.line(fmt::format("DPRNT[P{}*X#{}[{}{}]*Y#{}[{}{}]*Z#{}[{}{}]*T#{}[{}0]]", pose_points[j], b, a, d, b + 1, a, d,
                         b + 2, a, d, b + 3, kTimeDigits));
    }
    pose_points.clear();
  };
  auto own = [&](const nc::Op& op) {
    const Eigen::Vector3d& x = op.xyz;
    switch (op.kind) {
      case nc::Op::Kind::Comment: w.comment(op.text); break;
      case nc::Op::Kind::Mode:
        // G93 with F on every block (Haas: [HaasMan]; Fanuc: UNVERIFIED in controllers.md, F on
        // every block is the safe form).
        w.line(ctl::isoModeBlock(op));
        break;
      case nc::Op::Kind::Pause:
        // Seconds with a decimal point: Fanuc X2. (P would be integer ms), Haas P2. [HaasMan].
        if (op.dwell_s > 0) w.line(fmt::format("G04 {}{}", f_.dwell_word, ctl::trimmed(op.dwell_s, 3)));
        else w.line("M00");
        break;
      case nc::Op::Kind::Probe: {
        const int id = op.point_id;
        if (id <= 0 || kLabelBase + id > kMaxLabel)
          throw std::invalid_argument(fmt::format("point id {} cannot be a {} label (1..{})", id, f_.tag, kMaxLabel - kLabelBase));
        ctl::requireSingleTouch(op, f_.name);
        if (pose_points.size() >= static_cast<size_t>(f_.max_points_per_pose))
          throw std::invalid_argument(fmt::format("pose {} has more than {} points: the {} program stores them in #{}-#{}",
                                                  op.pose_name, f_.max_points_per_pose, f_.name, f_.store_base, store_top));
        const int b = f_.store_base + 4 * static_cast<int>(pose_points.size());
        const int label = kLabelBase + id;
        if (!op.text.empty()) w.comment(op.text);
        w.line(ctl::linearBlock("G31", op, 4, inch));  // mm and inch: 4 decimals, always a point
        for (int a = 0; a < 3; ++a) w.line(ctl::endPointCheckStatement(*end_check, a, x[a], 4));
        w.line(fmt::format("IF[[#1*#1+#2*#2+#3*#3]GT{}]GOTO{}", no_trigger_sq, label));
        w.line(fmt::format("#3000=1(POINT {} NOT TRIGGERED)", id));
        w.line(fmt::format("N{}", label));
        w.line(fmt::format("#{}=#5061", b));
        w.line(fmt::format("#{}=#5062", b + 1));
        w.line(fmt::format("#{}=#5063", b + 2));
        w.line(fmt::format("#{}=#3001", b + 3));
        pose_points.push_back(id);
        break;
      }
      default: break;  // written by ctl::writeOps
    }
  };
  // The pose's stored points are printed before the table turns to the next pose.
  ctl::writeOps(p, {f_.name, "G00", "G01", 4, ""}, w, own, flush);
  flush();
  w.line("DPRNT[END]");
  w.line("PCLOS");
  if (f_.lookahead_g103) w.line("G103");
  w.line("M30");
  w.line("%");
  return w.text;
}

std::string MacroBDialect::writeResults(const ProbePlan& plan, const MeasurementRun& run) const {
  const bool inch = plan.machine.units == LengthUnit::Inch;
  const double k = inch ? 1.0 / kMmPerInch : 1.0;
  // The header's second: the earliest trigger time rounded down; T = ms since then. The parser
  // then returns every t_s within 0.5 ms (the printed ms).
  double t0 = std::numeric_limits<double>::infinity();
  for (const auto& t : run.points) {
    if (std::isnan(t.t_s))
      throw std::invalid_argument(
          fmt::format("point {} has no time: the {} program always prints the clock", t.point_id, f_.name));
    t0 = std::min(t0, std::floor(t.t_s));
  }
  if (run.points.empty()) t0 = 0.0;
  const ctl::ClockStamp stamp = ctl::clockStamp(t0);
  std::string out = fmt::format("ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT {}\r\nDATE {} TIME {}\r\n", f_.tag,
                                dprntText(plan.cycle), plan.points.size(), unitName(inch),
                                macro_b::dprntNumber(static_cast<double>(stamp.yyyymmdd), 8, 0),
                                macro_b::dprntNumber(static_cast<double>(stamp.hhmmss), 6, 0));
  for (const auto& t : run.points) {
    if (!plan.findPoint(t.point_id)) throw std::invalid_argument(fmt::format("run point {} is not in the plan", t.point_id));
    const Eigen::Vector3d x = t.position_m_mm * k;
    const int a = xyzIntDigits(inch), d = xyzDecimals(inch);
    const double ms = std::round((t.t_s - t0) * 1000.0);
    if (ms > kMaxTimerMs)
      throw std::invalid_argument(fmt::format("point {} is {:.0f} ms after the first: the {} program prints #3001 as "
                                              "[{}0], at most {:.0f} ms",
                                              t.point_id, ms, f_.name, kTimeDigits, kMaxTimerMs));
    out += fmt::format("P{} X{} Y{} Z{} T{}\r\n", t.point_id, macro_b::dprntNumber(x.x(), a, d),
                       macro_b::dprntNumber(x.y(), a, d), macro_b::dprntNumber(x.z(), a, d),
                       macro_b::dprntNumber(ms, kTimeDigits, 0));
  }
  out += "END\r\n";
  return out;
}

MeasurementRun MacroBDialect::parseResults(const std::string& raw, const std::string& file, const ProbePlan& plan) const {
  // Punch control codes are dropped (NUL feed, DC1-DC4 from POPEN/PCLOS, DEL tape feed); any
  // other byte outside printable ASCII is a damaged file. '%' lines are skipped.
  std::string text;
  for (char c : raw)
    if (c != 0x00 && c != 0x7f && (c < 0x11 || c > 0x14)) text += c;
  ctl::requireText(text, file);
  const std::string expected_header =
      fmt::format("ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT MM|INCH", f_.tag, dprntText(plan.cycle),
                  plan.points.size());
  const std::string expected_clock = "DATE YYYYMMDD TIME HHMMSS";
  ctl::PointCollector points(plan, file);
  ctl::ResultLines in(text, file, "ROTACAL-RESULTS", expected_header, "", "%");
  double k = 1.0;
  double clock0 = 0.0;
  bool clock = false;
  while (in.next()) {
    const std::string& s = in.s;
    const auto& t = in.t;
    const int line = in.number;
    if (in.isHeader()) {
      k = ctl::taggedHeaderMmPerUnit(s, file, line, plan, f_.tag, dprntText(plan.cycle));
      continue;
    }
    if (t[0] == "DATE") {
      if (clock) ctl::fail(file, line, "a second DATE line: one run per results file");
      clock = true;
      if (t.size() != 4 || t[2] != "TIME")
        ctl::fail(file, line, fmt::format("expected '{}', got '{}'", expected_clock, s));
      // DPRNT may print a trailing point after an integer field ([80] prints none; tolerate it).
      auto digits = [](std::string v) {
        if (!v.empty() && v.back() == '.') v.pop_back();
        return ctl::parseDigits(v);
      };
      const auto date = digits(t[1]);
      const auto time = digits(t[3]);
      const auto secs = date && time ? ctl::clockSeconds(*date, *time) : std::nullopt;
      if (!secs)
        ctl::fail(file, line,
                  fmt::format("DATE {} TIME {} is not a date YYYYMMDD and a time HHMMSS (#3011, #3012)", t[1], t[3]));
      clock0 = *secs;
      continue;
    }
    if (!clock) ctl::fail(file, line, fmt::format("expected '{}' after the header, got '{}'", expected_clock, s));
    if (in.isEnd()) continue;
    const auto f = ctl::letteredFields(s, "XYZT", file, line);
    const char letters[] = {'X', 'Y', 'Z', 'T'};
    double v[4] = {0, 0, 0, 0};
    for (int i = 0; i < 4; ++i) {
      const auto value = ctl::parseNumber(f.fields[static_cast<size_t>(i)]);
      if (!value)
        ctl::fail(file, line,
                  fmt::format("{} '{}' of point {} is not a number", letters[i], f.fields[static_cast<size_t>(i)], f.id));
      v[i] = *value;
    }
    if (v[3] < 0) ctl::fail(file, line, fmt::format("T {} of point {} is negative: #3001 counts up from 0", v[3], f.id));
    {
      const std::string& t_text = f.fields[3];
      const auto digits = std::count_if(t_text.begin(), t_text.end(), [](char c) { return c >= '0' && c <= '9'; });
      if (digits > kTimeDigits)
        ctl::fail(file, line,
                  fmt::format("T '{}' of point {} has {} digits: the program prints #3001 as [{}0], at most {}", t_text,
                              f.id, digits, kTimeDigits, kTimeDigits));
    }
    points.add(line, static_cast<int>(f.id), Eigen::Vector3d(v[0], v[1], v[2]) * k, clock0 + v[3] / 1000.0);
  }
  in.finish(points, " (a point that does not trigger raises alarm 3000)");
  return points.finish(in.last());
}

std::vector<std::string> MacroBDialect::check(const std::string& text, const ProbePlan& plan, const nc::Shape& shape) const {
  const auto blocks = nc::readProgram(text);
  std::vector<std::string> out = ctl::readerIssues(blocks);
  auto problem = [&](int line, const std::string& what) { out.push_back(fmt::format("{}: {}", line, what)); };
  int probes = 0;
  // The program number O.... may only be the first block (after the opening '%').
  const size_t first = ctl::nextNonBlank(blocks, static_cast<size_t>(-1));
  const size_t o_block = first < blocks.size() && blocks[first].percent ? ctl::nextNonBlank(blocks, first) : first;
  if (o_block < blocks.size() && f_.program_digits == 5) {
    const nc::Word* o = blocks[o_block].find('O');
    if (!o || o->text.size() != 5 || o->has_decimal_point)
      problem(blocks[o_block].line, fmt::format("the program must start with O and 5 digits ({})", f_.tag));
  }
  bool g103 = false;
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
        problem(b.line, fmt::format("lower-case letters in a comment (not accepted by every {})", f_.tag));
        break;
      }
    if (b.control) {
      if (!b.oword.empty()) problem(b.line, "o-word control ('o.. if') is LinuxCNC, not Macro B");
      // rotacal's programs never loop: a WHILE may never end, and its body runs an unknown
      // number of times.
      if (b.keyword == "WHILE" || b.keyword == "DO" || b.keyword == "END")
        problem(b.line, fmt::format("{}: a WHILE loop the verifier cannot bound", ctl::trim(b.code)));
      if (b.code.find("#<") != std::string::npos) problem(b.line, "named parameters #<..> are not Macro B");
      if (b.keyword == "DPRNT") {
        if (f_.lookahead_g103 && !g103)
          problem(b.line, "DPRNT before G103 P1: it would print at look-ahead time, before the values exist");
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
                else if ((body[k + 1] - '0') + (body[k + 2] - '0') > kMaxDprntDigits)
                  problem(b.line, fmt::format("DPRNT format [ab] with a + b > {} (older {} controls refuse it)",
                                              kMaxDprntDigits, f_.tag));
                k = e == std::string::npos ? body.size() : e;
              } else {
                --k;
              }
              continue;
            }
            const bool ok =
                (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '*' || c == '-' || c == '.' || c == '/';
            if (!ok) {
              problem(b.line, fmt::format("DPRNT text has '{}' (only A-Z 0-9 * - . /)", c));
              break;
            }
          }
        }
      }
      continue;
    }
    if (b.hasWord('G', 103)) g103 = b.hasWord('P', 1);
    // What the verifier cannot follow is not passed (docs/safety.md): a subprogram or macro call
    // runs moves it never sees.
    // M97 is Haas' call of a block of the same program.
    for (const auto& [letter, code] : {std::pair{'M', 98}, {'M', 97}, {'M', 198}, {'G', 65}, {'G', 66}, {'M', 99}})
      if (b.hasWord(letter, code))
        problem(b.line, fmt::format("{}{}: a subprogram or macro call the verifier cannot follow", letter, code));
    for (const auto& w : b.words) {
      if (w.letter == 'O' && i != o_block) problem(b.line, "O word (program number) after the start of the program");
      const bool needs_point = w.letter == 'X' || w.letter == 'Y' || w.letter == 'Z' || w.letter == 'A' ||
                               w.letter == 'B' || w.letter == 'C' || w.letter == 'F';
      if (needs_point && w.value && !w.has_decimal_point)
        problem(b.line, fmt::format("{}{} has no decimal point (read in least input increments)", w.letter, w.text));
    }
    if (b.hasWord('G', 93) && !shape.inverse_time) problem(b.line, "G93 inverse time: rotacal probes and positions under G94 only");
    if (!b.hasWord('G', 31)) continue;
    ++probes;
    if (!b.find('X') && !b.find('Y') && !b.find('Z')) problem(b.line, "G31 without an axis word");
    if (!b.find('F')) problem(b.line, "G31 without F on its block");
    // Within the next 8 blocks: #5061-#5063 read, IF[...]GOTO n, then #3000 alarm, then N n.
    bool reads[3] = {false, false, false};
    bool ok = false;
    for (const size_t j : ctl::nextBlocks(blocks, i, 8)) {
      const nc::Block& c = blocks[j];
      // Only the end-point assignments come between the move and its test: a GOTO there (even
      // one the block-delete switch may skip) jumps past the alarm as the control runs it.
      if (!c.control || (c.keyword != "#" && c.keyword != "IF") || c.block_delete) break;
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
      // The jump past the alarm is taken when the probe stopped short of the end point (the squared
      // distance GT a positive tolerance). Any other comparison, or a tolerance at or below zero
      // (a squared distance is never negative), jumps always or never by the values alone: the
      // alarm either cannot be raised or the check is not the one rotacal writes.
      if (ok) {
        const size_t gt = g == std::string::npos ? std::string::npos : c.code.rfind("]GT", g);
        const double tol = gt == std::string::npos ? 0.0 : std::strtod(c.code.c_str() + gt + 3, nullptr);
        if (gt == std::string::npos || !(tol > 0.0)) {
          problem(c.line, "the no-trigger check must jump past its alarm on [squared distance]GT a positive tolerance: "
                          "as written the alarm can never be raised, or the test is not rotacal's");
        }
      }
      break;
    }
    if (!ok)
      problem(b.line, "G31 is not followed by the no-trigger check (#5061-#5063 vs the end point, IF[..]GOTO n, "
                      "#3000 alarm, N n)");
  }
  // A jump back to a label at or before it is a loop the verifier cannot bound (it may never end);
  // rotacal's programs jump forward only, past an alarm. A jump to a label that is not there stops
  // the control.
  {
    std::map<long, int> label_line;
    for (const auto& b : blocks)
      if (!b.control)
        if (const nc::Word* n = b.find('N'); n && n->value) label_line.emplace(static_cast<long>(*n->value), b.line);
    for (const auto& b : blocks) {
      if (!b.control) continue;
      const size_t g = b.code.find("GOTO");
      if (g == std::string::npos) continue;
      const auto label = ctl::parseDigits(ctl::trim(b.code.substr(g + 4)));
      if (!label) {
        problem(b.line, "GOTO without a label number");
        continue;
      }
      const auto it = label_line.find(*label);
      if (it == label_line.end()) problem(b.line, fmt::format("GOTO{}: no block N{} in the program", *label, *label));
      else if (it->second <= b.line)
        problem(b.line, fmt::format("GOTO{} jumps back to line {}: a loop the verifier cannot bound", *label, it->second));
    }
  }
  const int last_line = blocks.empty() ? 1 : blocks.back().line;
  if (static_cast<size_t>(probes) != shape.probes)
    problem(last_line, fmt::format("{} G31 moves, the plan has {} points", probes, shape.probes));
  for (auto& s : ctl::blockProblems(blocks, plan, f_.name)) out.push_back(std::move(s));
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

}  // namespace rotacal
