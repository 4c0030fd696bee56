#include "controllers/program_checking.hpp"

#include <fmt/format.h>

#include "core/units.hpp"

namespace rotacal::ctl {

bool isProbingBlock(const nc::Block& b) {
  return b.hasWord('G', 31) || b.hasWord('G', 38.2) || b.hasWord('G', 38.3) || b.hasWord('G', 38.4) ||
         b.hasWord('G', 38.5) || ctl::upper(b.code).find("MEAS") != std::string::npos;
}

namespace {
// The G codes of a block with a value, in order: the modes the checks below follow.
std::vector<double> gCodes(const nc::Block& b) {
  std::vector<double> out;
  for (const auto& w : b.words)
    if (w.letter == 'G' && w.value) out.push_back(*w.value);
  return out;
}
}  // namespace

std::vector<std::string> strokeProblems(const std::vector<nc::Block>& blocks, const ProbePlan& plan,
                                        const std::string& dialect) {
  std::vector<std::string> out;
  const MachineModel& m = plan.machine;
  bool inch = m.units == LengthUnit::Inch;
  bool absolute = true;
  const AxisRange* linear[3] = {&m.x, &m.y, &m.z};
  for (const auto& b : blocks) {
    if (b.control || b.words.empty()) continue;
    for (const double g : gCodes(b)) {
      if (g == 20) inch = true;
      if (g == 21) inch = false;
      if (g == 90) absolute = true;
      if (g == 91) absolute = false;
    }
    if (!absolute || b.hasWord('G', 10) || b.hasWord('G', 53) || b.hasWord('G', 92) || b.hasWord('G', 52)) continue;
    for (const auto& w : b.words) {
      if (!w.value) continue;
      const double v = *w.value;
      if (w.letter >= 'X' && w.letter <= 'Z') {
        const int i = w.letter - 'X';
        const double mm = inch ? v * kMmPerInch : v;
        if (!linear[i]->contains(mm, kStrokeTolMm))
          out.push_back(fmt::format("{}: {} = {:.4f} mm is outside the stroke [{}, {}]", b.line, w.letter, mm,
                                    linear[i]->min, linear[i]->max));
      } else if (w.letter >= 'A' && w.letter <= 'C') {
        if (!m.hasRotary(w.letter)) {
          out.push_back(fmt::format("{}: the machine has no rotary axis {}", b.line, w.letter));
          continue;
        }
        const RotaryAxis& r = m.rotaryAxis(w.letter);
        const double paper = v / m.controllerSign(w.letter, dialect);
        if (!r.continuous && !r.stroke_deg.contains(paper, 1e-6))
          out.push_back(fmt::format("{}: {} = {:.4f} deg (papers' convention {:.4f}) is outside the stroke [{}, {}]",
                                    b.line, w.letter, v, paper, r.stroke_deg.min, r.stroke_deg.max));
      }
    }
  }
  return out;
}

std::vector<std::string> readerIssues(const std::vector<nc::Block>& blocks) {
  std::vector<std::string> out;
  for (const auto& b : blocks)
    for (const auto& issue : b.issues) out.push_back(fmt::format("{}: {}", b.line, issue));
  return out;
}

size_t nextNonBlank(const std::vector<nc::Block>& blocks, size_t i) {
  for (size_t k = i + 1; k < blocks.size(); ++k)
    if (!blocks[k].empty()) return k;
  return blocks.size();
}

std::vector<size_t> nextBlocks(const std::vector<nc::Block>& blocks, size_t i, int n) {
  std::vector<size_t> out;
  for (size_t j = nextNonBlank(blocks, i); j < blocks.size() && static_cast<int>(out.size()) < n;
       j = nextNonBlank(blocks, j))
    out.push_back(j);
  return out;
}

std::vector<std::string> blockProblems(const std::vector<nc::Block>& blocks, const ProbePlan& plan,
                                       const std::string& dialect) {
  std::vector<std::string> out = inverseTimeProblems(blocks, isProbingBlock);
  for (auto& s : strokeProblems(blocks, plan, dialect)) out.push_back(std::move(s));
  return out;
}

std::vector<std::string> inverseTimeProblems(const std::vector<nc::Block>& blocks, bool (*isProbe)(const nc::Block&)) {
  std::vector<std::string> out;
  bool g93 = false;
  int motion = 0;
  for (const auto& b : blocks) {
    if (b.control || b.words.empty()) continue;
    for (const double g : gCodes(b)) {
      if (g == 93) g93 = true;
      if (g == 94 || g == 95) g93 = false;
      if (g == 0 || g == 1 || g == 2 || g == 3) motion = static_cast<int>(g);
    }
    if (!g93) continue;
    // Non-motion G codes whose X/P words are no axis moves: dwell (G04 X2.), data setting (G10).
    if (b.hasWord('G', 4) || b.hasWord('G', 10)) continue;
    if (isProbe && isProbe(b)) {
      out.push_back(fmt::format("{}: probing under inverse-time feed G93 (switch to G94 first)", b.line));
      continue;
    }
    bool axis_word = false;
    for (const auto& w : b.words)
      if ((w.letter >= 'X' && w.letter <= 'Z') || (w.letter >= 'A' && w.letter <= 'C')) axis_word = true;
    if (axis_word && motion >= 1 && !b.find('F'))
      out.push_back(fmt::format("{}: inverse-time (G93) move without an F word", b.line));
  }
  return out;
}

TextCheck::TextCheck(std::string_view text) : lines(splitLines(text)), code(lines.size()), text_(text) {}

void TextCheck::problem(int line, const std::string& what) { problems.push_back(fmt::format("{}: {}", line, what)); }

int TextCheck::lastLine() const { return lines.empty() ? 1 : lines.back().number; }

size_t TextCheck::nextCode(size_t i) const {
  for (size_t j = i + 1; j < code.size(); ++j)
    if (!code[j].empty()) return j;
  return code.size();
}

void TextCheck::lineLength(size_t i, size_t max) {
  if (lines[i].text.size() > max)
    problem(lines[i].number, fmt::format("line has {} characters, more than {}", lines[i].text.size(), max));
}

void TextCheck::probeCount(int found, size_t planned, std::string_view moves) {
  if (static_cast<size_t>(found) != planned)
    problem(lastLine(), fmt::format("{} {}, the plan has {} points", found, moves, planned));
}

std::vector<std::string> TextCheck::finish(std::string_view end, const std::string& motion_text, bool inch,
                                           const ProbePlan& plan, const std::string& dialect) {
  for (auto& s : inverseTimeProblems(nc::readProgram(text_), isProbingBlock)) problems.push_back(std::move(s));
  // The unit line comes first: each motion block then keeps its line's number.
  std::vector<nc::Block> blocks = nc::readProgram(std::string(inch ? "G20" : "G21") + "\n" + motion_text);
  for (size_t i = 0; i < blocks.size(); ++i) blocks[i].line = static_cast<int>(i);
  for (auto& s : strokeProblems(blocks, plan, dialect)) problems.push_back(std::move(s));
  size_t last = lines.size();
  for (size_t i = 0; i < lines.size(); ++i)
    if (!code[i].empty()) last = i;
  if (last == lines.size() || code[last] != end)
    problem(last == lines.size() ? 1 : lines[last].number, fmt::format("the program does not end with {}", end));
  return std::move(problems);
}

}  // namespace rotacal::ctl
