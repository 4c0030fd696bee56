#include "controllers/common.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "core/errors.hpp"
#include "core/units.hpp"

namespace rotacal::ctl {

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) throw std::invalid_argument("cannot write a non-finite number into NC text");
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (!s.empty() && s[0] == '-' && s.find_first_of("123456789") == std::string::npos) s.erase(0, 1);
  return s;
}

std::vector<TextLine> splitLines(std::string_view text) {
  std::vector<TextLine> lines;
  int n = 1;
  size_t start = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n' || text[i] == '\r') {
      lines.push_back({n++, std::string(text.substr(start, i - start))});
      if (text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      start = i + 1;
    }
  }
  if (start < text.size()) lines.push_back({n, std::string(text.substr(start))});
  return lines;
}

std::vector<std::string> tokens(std::string_view line) {
  std::vector<std::string> t;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) t.emplace_back(line.substr(b, i - b));
  }
  return t;
}

std::string trim(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return std::string(s.substr(b, e - b));
}

std::string upper(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return r;
}

std::string lower(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

std::optional<double> parseNumber(std::string_view t) {
  size_t i = 0;
  const size_t n = t.size();
  auto digit = [&](size_t k) { return k < n && t[k] >= '0' && t[k] <= '9'; };
  bool negative = false;
  if (i < n && (t[i] == '+' || t[i] == '-')) negative = t[i++] == '-';
  const size_t body = i;
  size_t mantissa_digits = 0;
  while (digit(i)) ++i, ++mantissa_digits;
  if (i < n && t[i] == '.') {
    ++i;
    while (digit(i)) ++i, ++mantissa_digits;
  }
  if (mantissa_digits == 0) return std::nullopt;
  if (i < n && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < n && (t[i] == '+' || t[i] == '-')) ++i;
    if (!digit(i)) return std::nullopt;
    while (digit(i)) ++i;
  }
  if (i != n) return std::nullopt;
  double v = 0.0;
  // from_chars takes no '+' and no sign after we skipped it; a body like "12." or ".5" is fine.
  const auto r = std::from_chars(t.data() + body, t.data() + n, v);
  if (r.ec != std::errc() || r.ptr != t.data() + n || !std::isfinite(v)) return std::nullopt;
  return negative ? -v : v;
}

std::optional<long> parseDigits(std::string_view t) {
  if (t.empty() || t.size() > 9) return std::nullopt;
  long v = 0;
  for (char c : t) {
    if (c < '0' || c > '9') return std::nullopt;
    v = v * 10 + (c - '0');
  }
  return v;
}

void fail(const std::string& file, int line, const std::string& what) { throw InputError(file, line, what); }

PointCollector::PointCollector(const ProbePlan& plan, std::string file) : plan_(plan), file_(std::move(file)) {
  run_.source = file_;
}

void PointCollector::add(int line, int id, const Eigen::Vector3d& p, double t_s) {
  if (!plan_.findPoint(id))
    fail(file_, line,
         fmt::format("point {} is not in the plan ({} cycle, {} points)", id, plan_.cycle, plan_.points.size()));
  const auto it = seen_line_.find(id);
  if (it != seen_line_.end())
    fail(file_, line, fmt::format("point {} appears twice (first at line {})", id, it->second));
  seen_line_[id] = line;
  run_.points.push_back({id, p, t_s});
}

int PointCollector::firstMissing() const {
  for (const auto& p : plan_.points)
    if (!seen_line_.count(p.id)) return p.id;
  return 0;
}

MeasurementRun PointCollector::finish(int last_line) const {
  if (const int missing = firstMissing())
    fail(file_, last_line,
         fmt::format("point {} is missing (the file has {} of the plan's {} points)", missing, run_.points.size(),
                     plan_.points.size()));
  return run_;
}

void requirePlausible(const OffsetRequest& r) {
  if (!r.plan) throw std::invalid_argument("offset request without a plan");
  if (r.identified.kinematics != r.plan->machine.kinematics)
    throw std::invalid_argument("identified errors are for another kinematics than the plan's machine");
  const auto& params = locationParameters(r.identified.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double v = r.identified.values[i];
    if (!std::isfinite(v))
      throw std::invalid_argument(fmt::format("{} is not a finite number; nothing written", params[i].name));
    if (r.force) continue;
    if (params[i].kind == ParamKind::Length && std::abs(v) > kMaxLengthCorrectionMm)
      throw std::invalid_argument(fmt::format(
          "{} = {:.4f} mm exceeds the plausibility limit of {} mm: check the setup and the results, or force it",
          params[i].name, v, kMaxLengthCorrectionMm));
    if (params[i].kind == ParamKind::Angle && std::abs(radToMdeg(v)) > kMaxAngleCorrectionMdeg)
      throw std::invalid_argument(fmt::format(
          "{} = {:.1f} mdeg exceeds the plausibility limit of {} mdeg: check the setup and the results, or force it",
          params[i].name, radToMdeg(v), kMaxAngleCorrectionMdeg));
  }
}

std::vector<std::string> identifiedLines(const OffsetRequest& r) {
  std::vector<std::string> out;
  const auto& params = locationParameters(r.identified.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const ParamKind k = params[i].kind;
    const double u = k == ParamKind::Length ? mmToUm(r.u[i]) : radToMdeg(r.u[i]);
    out.push_back(fmt::format("{:<6} {:<8} {:>10} {:<4} +- {} {}", params[i].name, params[i].iso,
                              fixed(r.identified.reportValue(i), 3), reportUnit(k),
                              std::isfinite(u) ? fixed(u, 3) : std::string("?"), reportUnit(k)));
  }
  return out;
}

double poseAngle(const Pose& pose, char axis) {
  switch (axis) {
    case 'A': return pose.A;
    case 'B': return pose.B;
    default: return pose.C;
  }
}

std::vector<std::string> strokeProblems(const std::vector<nc::Block>& blocks, const ProbePlan& plan,
                                        const std::string& dialect) {
  std::vector<std::string> out;
  const MachineModel& m = plan.machine;
  bool inch = m.units == LengthUnit::Inch;
  bool absolute = true;
  const AxisRange* linear[3] = {&m.x, &m.y, &m.z};
  for (const auto& b : blocks) {
    if (b.control || b.words.empty()) continue;
    for (const auto& w : b.words) {
      if (w.letter != 'G' || !w.value) continue;
      const double g = *w.value;
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

}  // namespace rotacal::ctl
