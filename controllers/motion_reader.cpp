#include "controllers/motion_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <regex>
#include <stdexcept>

#include <fmt/format.h>

#include "controllers/dialect.hpp"
#include "controllers/end_point_check.hpp"
#include "controllers/sinumerik_names.hpp"
#include "controllers/text.hpp"
#include "gcode/reader.hpp"

namespace rotacal::ctl {
namespace {

/// M2 or M30: the program ends with this block.
bool endsProgram(const nc::Word& w) {
  return w.letter == 'M' && w.value && (std::abs(*w.value - 2) < 1e-9 || std::abs(*w.value - 30) < 1e-9);
}

// Heidenhain's no-trigger test compares cycle 0's result with the end point moved this far
// back toward the start (controllers/heidenhain/dialect.cpp writes it so): the end point it guards is
// the literal moved forward again by the same amount.
constexpr double kHeidenhainNoTriggerMm = 0.01;

bool isAxisLetter(char c) { return std::string_view("XYZABC").find(c) != std::string_view::npos; }

nc::Motion motionAt(nc::Motion::Kind kind, int line, std::string why = "") {
  nc::Motion m;
  m.kind = kind;
  m.line = line;
  m.problem = std::move(why);
  return m;
}

nc::Motion unreadable(int line, std::string why) { return motionAt(nc::Motion::Kind::Unreadable, line, std::move(why)); }

/// Where G28 / G30 (through the current position: incremental zero) or G53 of `b` takes Z, from
/// its reference (program units, <= 0); nullopt when the block is anything else, or the
/// dialect's reference is not the top of the Z stroke.
std::optional<double> zFromReference(const Dialect& dialect, double g, bool incremental, const nc::Block& b) {
  if (!dialect.identity().z_reference_at_stroke_top) return std::nullopt;
  std::optional<double> z;
  for (const auto& w : b.words) {
    if (w.letter == 'Z' && w.value && !z) z = *w.value;
    else if (isAxisLetter(w.letter) || w.letter == 'Z') return std::nullopt;
  }
  if (!z) return std::nullopt;
  if (std::abs(g - 53) < 1e-9) return *z <= 0 ? z : std::nullopt;
  return incremental && *z == 0 ? std::optional<double>(0.0) : std::nullopt;
}

std::vector<nc::Motion> readWordAddress(const Dialect& dialect, const std::string& text) {
  const bool siemens = dialect.language() == ProgramLanguage::Sinumerik;
  const bool numbered = dialect.numbersPrograms();
  const std::optional<EndPointCheck>& form = dialect.endPointCheck();
  std::vector<nc::Motion> out;
  bool inch = false, incremental = false, inverse_time = false;
  std::optional<nc::Motion::Kind> modal;  // G0 / G1 in force
  std::array<std::optional<double>, 3> check_end;
  int check_line = 0;
  static const std::regex measuring(R"(^\s*(N\d+\s+)?(MEAS|MEAW)\s*=\s*-?\d+\s+)", std::regex::icase);

  for (const nc::Block& whole : nc::readProgram(text)) {
    if (whole.percent || whole.code.empty()) continue;
    const std::string code_upper = upper(whole.code);
    // The no-trigger check: its end-point statements, then the test.
    if (form) {
      if (const auto st = parseEndPointCheckStatement(*form, whole.code)) {
        if (!check_line) check_line = whole.line;
        check_end[static_cast<size_t>(st->axis)] = st->end;
        continue;
      }
    }
    const bool is_if = code_upper.rfind("IF", 0) == 0 || (whole.control && (whole.keyword == "IF"));
    if (is_if) {
      const bool flag = code_upper.find("#5070") != std::string::npos || code_upper.find("$AC_MEA") != std::string::npos;
      if (check_line || flag) {
        nc::Motion m;
        m.kind = nc::Motion::Kind::Check;
        m.line = check_line ? check_line : whole.line;
        m.check_end = check_end;
        out.push_back(m);
      }
      check_end = {};
      check_line = 0;
      continue;
    }
    if (whole.control) continue;  // macro statements, o-words, #assignments, DPRNT
    if (siemens) {
      if (const auto frame = sinumerikFrameChange(whole.code)) {
        out.push_back(unreadable(whole.line, *frame + " is not followed by the verifier"));
        continue;
      }
    }
    nc::Block b = whole;
    bool probe_prefix = false;
    std::smatch mm;
    if (siemens && std::regex_search(whole.code, mm, measuring)) {
      const std::vector<nc::Block> rest = nc::readProgram(whole.code.substr(mm.str(0).size()));
      if (rest.empty() || rest.front().words.empty()) {
        out.push_back(unreadable(whole.line, "a measuring prefix without a move after it"));
        continue;
      }
      b = rest.front();
      b.line = whole.line;
      probe_prefix = true;
    } else if (isStatement(whole.code, false)) {
      continue;
    }
    if (siemens) {
      // The language's own names (SOFT, X=-10, a subprogram's name) before the words.
      const SinumerikBlock sb = readSinumerikBlock(b.code);
      if (!sb.problem.empty()) {
        out.push_back(unreadable(whole.line, sb.problem));
        continue;
      }
      if (sb.code != upper(b.code)) {
        const std::vector<nc::Block> rest = nc::readProgram(sb.code);
        if (rest.empty()) continue;
        b = rest.front();
        b.line = whole.line;
      }
    }
    if (!b.issues.empty()) {
      out.push_back(unreadable(b.line, b.issues.front()));
      continue;
    }
    std::optional<nc::Motion::Kind> motion;
    bool probe = probe_prefix, alarms = false, dwell = false, end = false, modes = false;
    std::optional<double> reference_g;  // G28, G30 or G53 on this block
    std::string trouble;
    for (const auto& w : b.words) {
      if (w.letter != 'G') continue;
      if (!w.value) {
        trouble = "a G word that is an expression cannot be followed";
        break;
      }
      const double g = *w.value;
      auto is = [&](double v) { return std::abs(g - v) < 1e-9; };
      modes = true;
      if (is(0)) motion = nc::Motion::Kind::Rapid;
      else if (is(1)) motion = nc::Motion::Kind::Feed;
      else if (is(2) || is(3)) trouble = fmt::format("G{}: arcs are not followed by the verifier (rotacal writes none)", w.text);
      else if (is(4)) dwell = true;
      else if (g >= 31.0 && g < 32.0) probe = true;
      else if (is(38.2) || is(38.4)) probe = alarms = true;
      else if (is(38.3) || is(38.5)) probe = true;
      else if (!siemens && is(20)) inch = true;
      else if (!siemens && is(21)) inch = false;
      else if (siemens && (is(70) || is(700))) inch = true;
      else if (siemens && (is(71) || is(710))) inch = false;
      else if (is(90)) incremental = false;
      else if (is(91)) incremental = true;
      else if (is(93)) inverse_time = true;
      else if (is(94)) inverse_time = false;
      else if (is(95)) trouble = "G95 (feed per revolution) is not a probing program's feed";
      else if (is(53) || is(28) || is(30))
        reference_g = g;
      else if (is(10) || is(92) || is(52))
        trouble = fmt::format("G{} changes an offset inside the program: the verifier cannot know the new zero", w.text);
      else if (is(43.4) || is(43.5) || is(68) || is(68.2) || is(234))
        trouble = fmt::format("G{} (tool-centre-point control or a tilted plane) is not followed by the verifier", w.text);
    }
    if (reference_g && trouble.empty()) {
      // The retract every Fanuc and Haas part program ends with (G91 G28 Z0, G53 Z0): Z alone up
      // to the reference, the top of the stroke, which the verifier follows; anything else in
      // machine coordinates it cannot.
      const std::optional<double> z = zFromReference(dialect, *reference_g, incremental, b);
      if (!z) {
        out.push_back(unreadable(
            b.line, fmt::format("G{:g} moves in machine coordinates: the verifier follows program coordinates only{}",
                                *reference_g,
                                dialect.identity().z_reference_at_stroke_top
                                    ? ", and of machine coordinates the retract of Z alone to its reference (G91 G28 "
                                      "Z0, G53 Z0.)"
                                    : "")));
        continue;
      }
      nc::Motion m = motionAt(nc::Motion::Kind::Rapid, b.line);
      m.z_from_reference = *z;
      m.inch = inch;
      out.push_back(m);
      // The retract and the end in one block (G91 G28 Z0 M30): the program ends after it.
      if (std::any_of(b.words.begin(), b.words.end(), endsProgram)) {
        out.push_back(motionAt(nc::Motion::Kind::End, b.line));
        return out;
      }
      continue;
    }
    if (!trouble.empty()) {
      out.push_back(unreadable(b.line, trouble));
      continue;
    }
    if (dwell) continue;  // G4 X2.5 / G4 F2: the words are the time, not axes
    nc::Motion m;
    m.line = b.line;
    for (size_t i = 0; i < b.words.size(); ++i) {
      const auto& w = b.words[i];
      if (w.letter == 'O' && i == 0 && numbered) {
        if (!w.value) {
          trouble = "a program number that is not a number";
          break;
        }
        nc::Motion n;
        n.kind = nc::Motion::Kind::ProgramNumber;
        n.line = b.line;
        n.number = static_cast<int>(std::lround(*w.value));
        out.push_back(n);
      } else if (endsProgram(w)) {
        end = true;
      } else if (w.letter == 'F') {
        if (!w.value) {
          trouble = fmt::format("F{} is an expression: the verifier needs a literal feed", w.text);
          break;
        }
        m.feed = *w.value;
      } else if (isAxisLetter(w.letter)) {
        if (!w.value) {
          trouble = fmt::format("{}{} is an expression or a parameter: the verifier needs literal coordinates", w.letter,
                                w.text);
          break;
        }
        m.words.emplace_back(w.letter, *w.value);
      }
    }
    if (!trouble.empty()) {
      out.push_back(unreadable(b.line, trouble));
      continue;
    }
    m.incremental = incremental;
    m.inch = inch;
    m.inverse_time = inverse_time;
    if (probe) {
      if (m.words.empty()) {
        out.push_back(unreadable(b.line, "a probing word without an axis word"));
        continue;
      }
      m.kind = nc::Motion::Kind::Probe;
      m.alarms = alarms;
    } else if (motion) {
      modal = motion;
    }
    if (!probe && !m.words.empty()) {
      if (!modal) {
        out.push_back(unreadable(b.line, "axis words without G0 or G1 in force"));
        continue;
      }
      m.kind = *modal;
    }
    if (!m.words.empty() || m.feed || modes) {
      if (m.words.empty()) m.kind = nc::Motion::Kind::Setting;
      out.push_back(m);
    }
    if (end) {
      out.push_back(motionAt(nc::Motion::Kind::End, b.line));
      return out;
    }
  }
  return out;
}

std::vector<nc::Motion> readHeidenhain(const std::string& text) {
  std::vector<nc::Motion> out;
  bool inch = false;
  std::optional<std::pair<int, int>> probe_axis;  // from TCH PROBE 0.0
  int last_probe_axis = -1;
  static const std::regex number_prefix(R"(^\s*\d+\s*)");
  static const std::regex check(R"(^FN\s*1[12]\s*:\s*IF\s+\+?Q10\s+(LT|GT)\s+([+-]?[0-9.]+)\s+GOTO\s+LBL)",
                                std::regex::icase);
  static const std::regex probe0(R"(^TCH\s+PROBE\s+0\.0\s+REF\.\s+PLANE\s+Q10\s+([XYZ])([+-])\s*$)", std::regex::icase);
  for (const auto& tl : splitLines(text)) {
    std::string s = std::regex_replace(tl.text, number_prefix, "", std::regex_constants::format_first_only);
    const size_t sc = s.find(';');
    if (sc != std::string::npos) s = s.substr(0, sc);
    s = trim(s);
    if (s.empty()) continue;
    const std::string u = upper(s);
    const auto toks = tokens(u);
    if (toks.empty()) continue;
    std::smatch m;
    if (toks[0] == "BEGIN" && toks.size() >= 4) {
      inch = toks[3] == "INCH";
      continue;
    }
    if (toks[0] == "END" && toks.size() >= 2 && toks[1] == "PGM") {
      nc::Motion e;
      e.kind = nc::Motion::Kind::End;
      e.line = tl.number;
      out.push_back(e);
      return out;
    }
    if (std::regex_search(u, m, probe0)) {
      probe_axis = std::make_pair(static_cast<int>(std::string("XYZ").find(m.str(1)[0])), m.str(2) == "+" ? 1 : -1);
      continue;
    }
    auto axisWords = [&](size_t from, nc::Motion& mo) -> std::string {
      for (size_t i = from; i < toks.size(); ++i) {
        const std::string& t = toks[i];
        if (t.size() >= 2 && isAxisLetter(t[0]) && (t[1] == '+' || t[1] == '-' || std::isdigit(static_cast<unsigned char>(t[1])))) {
          const auto v = parseNumber(t.substr(1));
          if (!v) return fmt::format("{} is not a literal coordinate", t);
          mo.words.emplace_back(t[0], *v);
        }
      }
      return "";
    };
    if (u.rfind("TCH PROBE 0.1", 0) == 0) {
      if (!probe_axis) {
        out.push_back(unreadable(tl.number, "TCH PROBE 0.1 without its TCH PROBE 0.0 line"));
        continue;
      }
      nc::Motion p;
      p.kind = nc::Motion::Kind::Probe;
      p.line = tl.number;
      p.inch = inch;
      p.feed_from_control = true;
      p.travel_axis = probe_axis->first;
      p.travel_sign = probe_axis->second;
      const std::string why = axisWords(2, p);
      if (!why.empty()) {
        out.push_back(unreadable(tl.number, why));
        continue;
      }
      last_probe_axis = probe_axis->first;
      probe_axis.reset();
      out.push_back(p);
      continue;
    }
    if (u.rfind("TCH PROBE", 0) == 0) {
      out.push_back(unreadable(tl.number, "a touch-probe cycle other than cycle 0 is not followed by the verifier"));
      continue;
    }
    if (std::regex_search(u, m, check)) {
      const auto limit = parseNumber(m.str(2));
      if (!limit || last_probe_axis < 0) {
        out.push_back(unreadable(tl.number, "a no-trigger test without a probing move before it"));
        continue;
      }
      nc::Motion c;
      c.kind = nc::Motion::Kind::Check;
      c.line = tl.number;
      const double unit = inch ? 25.4 : 1.0;
      const double back = kHeidenhainNoTriggerMm / unit;
      c.check_end[static_cast<size_t>(last_probe_axis)] = m.str(1) == "LT" ? *limit - back : *limit + back;
      out.push_back(c);
      continue;
    }
    for (const char* kw : {"CYCL DEF 7", "CYCL DEF 19", "PLANE ", "M128", "FUNCTION TCPM", "CC ", "C ", "CR ", "CT "})
      if (u.rfind(kw, 0) == 0 || (std::string(kw) == "M128" && u.find(" M128") != std::string::npos)) {
        out.push_back(unreadable(tl.number, fmt::format("'{}' (datum shift, tilted plane, TCPM or an arc) is not "
                                                        "followed by the verifier", trim(kw))));
        goto next_line;
      }
    if (toks[0] == "L") {
      nc::Motion mo;
      mo.line = tl.number;
      mo.inch = inch;
      bool rapid = false, end = false;
      for (size_t i = 1; i < toks.size(); ++i) {
        const std::string& t = toks[i];
        if (t == "FMAX") rapid = true;
        else if (t[0] == 'F' && t.size() > 1) {
          const auto v = parseNumber(t.substr(1));
          if (!v) {
            out.push_back(unreadable(tl.number, t + " is not a literal feed"));
            goto next_line;
          }
          mo.feed = *v;
        } else if (t == "M30" || t == "M2" || t == "M02") {
          end = true;
        } else if (t[0] == 'I' && t.size() > 1 && isAxisLetter(t[1])) {
          out.push_back(unreadable(tl.number, "incremental coordinates (" + t + ") are not written by rotacal"));
          goto next_line;
        }
      }
      const std::string why = axisWords(1, mo);
      if (!why.empty()) {
        out.push_back(unreadable(tl.number, why));
        continue;
      }
      mo.kind = rapid ? nc::Motion::Kind::Rapid : nc::Motion::Kind::Feed;
      if (!mo.words.empty()) out.push_back(mo);
      if (end) {
        out.push_back(motionAt(nc::Motion::Kind::End, tl.number));
        return out;
      }
    }
  next_line:;
  }
  return out;
}

}  // namespace

bool isStatement(const std::string& code, bool if_is_statement) {
  static const std::regex stmt(
      R"(^\s*(N\d+\s+)?(([A-Z_$][A-Z0-9_$]*)(\[[^\]]*\])?\s*=|[A-Z_][A-Z0-9_]*\s*\(|[A-Z_][A-Z0-9_]*:|(DEF|IF|ELSE|ENDIF|GOTOF|GOTOB|GOTO|STOPRE|FWRITC|FREADC|PUT|WRITE|CLOSE|WHILE|ENDWHILE|LOOP|ENDLOOP|RET|MSG|SPRINT)\b))",
      std::regex::icase);
  std::smatch m;
  if (!std::regex_search(code, m, stmt)) return false;
  // Only the keyword IF matched: the caller reads IF lines itself (the no-trigger checks).
  if (!if_is_statement && m[5].matched && upper(m.str(5)) == "IF") return false;
  const std::string name = upper(m.str(3));
  return !(name.size() == 1 && std::string("XYZABC").find(name) != std::string::npos);
}

bool numbersPrograms(std::string_view dialect) {
  const Dialect* d = findDialect(dialect);
  return d && d->numbersPrograms();
}

std::vector<nc::Motion> readMotions(std::string_view dialect, const std::string& text) {
  const Dialect* d = findDialect(dialect);
  const ProgramLanguage language = d ? d->language() : ProgramLanguage::None;
  if (isWordAddress(language)) return readWordAddress(*d, text);
  if (language == ProgramLanguage::Klartext) return readHeidenhain(text);
  throw std::invalid_argument("dialect '" + std::string(dialect) + "' has no NC programs to read");
}

}  // namespace rotacal::ctl
