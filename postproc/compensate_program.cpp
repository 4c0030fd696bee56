#include "postproc/compensate_program.hpp"

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <string_view>

#include <fmt/format.h>

#include "controllers/dialect.hpp"
#include "controllers/end_point_check.hpp"
#include "controllers/motion_reader.hpp"
#include "controllers/program_checking.hpp"
#include "controllers/text.hpp"
#include "core/errors.hpp"
#include "core/units.hpp"
#include "gcode/reader.hpp"

namespace rotacal {
namespace {

// The rotary words are compared as printed and parsed back: only the double's own rounding.
constexpr double kRotaryStrokeTolDeg = 1e-9;
// Written at the top of every compensated program, refused in an input program.
constexpr const char* kCompensatedMarker = "ROTACAL-COMPENSATED";
// Across the approach, how far apart the compensated and the uncompensated probing lines must be at
// a touch for it to tell which program ran: far above the program's printed 0.1 um and the
// controller's recorded 0.001 um, below any compensation worth making.
constexpr double kProbingLineSeparationMm = 1e-3;
// Longest input line read. No control in controllers.md takes more than LinuxCNC's 255
// characters; a line of 100 kB would overflow the stack inside std::regex (recursive matcher).
constexpr size_t kMaxLineChars = 1024;

std::string fixedText(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.find_first_not_of("-0.") == std::string::npos) s = fmt::format("{:.{}f}", 0.0, decimals);  // no "-0.0000"
  return s;
}

double parsedBack(const std::string& s) { return std::stod(s); }

std::string upper(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return r;
}


double& poseAxis(Pose& p, char axis) { return axis == 'A' ? p.A : axis == 'B' ? p.B : p.C; }

// Modal state of the program as the rewrite needs it, in the nominal (uncompensated) command.
struct Modal {
  bool inch = false;
  bool incremental = false;
  enum class Motion { Linear, Arc } motion = Motion::Linear;
  bool rapid = false;         // G0 (not split: the control's path)
  bool inverse_time = false;  // G93: F is 1 / the block's time in minutes
  bool guarded = false;       // G31 / G38.x as the modal motion
  std::array<std::optional<double>, 3> xyz_mm;  // program coordinates, mm
  std::map<char, std::optional<double>> rotary;  // paper-convention angles, deg
};

// A rewritten probing move whose no-trigger check (ctl::EndPointCheck) still names the old end
// point: its three statements must be rewritten before the next move.
struct PendingCheck {
  int move_line = 0;
  Eigen::Vector3d old_end;  // program units
  Eigen::Vector3d new_end;  // program units
  int decimals = 4;         // of the move's printed words: the check then equals them digit for digit
  std::array<bool, 3> rewritten{false, false, false};
};

// A probing move: G31 (skip), G38.x (LinuxCNC probe) or a Siemens measuring prefix.
bool isGuardedMove(const nc::Block& b, bool measuring_prefix) {
  if (measuring_prefix) return true;
  for (const auto& w : b.words)
    if (w.letter == 'G' && w.value && ((*w.value >= 31.0 && *w.value < 32.0) || (*w.value >= 38.0 && *w.value < 39.0)))
      return true;
  return false;
}

// "LINE: what" of a checker into its parts; line -1 when there is none.
std::pair<int, std::string> splitProblem(const std::string& p) {
  const size_t colon = p.find(": ");
  if (colon != std::string::npos) {
    const auto n = ctl::parseDigits(p.substr(0, colon));
    if (n) return {static_cast<int>(*n), p.substr(colon + 2)};
  }
  return {-1, p};
}

}  // namespace

