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
#include "controllers/sinumerik_names.hpp"
#include "controllers/end_point_check.hpp"
#include "controllers/motion_reader.hpp"
#include "controllers/program_checking.hpp"
#include "controllers/text.hpp"
#include "core/errors.hpp"
#include "core/require_valid.hpp"
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

// The rewrite of one program, as named steps: the input is refused if it was compensated before;
// each block is then read (the modal state and the nominal command it leaves), compensated (the
// pose, the position, their strokes, a turning feed move split along the nominal path) and printed
// as the dialect spells it; a probing move's no-trigger check is rewritten with its move; last,
// the dialect's own checker judges the rewrite against the input.
class ProgramRewrite {
 public:
  ProgramRewrite(const std::string& text, const std::string& file, const MachineModel& machine,
                 const GeometricErrors& errors, const NcSyntax& syntax, const ProgramCompensationOptions& options)
      : text_(text), file_(file), machine_(machine), errors_(errors), syntax_(syntax), options_(options),
        dialect_(dialectByName(syntax.dialect)), end_check_(dialect_.endPointCheck()), blocks_(nc::readProgram(text)) {
    modal_.inch = machine.units == LengthUnit::Inch;
    for (const auto& r : machine.rotary) {
      rotary_letters_.push_back(r.name);
      modal_.rotary[r.name] = std::nullopt;
    }
  }

  ProgramCompensation run() {
    refuseCompensatedInput();
    prepareHeader();
    for (size_t bi = 0; bi < blocks_.size(); ++bi) {
      if (bi == header_at_) emitHeader();
      emitting_line_ = blocks_[bi].line;
      if (pending_ && rewrotePendingCheck(blocks_[bi])) continue;
      nc::Block b;
      std::string prefix;
      if (!motionPart(blocks_[bi], &b, &prefix)) continue;
      rewriteBlock(b, prefix);
    }
    closePending("before the end of the program");
    if (header_at_ >= blocks_.size()) emitHeader();
    out_.text = std::move(result_);
    recheckWithDialect();
    return std::move(out_);
  }

 private:
  // The program's own word for a position: the controlled point's rounded, printed coordinates.
  struct PrintedPose {
    Pose q_cmd;                               // the compensated pose as printed, papers' convention
    std::map<char, std::string> rotary_text;  // the rotary words' values as printed
  };
  // A feed move split where the joint-space line would leave the nominal path.
  struct Split {
    std::vector<std::pair<Eigen::Vector3d, std::map<char, std::string>>> pieces;  // all but the last end
    double feed_factor = 1.0;  // G93: each piece takes its share of the block's time
  };

  [[noreturn]] void fail(int line, const std::string& why) const { throw InputError(file_, line, why); }
  bool isRotary(char c) const { return modal_.rotary.count(c) > 0; }
  static int linearIndex(char c) { return c == 'X' ? 0 : c == 'Y' ? 1 : c == 'Z' ? 2 : -1; }
  double unitMm() const { return modal_.inch ? kMmPerInch : 1.0; }
  int lengthDecimals() const { return modal_.inch ? syntax_.length_decimals_inch : syntax_.length_decimals_mm; }
  // The program's own comments, kept on a rewritten line.
  std::string comment(const std::string& c) const {
    return syntax_.comment == NcSyntax::Comment::Parentheses ? "(" + c + ")" : ";" + c;
  }
  static const nc::Word* lastWord(const nc::Block& b, char letter) {
    const nc::Word* last = nullptr;
    for (const auto& w : b.words)
      if (w.letter == letter) last = &w;
    return last;
  }
  static void appendWord(std::string& line, const std::string& word) {
    line += (line.empty() || line.back() == '/' || line.back() == ' ' ? "" : " ") + word;
  }

  // ---- Before the first block ----

  // Compensating twice applies the errors twice: the marks this rewrite writes refuse it.
  void refuseCompensatedInput() const {
    const std::string mark = dialect_.compensationMark();
    // Upper case without blanks: how the control reads a statement (LinuxCNC ignores both).
    auto squeezed = [](std::string_view t) {
      std::string out;
      for (char ch : upper(t))
        if (ch != ' ' && ch != '\t') out += ch;
      return out;
    };
    for (const auto& b : blocks_) {
      if (b.raw.size() > kMaxLineChars)
        fail(b.line, fmt::format("line of {} characters: longer than any control accepts (LinuxCNC: 255) and than "
                                 "the {} the rewrite reads",
                                 b.raw.size(), kMaxLineChars));
      for (const auto& c : b.comments)
        if (upper(c).find(kCompensatedMarker) != std::string::npos)
          fail(b.line, fmt::format("the program is already compensated (comment {}): compensating it again would "
                                   "apply the location errors twice; compensate the original program",
                                   kCompensatedMarker));
      if (!mark.empty() && squeezed(b.raw).find(squeezed(mark)) != std::string::npos)
        fail(b.line, fmt::format("the program is already compensated (statement {}): compensating it again would "
                                 "apply the location errors twice; compensate the original program",
                                 mark));
    }
  }

