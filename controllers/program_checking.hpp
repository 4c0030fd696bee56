#pragma once
// The checks every strict program checker makes alike, whatever its dialect's syntax: the
// machine's strokes, inverse time (G93) without F or while probing, the reader's syntax issues,
// the blocks after a probing move where its no-trigger check must stand, and the line-based
// check of the dialects whose programs the word-address reader does not parse.
#include <string>
#include <string_view>
#include <vector>

#include "controllers/text.hpp"
#include "core/probe_plan.hpp"
#include "gcode/program.hpp"
#include "gcode/reader.hpp"

namespace rotacal::ctl {

/// Tolerance of the stroke check on printed coordinates: covers the rounding of 4-5 printed
/// decimals (<= 0.5e-4 mm, inch 0.5e-5 in) with margin.
constexpr double kStrokeTolMm = 1e-3;

/// Any dialect's probing block: G31, G38.x, MEAS=, TCH PROBE.
bool isProbingBlock(const nc::Block& block);

/// Machine-stroke problems of the motion blocks of a parsed program ("LINE: ..."): X/Y/Z
/// endpoints (absolute mode, converted to mm under G20) against the machine's strokes, A/B/C
/// against the rotary strokes in the papers' convention (controller angle / controller sign of
/// `dialect`). Blocks with G10, G53 or G92 are not motion endpoints and are skipped; so are
/// words whose value is an expression.
std::vector<std::string> strokeProblems(const std::vector<nc::Block>& blocks, const ProbePlan& plan,
                                        const std::string& dialect);

/// Syntax issues recorded by the reader, as "LINE: issue".
std::vector<std::string> readerIssues(const std::vector<nc::Block>& blocks);

/// Index of the next non-blank block after `i` (blocks.size() when none).
size_t nextNonBlank(const std::vector<nc::Block>& blocks, size_t i);
/// Indices of the (up to) `n` non-blank blocks after block `i`, in order: where a checker looks
/// for the no-trigger check that must follow a probing move.
std::vector<size_t> nextBlocks(const std::vector<nc::Block>& blocks, size_t i, int n);
/// The checks every block-based checker (Macro B, LinuxCNC) makes of the whole program: its
/// inverse-time problems, then its stroke problems.
std::vector<std::string> blockProblems(const std::vector<nc::Block>& blocks, const ProbePlan& plan,
                                       const std::string& dialect);

/// ISO word-address checks of the modes: under G93 every G1/G2/G3 block with an axis word
/// carries F, and no block under G93 probes (`isProbe`).
std::vector<std::string> inverseTimeProblems(const std::vector<nc::Block>& blocks,
                                             bool (*isProbe)(const nc::Block& block));

/// A line-based program check (the dialects whose programs the NC reader does not parse: okuma,
/// siemens, heidenhain): the text's lines, each line's code without its comments (the dialect
/// fills `code`, knowing its comment syntax) and the problems found, "LINE: what".
class TextCheck {
 public:
  explicit TextCheck(std::string_view text);
  const std::vector<TextLine> lines;
  std::vector<std::string> code;
  std::vector<std::string> problems;

  void problem(int line, const std::string& what);
  /// The number of the text's last line (1 for an empty text).
  int lastLine() const;
  /// Index of the next non-empty `code` entry after `i` (lines.size() when none).
  size_t nextCode(size_t i) const;
  /// Line `i` longer than `max` characters.
  void lineLength(size_t i, size_t max);
  /// "<found> <moves>, the plan has <planned> points" at the last line when the counts differ.
  void probeCount(int found, size_t planned, std::string_view moves);
  /// The checks a line-based checker ends with, in this order: the inverse-time problems of the
  /// whole text, the stroke problems of `motion_text` (the motion blocks at their lines' places,
  /// the others blank, read after the unit line of `inch`), and "LINE: the program does not end
  /// with <end>" when the last code is not `end`. Returns every problem found.
  std::vector<std::string> finish(std::string_view end, const std::string& motion_text, bool inch,
                                  const ProbePlan& plan, const std::string& dialect);

 private:
  std::string text_;
};

}  // namespace rotacal::ctl