ProgramCompensation compensateProgram(const std::string& text, const std::string& file, const MachineModel& machine,
                                      const GeometricErrors& errors, const NcSyntax& syntax,
                                      const ProgramCompensationOptions& options) {
  options.pose.validate();
  if (errors.kinematics() != machine.kinematics)
    throw std::invalid_argument("compensate: the location errors are for another kinematics than the machine");
  errors.validate();
  const Dialect* named = findDialect(syntax.dialect);
  if (named && !isWordAddress(named->language()))
    throw std::invalid_argument("compensate: '" + syntax.dialect + "' programs are not word-address G-code");
  const Dialect& dialect = dialectByName(syntax.dialect);
  const std::optional<ctl::EndPointCheck> end_check = dialect.endPointCheck();
  const std::vector<nc::Block> blocks = nc::readProgram(text);
  ProgramCompensation out;
  Modal m;
  m.inch = machine.units == LengthUnit::Inch;
  std::vector<char> rotary_letters;
  for (const auto& r : machine.rotary) {
    rotary_letters.push_back(r.name);
    m.rotary[r.name] = std::nullopt;
  }
  auto isRotary = [&](char c) { return m.rotary.count(c) > 0; };
  // The rotary words as last printed: a block rewritten at a compensated pose must also carry a
  // rotary word the block lacks when the machine is not yet at the compensated angle.
  std::map<char, std::string> printed_rotary;
  // The linear words likewise (G90 program coordinates, mm, as printed): a linear word the block
  // lacks is written only where the compensated position differs from the one last commanded,
  // so zero errors reproduce the program line for line.
  std::array<std::optional<double>, 3> printed_linear;
  auto linearIndex = [](char c) { return c == 'X' ? 0 : c == 'Y' ? 1 : c == 'Z' ? 2 : -1; };
  auto notePrinted = [&](const nc::Block& b) {
    for (const auto& w : b.words) {
      const int i = linearIndex(w.letter);
      if (i < 0) continue;
      if (m.incremental || !w.value) printed_linear[static_cast<size_t>(i)].reset();
      else printed_linear[static_cast<size_t>(i)] = *w.value * (m.inch ? kMmPerInch : 1.0);
    }
    for (const auto& w : b.words)
      if (isRotary(w.letter)) printed_rotary[w.letter] = w.text;
  };
  auto fail = [&](int line, const std::string& why) -> void { throw InputError(file, line, why); };
  // Cache: the compensated pose depends only on the nominal pose.
  std::map<std::array<double, 3>, CompensatedCommand> pose_cache;

  // The program's own comments, kept on a rewritten line.
  auto comment = [&](const std::string& c) {
    return syntax.comment == NcSyntax::Comment::Parentheses ? "(" + c + ")" : ";" + c;
  };

  const std::string mark = dialect.compensationMark();
  // Upper case without blanks: how the control reads a statement (LinuxCNC ignores both).
  auto squeezed = [](std::string_view t) {
    std::string out;
    for (char ch : upper(t))
      if (ch != ' ' && ch != '\t') out += ch;
    return out;
  };
  for (const auto& b : blocks) {
    if (b.raw.size() > kMaxLineChars)
      fail(b.line, fmt::format("line of {} characters: longer than any control accepts (LinuxCNC: 255) and than the "
                               "{} the rewrite reads",
                               b.raw.size(), kMaxLineChars));
    // Compensating twice applies the errors twice: the marks this function writes refuse it.
    for (const auto& c : b.comments)
      if (upper(c).find(kCompensatedMarker) != std::string::npos)
        fail(b.line, fmt::format("the program is already compensated (comment {}): compensating it again would "
                                 "apply the location errors twice; compensate the original program",
                                 kCompensatedMarker));
    if (!mark.empty() && squeezed(b.raw).find(squeezed(mark)) != std::string::npos)
      fail(b.line, fmt::format("the program is already compensated (statement {}): compensating it again would apply "
                               "the location errors twice; compensate the original program",
                               mark));
  }

  // Header: after the program's identification (a leading '%', a Fanuc/Okuma O-number line, a
  // Siemens transfer line "; %_N_NAME_MPF"), in the dialect's own comment form.
  auto identifies = [](const nc::Block& b) {
    if (b.percent) return true;
    if (!b.control && !b.words.empty() && b.words.front().letter == 'O') return true;
    return b.code.empty() && b.comments.size() == 1 && ctl::trim(b.comments[0]).rfind("%_N_", 0) == 0;
  };
  size_t header_at = 0;
  while (header_at < blocks.size() && identifies(blocks[header_at])) ++header_at;
  std::vector<std::string> header =
      dialect.commentLines(std::string(kCompensatedMarker) +
                           ": rewritten by rotacal compensate for the geometric errors below. Never compensate it "
                           "again; run it only on the uncompensated machine");
  if (!mark.empty()) header.push_back(mark);
  for (const auto& h : options.header)
    for (auto& l : dialect.commentLines(h)) header.push_back(std::move(l));
  // Zero errors change no word: the program is returned as it was, byte for byte, without the
  // mark (compensating it again, for any errors, is then right).
  bool zero = errors.location.values.isZero(0.0);
  for (const auto& c : errors.components)
    for (const auto& v : c.values) zero = zero && v.isZero(0.0);
  if (zero) header.clear();

  std::string result;
  std::vector<int> source_line;  // per output line: the input line it comes from, 0 for the header
  int emitting_line = 0;
  auto emit = [&](const std::string& line) {
    result += line;
    result += '\n';
    source_line.push_back(emitting_line);
  };
  auto emitHeader = [&] {
    emitting_line = 0;
    for (const auto& h : header) emit(h);
  };

  std::optional<PendingCheck> pending;
  // Before the next move: the previous probing move's check must have been rewritten, or it
  // would compare the probe's stop with the old end point and pass a probe that never triggered.
  auto closePending = [&](const std::string& where) {
    if (!pending) return;
    for (int a = 0; a < 3; ++a)
      if (!pending->rewritten[static_cast<size_t>(a)])
        fail(pending->move_line,
             fmt::format("the probing move's end point moves, but its no-trigger check ('{}' for {}) was not found "
                         "{}: left as written it would pass a probe that never triggered; give the check right after "
                         "the move in the form rotacal writes",
                         ctl::endPointCheckStatement(*end_check, a, pending->old_end[a], 4), "XYZ"[a], where));
    pending.reset();
  };

  std::optional<double> work_offset;  // G54 ... as first selected
  // The nominal command at the end of the last compensated block (machine frame): where a feed
  // move to be split starts.
  std::optional<MachineCommand> last_nominal;
  for (size_t bi = 0; bi < blocks.size(); ++bi) {
    if (bi == header_at) emitHeader();
    emitting_line = blocks[bi].line;
    if (pending) {
      if (const auto st = ctl::parseEndPointCheckStatement(*end_check, blocks[bi].code)) {
        const auto a = static_cast<size_t>(st->axis);
        const double tol = 0.5 * std::pow(10.0, -st->decimals) + 1e-9;
        if (std::abs(st->end - pending->old_end[st->axis]) > tol)
          fail(blocks[bi].line,
               fmt::format("this no-trigger check compares {} with {} but the probing move at line {} ends at {}: "
                           "the rewrite cannot tell what it guards",
                           "XYZ"[a], st->end, pending->move_line, fixedText(pending->old_end[st->axis], st->decimals)));
        if (pending->rewritten[a])
          fail(blocks[bi].line, fmt::format("a second {} statement in the no-trigger check of the probing move at line {}",
                                            "XYZ"[a], pending->move_line));
        pending->rewritten[a] = true;
        // The leading N word, if any, stays.
        const std::string code_upper = upper(blocks[bi].code);
        const size_t at = code_upper.find(upper(end_check->difference[a]));
        std::string line = blocks[bi].code.substr(0, at) +
                           ctl::endPointCheckStatement(*end_check, st->axis, pending->new_end[st->axis], pending->decimals);
        for (const auto& c : blocks[bi].comments) line += " " + comment(c);
        emit(line);
        ++out.rewritten_checks;
        continue;
      }
    }
    nc::Block b = blocks[bi];
    // Statements of the richer dialects (Siemens DEF/IF/WRITE/R90=..., Okuma VC1=.../PUT/FWRITC,
    // labels) carry no motion: they pass as written. A Siemens measuring prefix (MEAS=1 G1 ...)
    // is kept and the move behind it rewritten.
    std::string prefix;
    {
      static const std::regex measuring(R"(^\s*(N\d+\s+)?(MEAS|MEAW)\s*=\s*-?\d+\s+)", std::regex::icase);
      std::smatch mm;
      if (std::regex_search(b.raw, mm, measuring)) {
        prefix = mm.str(0);
        const int line_no = b.line;
        const std::vector<nc::Block> move = nc::readProgram(b.raw.substr(prefix.size()));
        if (move.empty() || move.front().words.empty())
          fail(line_no, fmt::format("'{}' without a move after it: a measuring prefix belongs on a motion block",
                                    upper(std::string_view(prefix).substr(0, prefix.find_last_not_of(" \t") + 1))));
        b = move.front();
        b.line = line_no;
        b.raw = blocks[bi].raw;
      } else if (ctl::isStatement(b.code, true)) {
        emit(b.raw);
        continue;
      }
    }
    // Frame changes first: the tokenizer reads TRAORI as words T, R, A, ... and would name those.
    const std::string code_upper = upper(b.code);
    for (const char* kw : {"TRAORI", "TRANSMIT", "TRACYL", "CYCLE800", "ROT ", "AROT", "TRANS ", "ATRANS"})
      if (code_upper.find(kw) != std::string::npos)
        fail(b.line, fmt::format("{} changes the coordinate frame inside the program: compensate a program in plain "
                                 "machine coordinates, or through the kinematics (analyze --offsets)",
                                 std::string(kw)));
    if (!b.issues.empty()) fail(b.line, b.issues.front());
    if (b.control || b.percent || b.words.empty()) {
      emit(b.raw);
      continue;
    }
    bool machine_coords = false, home = false;
    for (const auto& w : b.words) {
      if (w.letter != 'G') continue;
      if (!w.value) fail(b.line, "a G word that is an expression cannot be followed");
      const double g = *w.value;
      auto is = [&](double v) { return std::abs(g - v) < 1e-9; };
      if (is(20)) m.inch = true;
      else if (is(21)) m.inch = false;
      else if (is(90)) m.incremental = false;
      else if (is(91)) m.incremental = true;
      else if (is(0) || is(1) || is(31) || is(38.2) || is(38.3) || is(38.4) || is(38.5)) {
        m.motion = Modal::Motion::Linear;
        m.rapid = is(0);
        m.guarded = !is(0) && !is(1);
      } else if (is(93)) m.inverse_time = true;
      else if (is(94) || is(95)) m.inverse_time = false;
      else if (is(2) || is(3)) m.motion = Modal::Motion::Arc;
      else if (is(53)) machine_coords = true;
      else if (is(28) || is(30)) home = true;
      else if ((g >= 54 && g <= 59.3) || is(505)) {
        // The work offset the program zero (--program-origin) is: chosen once, before any move.
        if ((work_offset && std::abs(*work_offset - g) > 1e-9) || (!work_offset && out.motion_blocks > 0))
          fail(b.line, fmt::format("G{} changes the work offset inside the program: the rewrite knows one program "
                                   "zero (--program-origin); compensate each work offset's part separately",
                                   w.text));
        work_offset = g;
      } else if (is(10) || is(92) || is(52))
        fail(b.line, fmt::format("G{} changes an offset inside the program: the rewrite cannot know the new program "
                                 "zero; set offsets before the program and give --program-origin",
                                 w.text));
      else if (is(43.4) || is(43.5) || is(68) || is(68.2) || is(68.3) || is(68.4) || is(69.1) || is(234) || is(169))
        fail(b.line, fmt::format("G{} (tool-centre-point control or a tilted work plane): such programs are "
                                 "compensated by the control's kinematics, not by rewriting (analyze --offsets)",
                                 w.text));
    }
    // Axis words of this block.
    bool has_axis = false;
    for (const auto& w : b.words) {
      const bool lin = w.letter == 'X' || w.letter == 'Y' || w.letter == 'Z';
      if (!lin && !isRotary(w.letter)) continue;
      has_axis = true;
      if (!w.value)
        fail(b.line, fmt::format("{}{} is an expression or a parameter: compensate needs literal coordinates",
                                 w.letter, w.text));
    }
    if (!has_axis) {
      emit(b.raw);
      continue;
    }
    closePending(fmt::format("before the next move at line {}", b.line));
    ++out.motion_blocks;
    const double unit_mm = m.inch ? kMmPerInch : 1.0;
    if (machine_coords || home) {
      // Machine-coordinate moves (tool change, parking) do not address the workpiece: unchanged,
      // and the axes they move are no longer known in program coordinates.
      for (const auto& w : b.words) {
        if (w.letter == 'X') m.xyz_mm[0].reset();
        else if (w.letter == 'Y') m.xyz_mm[1].reset();
        else if (w.letter == 'Z') m.xyz_mm[2].reset();
        else if (isRotary(w.letter)) m.rotary[w.letter].reset();
      }
      if (home)
        for (auto& v : m.xyz_mm) v.reset();
      last_nominal.reset();
      ++out.uncompensated_blocks;
      notePrinted(b);
      // Machine coordinates are not program coordinates: what they moved is no longer known.
      for (const auto& w : b.words)
        if (linearIndex(w.letter) >= 0) printed_linear[static_cast<size_t>(linearIndex(w.letter))].reset();
      if (home) printed_linear = {};
      emit(b.raw);
      continue;
    }
    if (m.motion == Modal::Motion::Arc)
      fail(b.line, "an arc (G2/G3) cannot be compensated point by point: on the machine with errors its plane is "
                   "tilted; output linear moves (G1) from CAM, or compensate through the kinematics (analyze --offsets)");
    // The nominal command before and after this block.
    const std::array<std::optional<double>, 3> before = m.xyz_mm;
    for (const auto& w : b.words) {
      const int i = w.letter == 'X' ? 0 : w.letter == 'Y' ? 1 : w.letter == 'Z' ? 2 : -1;
      if (i >= 0) {
        const double v = *w.value * unit_mm;
        if (m.incremental) {
          if (m.xyz_mm[i]) m.xyz_mm[i] = *m.xyz_mm[i] + v;
        } else {
          m.xyz_mm[i] = v;
        }
      } else if (isRotary(w.letter)) {
        if (m.incremental)
          fail(b.line, fmt::format("an incremental (G91) move of {} cannot be compensated: command rotary axes in G90",
                                   w.letter));
        m.rotary[w.letter] = *w.value * machine.controllerSign(w.letter, syntax.dialect);
      }
    }
    bool known = m.xyz_mm[0] && m.xyz_mm[1] && m.xyz_mm[2];
    for (const auto& [c, v] : m.rotary) known = known && v.has_value();
    if (m.incremental) known = known && before[0] && before[1] && before[2];
    if (!known) {
      last_nominal.reset();
      ++out.uncompensated_blocks;
      notePrinted(b);
      emit(b.raw);
      continue;
    }
    Pose q;
    for (const auto& [c, v] : m.rotary) poseAxis(q, c) = *v;
    const std::array<double, 3> key{q.A, q.B, q.C};
    auto it = pose_cache.find(key);
    if (it == pose_cache.end()) it = pose_cache.emplace(key, compensatePose(errors, q, options.pose)).first;
    const CompensatedCommand& cc = it->second;
    // The rotary words as they will be printed; the position is computed for exactly those.
    Pose q_cmd = q;
    std::map<char, std::string> rotary_text;
    for (char c : rotary_letters) {
      const int sign = machine.controllerSign(c, syntax.dialect);
      Pose tmp = cc.pose;
      const std::string t = fixedText(sign * poseAxis(tmp, c), syntax.angle_decimals);
      rotary_text[c] = t;
      poseAxis(q_cmd, c) = sign * parsedBack(t);
      out.max_rotary_change_deg = std::max(out.max_rotary_change_deg, std::abs(poseAxis(q_cmd, c) - poseAxis(q, c)));
    }
    // Stroke check of the rotary words as printed: the compensation may push an angle that sits
    // on a stroke end past it (A-110.0005 on a [-110, 20] axis).
    for (char c : rotary_letters) {
      const RotaryAxis& axis = machine.rotaryAxis(c);
      const double paper = poseAxis(q_cmd, c);
      if (!axis.continuous && !axis.stroke_deg.contains(paper, kRotaryStrokeTolDeg))
        fail(b.line, fmt::format("the compensated {}{} (papers' convention {:.4f} deg) is outside the stroke [{}, {}] "
                                 "deg of MACHINE.json",
                                 c, rotary_text[c], paper, axis.stroke_deg.min, axis.stroke_deg.max));
    }
    out.max_direction_residual_rad =
        std::max(out.max_direction_residual_rad, toolDirectionError(errors, q_cmd, q, options.pose.tool_axis_m));
    auto compensate = [&](const std::array<std::optional<double>, 3>& xyz) {
      const Eigen::Vector3d x_m(*xyz[0], *xyz[1], *xyz[2]);
      return Eigen::Vector3d(compensatedPosition(errors, q, x_m + options.program_origin_m_mm, q_cmd) -
                             options.program_origin_m_mm);
    };
    const Eigen::Vector3d x_nom(*m.xyz_mm[0], *m.xyz_mm[1], *m.xyz_mm[2]);
    const Eigen::Vector3d x_new = compensate(m.xyz_mm);
    out.max_shift_mm = std::max(out.max_shift_mm, (x_new - x_nom).norm());
    // Stroke check of the endpoint the machine will actually be commanded to. Only the printing
    // may round it outward (half a unit of the last printed decimal): a soft limit alarms on
    // anything more.
    const int dec = m.inch ? syntax.length_decimals_inch : syntax.length_decimals_mm;
    const double print_tol_mm = 0.5 * std::pow(10.0, -dec) * unit_mm + 1e-9;
    const Eigen::Vector3d x_machine = x_new + options.program_origin_m_mm;
    const std::array<const AxisRange*, 3> strokes{&machine.x, &machine.y, &machine.z};
    for (int i = 0; i < 3; ++i)
      if (!strokes[i]->contains(x_machine[i], print_tol_mm))
        fail(b.line, fmt::format("the compensated {} {:.4f} mm is outside the stroke [{}, {}] mm of MACHINE.json",
                                 "XYZ"[i], x_machine[i], strokes[i]->min, strokes[i]->max));
    Eigen::Vector3d words = x_new;
    if (m.incremental) words = x_new - compensate(before);
    if (errors.location_covariance) {
      const Eigen::Vector3d p_w = T_m_w_nominal(errors.kinematics(), q).inverse() * (x_nom + options.program_origin_m_mm);
      const auto J = J_pm_e(errors.location, q_cmd, p_w);
      const Eigen::Matrix3d C = J * (*errors.location_covariance) * J.transpose();
      out.max_position_u_mm =
          std::max(out.max_position_u_mm, std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C).eigenvalues().maxCoeff())));
    }
    // A feed move that turns a rotary axis: the straight joint-space move between compensated
    // ends leaves the nominal path in between; split it where it would leave it by more than
    // the tolerance (core/compensation.hpp). The pieces' ends are printed as the block's are.
    std::vector<std::pair<Eigen::Vector3d, std::map<char, std::string>>> pieces;  // all but the last
    double piece_feed_factor = 1.0;
    const MachineCommand nominal_end{x_nom + options.program_origin_m_mm, q};
    bool turns = false;
    if (last_nominal)
      for (char c : rotary_letters) turns = turns || std::abs(poseAxis(last_nominal->pose, c) - poseAxis(q, c)) > 1e-12;
    if (options.subdivide && last_nominal && turns && !m.rapid) {
      if (m.guarded || !prefix.empty())
        fail(b.line, "a probing move that turns a rotary axis: probe at a fixed rotary pose");
      auto rounding = [&](const Pose& p) {
        Pose r = p;
        for (char c : rotary_letters) {
          const int sign = machine.controllerSign(c, syntax.dialect);
          poseAxis(r, c) = sign * parsedBack(fixedText(sign * poseAxis(r, c), syntax.angle_decimals));
        }
        return r;
      };
      CompensatedMove move;
      try {
        move = compensateMove(errors, *last_nominal, nominal_end, options.pose, options.subdivision, rounding);
      } catch (const std::runtime_error& e) {
        fail(b.line, e.what());
      }
      out.max_unsplit_deviation_mm = std::max(out.max_unsplit_deviation_mm, move.unsplit_deviation_mm);
      out.max_path_deviation_mm = std::max(out.max_path_deviation_mm, move.max_deviation_mm);
      if (move.ends.size() > 1) {
        if (m.incremental) fail(b.line, "a G91 move that turns a rotary axis cannot be split: command it in G90");
        for (const auto& w : b.words)
          if (w.letter == 'M' && w.value &&
              (*w.value == 0 || *w.value == 1 || *w.value == 2 || *w.value == 30 || *w.value == 60))
            fail(b.line, fmt::format("this move must be split to stay on the nominal path, but M{} acts after the "
                                     "move: put it on a line of its own",
                                     w.text));
        ++out.split_blocks;
        out.added_blocks += static_cast<int>(move.ends.size()) - 1;
        if (m.inverse_time) piece_feed_factor = static_cast<double>(move.ends.size());
        for (size_t k = 0; k + 1 < move.ends.size(); ++k) {
          std::map<char, std::string> rt;
          for (char c : rotary_letters) {
            const int sign = machine.controllerSign(c, syntax.dialect);
            rt[c] = fixedText(sign * poseAxis(move.ends[k].pose, c), syntax.angle_decimals);
            const RotaryAxis& axis = machine.rotaryAxis(c);
            if (!axis.continuous && !axis.stroke_deg.contains(poseAxis(move.ends[k].pose, c), kRotaryStrokeTolDeg))
              fail(b.line, fmt::format("a piece of this split move puts {} at {} deg, outside the stroke [{}, {}] deg "
                                       "of MACHINE.json",
                                       c, poseAxis(move.ends[k].pose, c), axis.stroke_deg.min, axis.stroke_deg.max));
          }
          const Eigen::Vector3d xm = move.ends[k].x_m_mm;
          for (int i = 0; i < 3; ++i)
            if (!strokes[i]->contains(xm[i], print_tol_mm))
              fail(b.line, fmt::format("a piece of this split move puts {} at {:.4f} mm, outside the stroke [{}, {}] mm "
                                       "of MACHINE.json",
                                       "XYZ"[i], xm[i], strokes[i]->min, strokes[i]->max));
          pieces.emplace_back(xm - options.program_origin_m_mm, rt);
        }
      }
    }
    last_nominal = nominal_end;
    auto axisWords = [&](const Eigen::Vector3d& w, const std::map<char, std::string>& rt) {
      std::string a;
      for (int i = 0; i < 3; ++i) a += fmt::format("{}{}{}", a.empty() ? "" : " ", "XYZ"[i], fixedText(w[i] / unit_mm, dec));
      for (char c : rotary_letters) a += fmt::format(" {}{}", c, rt.at(c));
      return a;
    };
    // G93: each piece takes its share of the block's time, F = 1 / time.
    auto feedText = [&](const nc::Word& f) {
      const size_t dot = f.text.find('.');
      const int decimals = std::max(3, dot == std::string::npos ? 0 : static_cast<int>(f.text.size() - dot - 1));
      return fixedText(*f.value * piece_feed_factor, decimals);
    };
    const nc::Word* feed_word = nullptr;
    for (const auto& w : b.words)
      if (w.letter == 'F') feed_word = &w;
    if (m.inverse_time && !pieces.empty() && (feed_word == nullptr || !feed_word->value))
      fail(b.line, "an inverse-time (G93) move to be split needs its F word as a number on the block");
    std::string line = prefix + (b.block_delete ? "/" : "");
    bool axes_written = false;
    for (const auto& w : b.words) {
      const bool lin = w.letter == 'X' || w.letter == 'Y' || w.letter == 'Z';
      if (!pieces.empty() && w.letter == 'F' && m.inverse_time) {
        line += (line.empty() || line.back() == '/' || line.back() == ' ' ? "" : " ") + std::string("F") + feedText(w);
        continue;
      }
      if ((lin || isRotary(w.letter)) && !pieces.empty()) {
        if (axes_written) continue;
        axes_written = true;
        line += (line.empty() || line.back() == '/' || line.back() == ' ' ? "" : " ") +
                axisWords(pieces.front().first, pieces.front().second);
        continue;
      }
      if (lin || isRotary(w.letter)) {
        if (axes_written) continue;
        axes_written = true;
        std::string a;
        for (int i = 0; i < 3; ++i) {
          bool in_block = false;
          for (const auto& w2 : b.words) in_block = in_block || w2.letter == "XYZ"[i];
          const std::string t = fixedText(words[i] / unit_mm, dec);
          const auto& pl = printed_linear[static_cast<size_t>(i)];
          const bool moved = m.incremental ? parsedBack(t) != 0.0 : !pl || std::abs(*pl - parsedBack(t) * unit_mm) > 1e-12;
          if (in_block || moved) a += fmt::format("{}{}{}", a.empty() ? "" : " ", "XYZ"[i], t);
        }
        for (char c : rotary_letters) {
          bool in_block = false;
          for (const auto& w2 : b.words) in_block = in_block || w2.letter == c;
          const auto pr = printed_rotary.find(c);
          const bool moved = pr == printed_rotary.end() || std::abs(parsedBack(pr->second) - parsedBack(rotary_text[c])) > 1e-12;
          if (moved && !in_block && m.incremental)
            fail(b.line, fmt::format("the compensated {} must be commanded before this incremental (G91) move: "
                                     "give the rotary axes in a G90 block first",
                                     c));
          if (in_block || moved) {
            a += fmt::format("{}{}{}", a.empty() ? "" : " ", c, rotary_text[c]);
            printed_rotary[c] = rotary_text[c];
          }
        }
        line += (line.empty() || line.back() == '/' || line.back() == ' ' ? "" : " ") + a;
        continue;
      }
      line += (line.empty() || line.back() == '/' || line.back() == ' ' ? "" : " ") + std::string(1, w.letter) + w.text;
    }
    for (const auto& c : b.comments) line += " " + comment(c);
    emit(line);
    if (!pieces.empty()) {
      // The remaining pieces, the last one the block's own end; G1 is modal from the first line.
      for (size_t k = 1; k <= pieces.size(); ++k) {
        std::string piece = k < pieces.size() ? axisWords(pieces[k].first, pieces[k].second) : axisWords(words, rotary_text);
        if (m.inverse_time) piece += " F" + feedText(*feed_word);
        emit(piece);
      }
      for (char c : rotary_letters) printed_rotary[c] = rotary_text[c];
    }
    for (int i = 0; i < 3; ++i) {
      if (m.incremental) printed_linear[static_cast<size_t>(i)].reset();
      else printed_linear[static_cast<size_t>(i)] = parsedBack(fixedText(x_new[i] / unit_mm, dec)) * unit_mm;
    }
    ++out.compensated_blocks;
    if (end_check && isGuardedMove(b, !prefix.empty())) {
      PendingCheck p;
      p.move_line = b.line;
      p.old_end = x_nom / unit_mm;
      p.new_end = x_new / unit_mm;
      p.decimals = dec;
      out.max_check_shift_mm = std::max(out.max_check_shift_mm, (x_new - x_nom).norm());
      pending = p;
    }
  }
  closePending("before the end of the program");
  if (header_at >= blocks.size()) emitHeader();
  out.text = std::move(result);

  // The dialect's own checker, on the input and on the rewrite: the rewrite may add no problem
  // (a rotacal program, clean before, stays clean; a foreign program keeps its own problems).
  // What the input shows stands in for its neutral program: the rewrite must show the same.
  ProbePlan plan;
  plan.machine = machine;
  nc::Shape shape;
  for (const auto& b : blocks) {
    shape.probes += ctl::isProbingBlock(b);
    shape.inverse_time = shape.inverse_time || b.hasWord('G', 93);
  }
  plan.points.resize(shape.probes);
  std::set<std::pair<int, std::string>> known;
  for (const auto& p : dialect.check(text, plan, shape)) known.insert(splitProblem(p));
  for (const auto& p : dialect.check(out.text, plan, shape)) {
    auto [line, what] = splitProblem(p);
    const bool mapped = line >= 1 && static_cast<size_t>(line) <= source_line.size();
    const int src = mapped ? source_line[static_cast<size_t>(line) - 1] : line;
    if (mapped && src == 0)
      fail(header_at < blocks.size() ? blocks[header_at].line : static_cast<int>(blocks.size()) + 1,
           fmt::format("the header comment rotacal writes here fails the {} checker: {}", syntax.dialect, what));
    if (!known.count({src, what}))
      fail(std::max(src, 1), fmt::format("the rewritten line fails the {} checker: {}", syntax.dialect, what));
  }
  return out;
}