  // The header goes after the program's identification (a leading '%', a Fanuc/Okuma O-number
  // line, a Siemens transfer line "; %_N_NAME_MPF"), in the dialect's own comment form. Zero
  // errors change no word: the program is returned as it was, byte for byte, without the mark
  // (compensating it again, for any errors, is then right).
  void prepareHeader() {
    auto identifies = [](const nc::Block& b) {
      if (b.percent) return true;
      if (!b.control && !b.words.empty() && b.words.front().letter == 'O') return true;
      return b.code.empty() && b.comments.size() == 1 && ctl::trim(b.comments[0]).rfind("%_N_", 0) == 0;
    };
    while (header_at_ < blocks_.size() && identifies(blocks_[header_at_])) ++header_at_;
    header_ = dialect_.commentLines(std::string(kCompensatedMarker) +
                                    ": rewritten by rotacal compensate for the geometric errors below. Never "
                                    "compensate it again; run it only on the uncompensated machine");
    const std::string mark = dialect_.compensationMark();
    if (!mark.empty()) header_.push_back(mark);
    for (const auto& h : options_.header)
      for (auto& l : dialect_.commentLines(h)) header_.push_back(std::move(l));
    bool zero = errors_.location.values.isZero(0.0);
    for (const auto& c : errors_.components)
      for (const auto& v : c.values) zero = zero && v.isZero(0.0);
    if (zero) header_.clear();
  }

  void emit(const std::string& line) {
    result_ += line;
    result_ += '\n';
    source_line_.push_back(emitting_line_);
  }

  void emitHeader() {
    emitting_line_ = 0;
    for (const auto& h : header_) emit(h);
  }

  // ---- A probing move's no-trigger check ----

  // The block after a rewritten probing move: when it is a statement of the move's check, it is
  // given the new end point (true); anything else is for the next step (false).
  bool rewrotePendingCheck(const nc::Block& block) {
    const auto st = ctl::parseEndPointCheckStatement(*end_check_, block.code);
    if (!st) return false;
    const auto a = static_cast<size_t>(st->axis);
    const double tol = 0.5 * std::pow(10.0, -st->decimals) + 1e-9;
    if (std::abs(st->end - pending_->old_end[st->axis]) > tol)
      fail(block.line, fmt::format("this no-trigger check compares {} with {} but the probing move at line {} ends at "
                                   "{}: the rewrite cannot tell what it guards",
                                   "XYZ"[a], st->end, pending_->move_line,
                                   fixedText(pending_->old_end[st->axis], st->decimals)));
    if (pending_->rewritten[a])
      fail(block.line, fmt::format("a second {} statement in the no-trigger check of the probing move at line {}",
                                   "XYZ"[a], pending_->move_line));
    pending_->rewritten[a] = true;
    // The leading N word, if any, stays.
    const size_t at = upper(block.code).find(upper(end_check_->difference[a]));
    std::string line = block.code.substr(0, at) +
                       ctl::endPointCheckStatement(*end_check_, st->axis, pending_->new_end[st->axis], pending_->decimals);
    for (const auto& c : block.comments) line += " " + comment(c);
    emit(line);
    ++out_.rewritten_checks;
    return true;
  }

  // Before the next move: the previous probing move's check must have been rewritten, or it
  // would compare the probe's stop with the old end point and pass a probe that never triggered.
  void closePending(const std::string& where) {
    if (!pending_) return;
    for (int a = 0; a < 3; ++a)
      if (!pending_->rewritten[static_cast<size_t>(a)])
        fail(pending_->move_line,
             fmt::format("the probing move's end point moves, but its no-trigger check ('{}' for {}) was not found "
                         "{}: left as written it would pass a probe that never triggered; give the check right after "
                         "the move in the form rotacal writes",
                         ctl::endPointCheckStatement(*end_check_, a, pending_->old_end[a], 4), "XYZ"[a], where));
    pending_.reset();
  }

  // A rewritten probing move's check must follow it (closePending refuses a program where not).
  void armCheck(const nc::Block& b, bool measuring_prefix, const Eigen::Vector3d& x_nom, const Eigen::Vector3d& x_new) {
    if (!end_check_ || !isGuardedMove(b, measuring_prefix)) return;
    PendingCheck p;
    p.move_line = b.line;
    p.old_end = x_nom / unitMm();
    p.new_end = x_new / unitMm();
    p.decimals = lengthDecimals();
    out_.max_check_shift_mm = std::max(out_.max_check_shift_mm, (x_new - x_nom).norm());
    pending_ = p;
  }

  // ---- Reading a block ----

  // The motion part of a block (false: the block carries none and was written as it is).
  // Statements of the richer dialects (Siemens DEF/IF/WRITE/R90=..., Okuma VC1=.../PUT/FWRITC,
  // labels) pass as written. A Siemens measuring prefix (MEAS=1 G1 ...) is kept in `prefix` and
  // the move behind it is the motion part.
  bool motionPart(const nc::Block& block, nc::Block* b, std::string* prefix) {
    static const std::regex measuring(R"(^\s*(N\d+\s+)?(MEAS|MEAW)\s*=\s*-?\d+\s+)", std::regex::icase);
    refuseFrameChanges(block);
    *b = block;
    std::smatch mm;
    if (std::regex_search(block.raw, mm, measuring)) {
      *prefix = mm.str(0);
      const std::vector<nc::Block> move = nc::readProgram(block.raw.substr(prefix->size()));
      if (move.empty() || move.front().words.empty())
        fail(block.line, fmt::format("'{}' without a move after it: a measuring prefix belongs on a motion block",
                                     upper(std::string_view(*prefix).substr(0, prefix->find_last_not_of(" \t") + 1))));
      *b = move.front();
      b->line = block.line;
      b->raw = block.raw;
      return true;
    }
    if (ctl::isStatement(block.code, true)) {
      emit(block.raw);
      return false;
    }
    return sinumerikMotion(block, b);
  }

  // A Sinumerik block's own names (SOFT, X=-10, a cycle's name) before its words: settings pass
  // on the rewritten line, a block of settings alone as written.
  bool sinumerikMotion(const nc::Block& block, nc::Block* b) {
    block_settings_.clear();
    if (dialect_.language() != ProgramLanguage::Sinumerik) return true;
    const ctl::SinumerikBlock sb = ctl::readSinumerikBlock(b->code);
    if (!sb.problem.empty()) fail(block.line, sb.problem);
    if (sb.code == upper(b->code)) return true;
    const std::vector<nc::Block> read = nc::readProgram(sb.code);
    if (read.empty()) {
      emit(block.raw);
      return false;
    }
    const std::vector<std::string> comments = b->comments;
    *b = read.front();
    b->line = block.line;
    b->raw = block.raw;
    b->comments = comments;
    block_settings_ = sb.settings;
    return true;
  }

  // Frame changes first: the tokenizer reads TRAORI as words T, R, A, ... and would name those.
  void refuseFrameChanges(const nc::Block& b) const {
    if (dialect_.language() != ProgramLanguage::Sinumerik) return;
    if (const auto frame = ctl::sinumerikFrameChange(b.code))
      fail(b.line, fmt::format("{} changes the coordinate frame inside the program: compensate a program in plain "
                               "machine coordinates, or through the kinematics (analyze --offsets)",
                               *frame));
  }

  struct BlockModes {
    bool machine_coords = false;  // G53
    bool home = false;            // G28 / G30
  };