MeasurementRun undoCompensation(const ProbePlan& plan, const MeasurementRun& run, const GeometricErrors& errors,
                                const NcSyntax& syntax, const ProgramCompensationOptions& options) {
  if (errors.kinematics() != plan.machine.kinematics)
    throw std::invalid_argument("the compensation's errors are for another kinematics than the plan's machine");
  errors.validate();
  std::map<std::array<double, 3>, Pose> printed;  // nominal pose -> compensated pose as printed
  MeasurementRun out = run;
  for (auto& t : out.points) {
    const ProbePoint* p = plan.findPoint(t.point_id);
    if (!p) throw std::invalid_argument(fmt::format("point {} is not in the plan", t.point_id));
    const Pose& q = p->pose;
    const std::array<double, 3> key{q.A, q.B, q.C};
    auto it = printed.find(key);
    if (it == printed.end()) {
      Pose qc = compensatePose(errors, q, options.pose).pose;
      for (const auto& r : plan.machine.rotary) {
        const int sign = plan.machine.controllerSign(r.name, syntax.dialect);
        poseAxis(qc, r.name) = sign * parsedBack(fixedText(sign * poseAxis(qc, r.name), syntax.angle_decimals));
      }
      it = printed.emplace(key, qc).first;
    }
    const Eigen::Vector3d x = t.position_m_mm + options.program_origin_m_mm;
    t.position_m_mm = T_m_w_nominal(errors.kinematics(), q) * (T_m_w(errors, it->second).inverse() * x) -
                      options.program_origin_m_mm;
  }
  // The results must be of the compensated program. A controller records positions on the line
  // it ran: the compensated program's touches lie on the plan's probing lines once read back, the
  // uncompensated program's before. Read back as compensated, the latter would identify the
  // errors minus the compensation - a residual near zero, a false "verified".
  int decisive = 0, on_nominal = 0;
  for (size_t i = 0; i < out.points.size(); ++i) {
    const ProbePoint& p = *plan.findPoint(out.points[i].point_id);
    auto across = [&](const Eigen::Vector3d& x) {
      const Eigen::Vector3d d = x - p.trigger_m_mm;
      return (d - d.dot(p.approach_m) * p.approach_m).norm();
    };
    const double raw = across(run.points[i].position_m_mm), undone = across(out.points[i].position_m_mm);
    if (std::abs(raw - undone) < kProbingLineSeparationMm) continue;
    ++decisive;
    if (raw < undone) ++on_nominal;
  }
  if (2 * on_nominal > decisive)
    throw std::invalid_argument(fmt::format(
        "{} of the {} touches where the two programs' probing lines differ by {:.1f} um or more lie on the "
        "uncompensated program's lines: these are not the results of the program compensated for these errors "
        "(analyze them without --compensated-with)",
        on_nominal, decisive, kProbingLineSeparationMm * 1000.0));
  return out;
}

}  // namespace rotacal