  // The G words: the modal state they set, and what this block alone does.
  BlockModes readGWords(const nc::Block& b) {
    BlockModes modes;
    Modal& m = modal_;
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
      else if (is(53)) modes.machine_coords = true;
      else if (is(28) || is(30)) modes.home = true;
      else if ((g >= 54 && g <= 59.3) || is(505)) {
        // The work offset the program zero (--program-origin) is: chosen once, before any move.
        if ((work_offset_ && std::abs(*work_offset_ - g) > 1e-9) || (!work_offset_ && out_.motion_blocks > 0))
          fail(b.line, fmt::format("G{} changes the work offset inside the program: the rewrite knows one program "
                                   "zero (--program-origin); compensate each work offset's part separately",
                                   w.text));
        work_offset_ = g;
      } else if (is(10) || is(92) || is(52))
        fail(b.line, fmt::format("G{} changes an offset inside the program: the rewrite cannot know the new program "
                                 "zero; set offsets before the program and give --program-origin",
                                 w.text));
      else if (is(43.4) || is(43.5) || is(68) || is(68.2) || is(68.3) || is(68.4) || is(69.1) || is(234) || is(169))
        fail(b.line, fmt::format("G{} (tool-centre-point control or a tilted work plane): such programs are "
                                 "compensated by the control's kinematics, not by rewriting (analyze --offsets)",
                                 w.text));
    }
    return modes;
  }

  // Whether the block has axis words; each must be a literal.
  bool hasAxisWords(const nc::Block& b) const {
    bool has_axis = false;
    for (const auto& w : b.words) {
      if (linearIndex(w.letter) < 0 && !isRotary(w.letter)) continue;
      has_axis = true;
      if (!w.value)
        fail(b.line, fmt::format("{}{} is an expression or a parameter: compensate needs literal coordinates",
                                 w.letter, w.text));
    }
    return has_axis;
  }

  // The rotary and linear words as last printed: a block rewritten at a compensated pose must also
  // carry a rotary word the block lacks when the machine is not yet at the compensated angle; a
  // linear word the block lacks is written only where the compensated position differs from the
  // one last commanded, so zero errors reproduce the program line for line.
  void notePrinted(const nc::Block& b) {
    for (const auto& w : b.words) {
      const int i = linearIndex(w.letter);
      if (i < 0) continue;
      if (modal_.incremental || !w.value) printed_linear_[static_cast<size_t>(i)].reset();
      else printed_linear_[static_cast<size_t>(i)] = *w.value * unitMm();
    }
    for (const auto& w : b.words)
      if (isRotary(w.letter)) printed_rotary_[w.letter] = w.text;
  }

  // Machine-coordinate moves (tool change, parking) do not address the workpiece: unchanged, and
  // the axes they move are no longer known in program coordinates.
  void passMachineCoordinateMove(const nc::Block& b, bool home) {
    for (const auto& w : b.words) {
      if (const int i = linearIndex(w.letter); i >= 0) modal_.xyz_mm[static_cast<size_t>(i)].reset();
      else if (isRotary(w.letter)) modal_.rotary[w.letter].reset();
    }
    if (home)
      for (auto& v : modal_.xyz_mm) v.reset();
    last_nominal_.reset();
    ++out_.uncompensated_blocks;
    notePrinted(b);
    for (const auto& w : b.words)
      if (linearIndex(w.letter) >= 0) printed_linear_[static_cast<size_t>(linearIndex(w.letter))].reset();
    if (home) printed_linear_ = {};
    emit(b.raw);
  }

  // The nominal command after this block (program coordinates, mm; rotary axes in the papers'
  // convention); false when some axis is not known yet (the block then passes unchanged).
  bool advanceNominal(const nc::Block& b, const std::array<std::optional<double>, 3>& before) {
    Modal& m = modal_;
    for (const auto& w : b.words) {
      if (const int i = linearIndex(w.letter); i >= 0) {
        const double v = *w.value * unitMm();
        auto& x = m.xyz_mm[static_cast<size_t>(i)];
        if (!m.incremental) x = v;
        else if (x) x = *x + v;
      } else if (isRotary(w.letter)) {
        if (m.incremental)
          fail(b.line, fmt::format("an incremental (G91) move of {} cannot be compensated: command rotary axes in G90",
                                   w.letter));
        m.rotary[w.letter] = *w.value * machine_.controllerSign(w.letter, syntax_.dialect);
      }
    }
    bool known = m.xyz_mm[0] && m.xyz_mm[1] && m.xyz_mm[2];
    for (const auto& [c, v] : m.rotary) known = known && v.has_value();
    if (m.incremental) known = known && before[0] && before[1] && before[2];
    return known;
  }

  // ---- One block ----

  void rewriteBlock(const nc::Block& b, const std::string& prefix) {
    if (!b.issues.empty()) fail(b.line, b.issues.front());
    if (b.control || b.percent || b.words.empty()) {
      emit(b.raw);
      return;
    }
    const BlockModes modes = readGWords(b);
    if (!hasAxisWords(b)) {
      emit(b.raw);
      return;
    }
    closePending(fmt::format("before the next move at line {}", b.line));
    ++out_.motion_blocks;
    if (modes.machine_coords || modes.home) {
      passMachineCoordinateMove(b, modes.home);
      return;
    }
    if (modal_.motion == Modal::Motion::Arc)
      fail(b.line, "an arc (G2/G3) cannot be compensated point by point: on the machine with errors its plane is "
                   "tilted; output linear moves (G1) from CAM, or compensate through the kinematics (analyze --offsets)");
    const std::array<std::optional<double>, 3> before = modal_.xyz_mm;
    if (!advanceNominal(b, before)) {
      last_nominal_.reset();
      ++out_.uncompensated_blocks;
      notePrinted(b);
      emit(b.raw);
      return;
    }
    compensateBlock(b, prefix, before);
  }

  void compensateBlock(const nc::Block& b, const std::string& prefix, const std::array<std::optional<double>, 3>& before) {
    Pose q;
    for (const auto& [c, v] : modal_.rotary) poseAxis(q, c) = *v;
    const PrintedPose printed = printedCompensatedPose(q, b.line);
    out_.max_direction_residual_rad =
        std::max(out_.max_direction_residual_rad, toolDirectionError(errors_, printed.q_cmd, q, options_.pose.tool_axis_m));
    const Eigen::Vector3d x_nom(*modal_.xyz_mm[0], *modal_.xyz_mm[1], *modal_.xyz_mm[2]);
    const Eigen::Vector3d x_new = compensatedXyz(q, printed.q_cmd, modal_.xyz_mm);
    out_.max_shift_mm = std::max(out_.max_shift_mm, (x_new - x_nom).norm());
    checkLinearStrokes(x_new + options_.program_origin_m_mm, b.line, "the compensated {} {:.4f} mm is outside the stroke "
                                                                      "[{}, {}] mm of MACHINE.json");
    const Eigen::Vector3d words = modal_.incremental ? Eigen::Vector3d(x_new - compensatedXyz(q, printed.q_cmd, before)) : x_new;
    notePositionUncertainty(q, printed.q_cmd, x_nom);
    const MachineCommand nominal_end{x_nom + options_.program_origin_m_mm, q};
    const Split split = splitTurningMove(b, prefix, nominal_end);
    last_nominal_ = nominal_end;
    emit(rewrittenLine(b, prefix, words, printed, split));
    if (!split.pieces.empty()) {
      // The remaining pieces, the last one the block's own end; G1 is modal from the first line.
      for (size_t k = 1; k <= split.pieces.size(); ++k) {
        std::string piece = k < split.pieces.size() ? axisWords(split.pieces[k].first, split.pieces[k].second)
                                                    : axisWords(words, printed.rotary_text);
        if (modal_.inverse_time) piece += " F" + feedText(*lastWord(b, 'F'), split.feed_factor);
        emit(piece);
      }
      for (char c : rotary_letters_) printed_rotary_[c] = printed.rotary_text.at(c);
    }
    for (int i = 0; i < 3; ++i) {
      if (modal_.incremental) printed_linear_[static_cast<size_t>(i)].reset();
      else printed_linear_[static_cast<size_t>(i)] = parsedBack(fixedText(x_new[i] / unitMm(), lengthDecimals())) * unitMm();
    }
    ++out_.compensated_blocks;
    armCheck(b, !prefix.empty(), x_nom, x_new);
  }

  // ---- Compensating ----

  // The compensated pose of nominal pose q as it will be printed (the position is computed for
  // exactly those angles), its rotary words inside MACHINE.json's strokes: the compensation may
  // push an angle that sits on a stroke end past it (A-110.0005 on a [-110, 20] axis).
  PrintedPose printedCompensatedPose(const Pose& q, int line) {
    const std::array<double, 3> key{q.A, q.B, q.C};
    auto it = pose_cache_.find(key);
    if (it == pose_cache_.end()) it = pose_cache_.emplace(key, compensatePose(errors_, q, options_.pose)).first;
    const CompensatedCommand& cc = it->second;
    PrintedPose p{q, {}};
    for (char c : rotary_letters_) {
      const int sign = machine_.controllerSign(c, syntax_.dialect);
      Pose tmp = cc.pose;
      const std::string t = fixedText(sign * poseAxis(tmp, c), syntax_.angle_decimals);
      p.rotary_text[c] = t;
      poseAxis(p.q_cmd, c) = sign * parsedBack(t);
      Pose nominal = q;
      out_.max_rotary_change_deg = std::max(out_.max_rotary_change_deg, std::abs(poseAxis(p.q_cmd, c) - poseAxis(nominal, c)));
    }
    for (char c : rotary_letters_) {
      const RotaryAxis& axis = machine_.rotaryAxis(c);
      const double paper = poseAxis(p.q_cmd, c);
      if (!axis.continuous && !axis.stroke_deg.contains(paper, kRotaryStrokeTolDeg))
        fail(line, fmt::format("the compensated {}{} (papers' convention {:.4f} deg) is outside the stroke [{}, {}] deg "
                               "of MACHINE.json",
                               c, p.rotary_text[c], paper, axis.stroke_deg.min, axis.stroke_deg.max));
    }
    return p;
  }

  // The compensated program coordinates of nominal program coordinates `xyz` at nominal pose q,
  // the machine commanded to q_cmd.
  Eigen::Vector3d compensatedXyz(const Pose& q, const Pose& q_cmd, const std::array<std::optional<double>, 3>& xyz) const {
    const Eigen::Vector3d x_m(*xyz[0], *xyz[1], *xyz[2]);
    return compensatedPosition(errors_, q, x_m + options_.program_origin_m_mm, q_cmd) - options_.program_origin_m_mm;
  }

  // The end point the machine will actually be commanded to, inside the strokes. Only the
  // printing may round it outward (half a unit of the last printed decimal): a soft limit alarms
  // on anything more. `what` formats the axis, the value and the stroke's ends.
  void checkLinearStrokes(const Eigen::Vector3d& x_machine, int line, fmt::string_view what) const {
    const double print_tol_mm = 0.5 * std::pow(10.0, -lengthDecimals()) * unitMm() + 1e-9;
    const std::array<const AxisRange*, 3> strokes{&machine_.x, &machine_.y, &machine_.z};
    for (int i = 0; i < 3; ++i)
      if (!strokes[static_cast<size_t>(i)]->contains(x_machine[i], print_tol_mm)) {
        const char axis = "XYZ"[i];
        const double value = x_machine[i], min = strokes[static_cast<size_t>(i)]->min, max = strokes[static_cast<size_t>(i)]->max;
        fail(line, fmt::vformat(what, fmt::make_format_args(axis, value, min, max)));
      }
  }

  // The standard uncertainty of the compensated controlled point, from the location errors'
  // covariance (largest axis of J C J^T), where the errors carry one.
  void notePositionUncertainty(const Pose& q, const Pose& q_cmd, const Eigen::Vector3d& x_nom) {
    if (!errors_.location_covariance) return;
    const Eigen::Vector3d p_w = T_m_w_nominal(errors_.kinematics(), q).inverse() * (x_nom + options_.program_origin_m_mm);
    const auto J = J_pm_e(errors_.location, q_cmd, p_w);
    const Eigen::Matrix3d C = J * (*errors_.location_covariance) * J.transpose();
    out_.max_position_u_mm = std::max(
        out_.max_position_u_mm, std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C).eigenvalues().maxCoeff())));
  }

  // A feed move that turns a rotary axis: the straight joint-space move between compensated ends
  // leaves the nominal path in between; split it where it would leave it by more than the
  // tolerance (core/compensation.hpp). The pieces' ends are printed as the block's are.
  Split splitTurningMove(const nc::Block& b, const std::string& prefix, const MachineCommand& nominal_end) {
    Split split;
    bool turns = false;
    if (last_nominal_)
      for (char c : rotary_letters_) {
        Pose last = last_nominal_->pose, end = nominal_end.pose;
        turns = turns || std::abs(poseAxis(last, c) - poseAxis(end, c)) > 1e-12;
      }
    if (!options_.subdivide || !last_nominal_ || !turns || modal_.rapid) return split;
    if (modal_.guarded || !prefix.empty()) fail(b.line, "a probing move that turns a rotary axis: probe at a fixed rotary pose");
    auto rounding = [this](const Pose& p) {
      Pose r = p;
      for (char c : rotary_letters_) {
        const int sign = machine_.controllerSign(c, syntax_.dialect);
        poseAxis(r, c) = sign * parsedBack(fixedText(sign * poseAxis(r, c), syntax_.angle_decimals));
      }
      return r;
    };
    CompensatedMove move;
    try {
      move = compensateMove(errors_, *last_nominal_, nominal_end, options_.pose, options_.subdivision, rounding);
    } catch (const std::runtime_error& e) {
      fail(b.line, e.what());
    }
    out_.max_unsplit_deviation_mm = std::max(out_.max_unsplit_deviation_mm, move.unsplit_deviation_mm);
    out_.max_path_deviation_mm = std::max(out_.max_path_deviation_mm, move.max_deviation_mm);
    if (move.ends.size() <= 1) return split;
    if (modal_.incremental) fail(b.line, "a G91 move that turns a rotary axis cannot be split: command it in G90");
    for (const auto& w : b.words)
      if (w.letter == 'M' && w.value && (*w.value == 0 || *w.value == 1 || *w.value == 2 || *w.value == 30 || *w.value == 60))
        fail(b.line, fmt::format("this move must be split to stay on the nominal path, but M{} acts after the move: "
                                 "put it on a line of its own",
                                 w.text));
    ++out_.split_blocks;
    out_.added_blocks += static_cast<int>(move.ends.size()) - 1;
    if (modal_.inverse_time) split.feed_factor = static_cast<double>(move.ends.size());
    for (size_t k = 0; k + 1 < move.ends.size(); ++k) {
      std::map<char, std::string> rt;
      Pose end = move.ends[k].pose;
      for (char c : rotary_letters_) {
        const int sign = machine_.controllerSign(c, syntax_.dialect);
        rt[c] = fixedText(sign * poseAxis(end, c), syntax_.angle_decimals);
        const RotaryAxis& axis = machine_.rotaryAxis(c);
        if (!axis.continuous && !axis.stroke_deg.contains(poseAxis(end, c), kRotaryStrokeTolDeg))
          fail(b.line, fmt::format("a piece of this split move puts {} at {} deg, outside the stroke [{}, {}] deg of "
                                   "MACHINE.json",
                                   c, poseAxis(end, c), axis.stroke_deg.min, axis.stroke_deg.max));
      }
      checkLinearStrokes(move.ends[k].x_m_mm, b.line, "a piece of this split move puts {} at {:.4f} mm, outside the "
                                                      "stroke [{}, {}] mm of MACHINE.json");
      split.pieces.emplace_back(move.ends[k].x_m_mm - options_.program_origin_m_mm, rt);
    }
    if (modal_.inverse_time) {
      const nc::Word* f = lastWord(b, 'F');
      if (f == nullptr || !f->value) fail(b.line, "an inverse-time (G93) move to be split needs its F word as a number on the block");
    }
    return split;
  }

  // ---- Printing ----

  std::string axisWords(const Eigen::Vector3d& w, const std::map<char, std::string>& rotary_text) const {
    std::string a;
    for (int i = 0; i < 3; ++i)
      a += fmt::format("{}{}{}", a.empty() ? "" : " ", "XYZ"[i], fixedText(w[i] / unitMm(), lengthDecimals()));
    for (char c : rotary_letters_) a += fmt::format(" {}{}", c, rotary_text.at(c));
    return a;
  }

  // G93: each piece takes its share of the block's time, F = 1 / time.
  static std::string feedText(const nc::Word& f, double factor) {
    const size_t dot = f.text.find('.');
    const int decimals = std::max(3, dot == std::string::npos ? 0 : static_cast<int>(f.text.size() - dot - 1));
    return fixedText(*f.value * factor, decimals);
  }

  // The block's axis words at the compensated command (a word the block lacks only where the
  // command moved it), its other words and comments as written; a split block's first piece.
  std::string rewrittenLine(const nc::Block& b, const std::string& prefix, const Eigen::Vector3d& words,
                            const PrintedPose& printed, const Split& split) {
    const bool split_move = !split.pieces.empty();
    const int dec = lengthDecimals();
    std::string line = prefix + (b.block_delete ? "/" : "");
    bool axes_written = false;
    for (const auto& w : b.words) {
      // A setting before the words: the block's number stays first, and the motion words keep the
      // form the dialect's checker reads.
      if (!block_settings_.empty() && w.letter != 'N') {
        appendWord(line, block_settings_);
        block_settings_.clear();
      }
      const bool axis_word = linearIndex(w.letter) >= 0 || isRotary(w.letter);
      if (split_move && w.letter == 'F' && modal_.inverse_time) {
        appendWord(line, "F" + feedText(w, split.feed_factor));
        continue;
      }
      if (!axis_word) {
        appendWord(line, std::string(1, w.letter) + w.text);
        continue;
      }
      if (axes_written) continue;
      axes_written = true;
      if (split_move) {
        appendWord(line, axisWords(split.pieces.front().first, split.pieces.front().second));
        continue;
      }
      std::string a;
      for (int i = 0; i < 3; ++i) {
        const bool in_block = b.find("XYZ"[i]) != nullptr;
        const std::string t = fixedText(words[i] / unitMm(), dec);
        const auto& pl = printed_linear_[static_cast<size_t>(i)];
        const bool moved =
            modal_.incremental ? parsedBack(t) != 0.0 : !pl || std::abs(*pl - parsedBack(t) * unitMm()) > 1e-12;
        if (in_block || moved) a += fmt::format("{}{}{}", a.empty() ? "" : " ", "XYZ"[i], t);
      }
      for (char c : rotary_letters_) {
        const bool in_block = b.find(c) != nullptr;
        const std::string& t = printed.rotary_text.at(c);
        const auto pr = printed_rotary_.find(c);
        const bool moved = pr == printed_rotary_.end() || std::abs(parsedBack(pr->second) - parsedBack(t)) > 1e-12;
        if (moved && !in_block && modal_.incremental)
          fail(b.line, fmt::format("the compensated {} must be commanded before this incremental (G91) move: give the "
                                   "rotary axes in a G90 block first",
                                   c));
        if (in_block || moved) {
          a += fmt::format("{}{}{}", a.empty() ? "" : " ", c, t);
          printed_rotary_[c] = t;
        }
      }
      appendWord(line, a);
    }
    for (const auto& c : b.comments) line += " " + comment(c);
    return line;
  }

  // ---- After the last block ----

  // The dialect's own checker, on the input and on the rewrite: the rewrite may add no problem
  // (a rotacal program, clean before, stays clean; a foreign program keeps its own problems).
  // What the input shows stands in for its neutral program: the rewrite must show the same.
  void recheckWithDialect() const {
    ProbePlan plan;
    plan.machine = machine_;
    nc::Shape shape;
    for (const auto& b : blocks_) {
      shape.probes += ctl::isProbingBlock(b);
      shape.inverse_time = shape.inverse_time || b.hasWord('G', 93);
    }
    plan.points.resize(shape.probes);
    std::set<std::pair<int, std::string>> known;
    for (const auto& p : dialect_.check(text_, plan, shape)) known.insert(splitProblem(p));
    for (const auto& p : dialect_.check(out_.text, plan, shape)) {
      auto [line, what] = splitProblem(p);
      const bool mapped = line >= 1 && static_cast<size_t>(line) <= source_line_.size();
      const int src = mapped ? source_line_[static_cast<size_t>(line) - 1] : line;
      if (mapped && src == 0)
        fail(header_at_ < blocks_.size() ? blocks_[header_at_].line : static_cast<int>(blocks_.size()) + 1,
             fmt::format("the header comment rotacal writes here fails the {} checker: {}", syntax_.dialect, what));
      if (!known.count({src, what}))
        fail(std::max(src, 1), fmt::format("the rewritten line fails the {} checker: {}", syntax_.dialect, what));
    }
  }

  // What the rewrite reads.
  const std::string& text_;
  const std::string& file_;
  const MachineModel& machine_;
  const GeometricErrors& errors_;
  const NcSyntax& syntax_;
  const ProgramCompensationOptions& options_;
  const Dialect& dialect_;
  std::string block_settings_;  // a Sinumerik block's settings, written after its N word
  const std::optional<ctl::EndPointCheck> end_check_;
  const std::vector<nc::Block> blocks_;
  std::vector<char> rotary_letters_;
  // Where it is in the program.
  Modal modal_;
  std::map<char, std::string> printed_rotary_;
  std::array<std::optional<double>, 3> printed_linear_;  // G90 program coordinates, mm, as printed
  std::optional<double> work_offset_;                     // G54 ... as first selected
  // The nominal command at the end of the last compensated block (machine frame): where a feed
  // move to be split starts.
  std::optional<MachineCommand> last_nominal_;
  std::optional<PendingCheck> pending_;
  // The compensated pose depends only on the nominal pose.
  std::map<std::array<double, 3>, CompensatedCommand> pose_cache_;
  // What it writes.
  std::vector<std::string> header_;
  size_t header_at_ = 0;
  std::string result_;
  std::vector<int> source_line_;  // per output line: the input line it comes from, 0 for the header
  int emitting_line_ = 0;
  ProgramCompensation out_;
};

}  // namespace

ProgramCompensation compensateProgram(const std::string& text, const std::string& file, const MachineModel& machine,
                                      const GeometricErrors& errors, const NcSyntax& syntax,
                                      const ProgramCompensationOptions& options) {
  requireValid(options.pose, "CompensationOptions");
  if (errors.kinematics() != machine.kinematics)
    throw std::invalid_argument("compensate: the location errors are for another kinematics than the machine");
  if (std::string why; !errors.validate(&why)) throw std::invalid_argument(why);
  const Dialect* named = findDialect(syntax.dialect);
  if (named && !isWordAddress(named->language()))
    throw std::invalid_argument("compensate: '" + syntax.dialect + "' programs are not word-address G-code");
  return ProgramRewrite(text, file, machine, errors, syntax, options).run();
}

MeasurementRun undoCompensation(const ProbePlan& plan, const MeasurementRun& run, const GeometricErrors& errors,
                                const NcSyntax& syntax, const ProgramCompensationOptions& options) {
  if (errors.kinematics() != plan.machine.kinematics)
    throw std::invalid_argument("the compensation's errors are for another kinematics than the plan's machine");
  if (std::string why; !errors.validate(&why)) throw std::invalid_argument(why);
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
