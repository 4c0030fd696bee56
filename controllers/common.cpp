#include "controllers/common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "controllers/result_checks.hpp"
#include "core/errors.hpp"
#include "core/limits.hpp"
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

std::string printableLine(std::string_view text) {
  std::string s(text);
  for (auto& c : s)
    if (c < 0x20 || c > 0x7e) c = ' ';
  return s;
}

std::vector<std::string> wrap(std::string_view text, size_t width) {
  const std::string s = trim(text);
  std::vector<std::string> out;
  size_t i = 0;
  while (i < s.size()) {
    size_t n = std::min(width, s.size() - i);
    if (i + n < s.size()) {
      const size_t sp = s.rfind(' ', i + n);
      if (sp != std::string::npos && sp > i) n = sp - i;
    }
    out.push_back(trim(s.substr(i, n)));
    i += n;
    while (i < s.size() && s[i] == ' ') ++i;
  }
  return out;
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
  const ProbePoint* point = plan_.findPoint(id);
  if (!point)
    fail(file_, line,
         fmt::format("point {} is not in the plan ({} cycle, {} points)", id, plan_.cycle, plan_.points.size()));
  const auto it = seen_line_.find(id);
  if (it != seen_line_.end())
    fail(file_, line, fmt::format("point {} appears twice (first at line {})", id, it->second));
  // The clock of simulate --start-s and of the controllers: 0 to kMaxClockSeconds (NaN: unknown).
  if (!std::isnan(t_s) && !(t_s >= 0.0 && t_s <= kMaxClockSeconds))
    fail(file_, line, fmt::format("time {:g} s of point {} is outside the clock's range 0 to {:g} s", t_s, id,
                                  kMaxClockSeconds));
  requireOnProbingMove(plan_, *point, p, file_, line);
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

std::string implausibility(Kinematics kinematics, int index, double v) {
  const auto& p = locationParameters(kinematics).at(static_cast<size_t>(index));
  if (!std::isfinite(v)) return fmt::format("{} is not a finite number; nothing written", p.name);
  if (p.kind == ParamKind::Length && std::abs(v) > kMaxLengthCorrectionMm)
    return fmt::format("{} = {:.4f} mm exceeds the plausibility limit of {} mm: check the setup and the results, or "
                       "force it",
                       p.name, v, kMaxLengthCorrectionMm);
  if (p.kind == ParamKind::Angle && std::abs(radToMdeg(v)) > kMaxAngleCorrectionMdeg)
    return fmt::format("{} = {:.1f} mdeg exceeds the plausibility limit of {} mdeg: check the setup and the results, "
                       "or force it",
                       p.name, radToMdeg(v), kMaxAngleCorrectionMdeg);
  return "";
}

void requirePlausible(const OffsetRequest& r) {
  if (!r.plan) throw std::invalid_argument("offset request without a plan");
  if (r.identified.kinematics != r.plan->machine.kinematics)
    throw std::invalid_argument("identified errors are for another kinematics than the plan's machine");
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double v = r.identified.values[i];
    if (r.force && std::isfinite(v)) continue;
    const std::string why = implausibility(r.identified.kinematics, i, v);
    if (!why.empty()) throw std::invalid_argument(why);
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


namespace {
// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil).
long long daysFromCivil(long long y, unsigned m, unsigned d) {
  y -= m <= 2;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long long>(doe) - 719468;
}
void civilFromDays(long long z, long long& y, unsigned& m, unsigned& d) {
  z += 719468;
  const long long era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  y = static_cast<long long>(yoe) + era * 400;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y += m <= 2;
}
const long long kEpochDays = daysFromCivil(kClockEpochYear, 1, 1);
}  // namespace

std::optional<double> clockSeconds(long yyyymmdd, long hhmmss) {
  const long y = yyyymmdd / 10000, mo = yyyymmdd / 100 % 100, d = yyyymmdd % 100;
  const long h = hhmmss / 10000, mi = hhmmss / 100 % 100, s = hhmmss % 100;
  if (yyyymmdd < 0 || hhmmss < 0 || y < 1900 || y > 9999 || mo < 1 || mo > 12 || d < 1 || h > 23 || mi > 59 || s > 59)
    return std::nullopt;
  static const int kDays[] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  if (d > kDays[mo - 1] || (mo == 2 && d == 29 && !leap)) return std::nullopt;
  const long long days = daysFromCivil(y, static_cast<unsigned>(mo), static_cast<unsigned>(d)) - kEpochDays;
  return static_cast<double>(days * 86400 + h * 3600 + mi * 60 + s);
}

ClockStamp clockStamp(double seconds) {
  if (!std::isfinite(seconds)) throw std::invalid_argument("a time stamp must be a finite number of seconds");
  // Years 1900..9999 lie within +-2.6e11 s of the epoch: refuse anything beyond before the cast
  // to an integer (1e300 s does not fit one) and the day arithmetic (which would overflow).
  if (std::abs(seconds) > 4e11)
    throw std::invalid_argument(fmt::format("time stamp {:g} s is outside the years 1900-9999", seconds));
  const long long s = static_cast<long long>(std::floor(seconds));
  const long long day = (s >= 0 ? s / 86400 : -((-s + 86399) / 86400));
  const long long sod = s - day * 86400;
  long long y = 0;
  unsigned m = 0, d = 0;
  civilFromDays(day + kEpochDays, y, m, d);
  if (y < 1900 || y > 9999) throw std::invalid_argument(fmt::format("time stamp {} s is outside the years 1900-9999", seconds));
  return {static_cast<long>(y * 10000 + m * 100 + d), static_cast<long>(sod / 3600 * 10000 + sod / 60 % 60 * 100 + sod % 60)};
}

LetteredLine letteredFields(const std::string& s, std::string_view letters, const std::string& file, int line) {
  size_t i = 0;
  auto skip = [&]() {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  };
  std::string expected = "P<id>";
  for (char c : letters) expected += fmt::format(" {}..", c);
  skip();
  if (i >= s.size() || s[i] != 'P') fail(file, line, fmt::format("expected '{}', got '{}'", expected, trim(s)));
  ++i;
  skip();
  const size_t id_begin = i;
  while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
  const auto id = parseDigits(std::string_view(s).substr(id_begin, i - id_begin));
  if (!id || *id == 0 || (i < s.size() && s[i] != ' ' && s[i] != '\t' && letters.find(s[i]) != 0))
    fail(file, line, fmt::format("'{}' does not start with a point id P<n>", trim(s)));
  LetteredLine out;
  out.id = *id;
  for (size_t n = 0; n < letters.size(); ++n) {
    skip();
    if (i >= s.size() || s[i] != letters[n])
      fail(file, line, fmt::format("point {}: expected '{}' at column {} ('{}')", *id, letters[n], i + 1, expected));
    ++i;
    skip();
    const size_t b = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t' && (n + 1 == letters.size() || s[i] != letters[n + 1])) ++i;
    out.fields.push_back(s.substr(b, i - b));
  }
  skip();
  if (i != s.size())
    fail(file, line, fmt::format("point {}: unexpected text '{}' after {}", *id, s.substr(i), letters.back()));
  return out;
}

std::optional<double> parseNumberComma(std::string_view token) {
  std::string t(token);
  if (std::count(t.begin(), t.end(), ',') + std::count(t.begin(), t.end(), '.') > 1) return std::nullopt;
  for (auto& c : t)
    if (c == ',') c = '.';
  return parseNumber(t);
}

std::vector<nc::Block> motionBlocks(const std::vector<MotionEndpoint>& endpoints, bool inch) {
  std::vector<nc::Block> blocks;
  nc::Block unit;
  unit.line = 0;
  unit.code = inch ? "G20" : "G21";
  unit.words.push_back({'G', inch ? "20" : "21", false, inch ? 20.0 : 21.0});
  blocks.push_back(unit);
  for (const auto& e : endpoints) {
    nc::Block b;
    b.line = e.line;
    b.code = "motion";
    for (const auto& [axis, v] : e.axes) b.words.push_back({axis, fixed(v, 6), true, v});
    blocks.push_back(std::move(b));
  }
  return blocks;
}

std::optional<AxisDirection> axisAligned(const Eigen::Vector3d& d) {
  const double n = d.norm();
  if (!(n > 0)) return std::nullopt;
  const Eigen::Vector3d u = d / n;
  for (int a = 0; a < 3; ++a)
    if (std::abs(std::abs(u[a]) - 1.0) < 1e-9) return AxisDirection{a, u[a] > 0 ? 1 : -1};
  return std::nullopt;
}

ResultLines::ResultLines(const std::string& text, std::string file, std::string header_token,
                         std::string expected_header, std::string second_header_why, std::string skip)
    : lines_(splitLines(text)),
      file_(std::move(file)),
      header_token_(std::move(header_token)),
      expected_header_(std::move(expected_header)),
      second_header_why_(std::move(second_header_why)),
      skip_(std::move(skip)) {}

bool ResultLines::next() {
  for (; at_ < lines_.size(); ++at_) {
    s = trim(lines_[at_].text);
    if (s.empty() || (!skip_.empty() && s == skip_)) continue;
    number = last_ = lines_[at_++].number;
    if (end_line_) fail(file_, number, fmt::format("text after END (line {}): '{}'", end_line_, s));
    t = tokens(s);
    if (isHeader()) {
      if (header_) fail(file_, number, "a second header line: one run per results file" + second_header_why_);
      header_ = true;
    } else if (!header_) {
      fail(file_, number, fmt::format("expected the header '{}', got '{}'", expected_header_, s));
    }
    return true;
  }
  return false;
}

bool ResultLines::isEnd() {
  if (s != "END") return false;
  end_line_ = number;
  return true;
}

void ResultLines::refuseNotTriggered() const {
  if (t.empty() || t[0] != "NOT-TRIGGERED") return;
  const std::string id_text = trim(s.substr(std::string("NOT-TRIGGERED").size()));
  const auto id = id_text.size() > 1 && id_text[0] == 'P' ? parseDigits(trim(id_text.substr(1))) : std::nullopt;
  if (!id) fail(file_, number, fmt::format("expected 'NOT-TRIGGERED P<id>', got '{}'", s));
  fail(file_, number, fmt::format("point {} was not triggered: the program stopped there", *id));
}

void ResultLines::finish(const PointCollector& points, std::string_view stopped_why) const {
  if (!header_) fail(file_, 1, fmt::format("empty results file: expected the header '{}'", expected_header_));
  if (end_line_) return;
  if (const int missing = points.firstMissing())
    fail(file_, last_, fmt::format("point {} is missing and there is no END line: the program stopped early{}", missing,
                                   stopped_why));
  fail(file_, last_, "no END line after the last point: the file is incomplete");
}

double taggedHeaderMmPerUnit(const std::string& s, const std::string& file, int line, const ProbePlan& plan,
                             std::string_view tag, std::string_view cycle_token) {
  const auto t = tokens(s);
  if (t.size() != 9 || t[1] != "DIALECT" || t[3] != "CYCLE" || t[5] != "POINTS" || t[7] != "UNIT")
    fail(file, line,
         fmt::format("expected the header 'ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT MM|INCH', got '{}'", tag,
                     cycle_token, plan.points.size(), s));
  if (t[2] != tag) fail(file, line, fmt::format("results of dialect '{}', expected {}", t[2], tag));
  if (t[4] != cycle_token) fail(file, line, fmt::format("results of cycle '{}', the plan is '{}'", t[4], cycle_token));
  const auto n = parseDigits(t[6]);
  if (!n) fail(file, line, fmt::format("POINTS '{}' is not a number", t[6]));
  if (static_cast<size_t>(*n) != plan.points.size())
    fail(file, line, fmt::format("header says POINTS {} but the plan has {} points", *n, plan.points.size()));
  if (t[8] == "MM") return 1.0;
  if (t[8] == "INCH") return kMmPerInch;
  fail(file, line, fmt::format("UNIT '{}' must be MM or INCH", t[8]));
}

MeasurementRun parseTaggedResults(const std::string& text, const std::string& file, const ProbePlan& plan,
                                  std::string_view tag, std::string_view cycle_token,
                                  std::string_view second_header_why) {
  requireText(text, file);
  ResultLines in(text, file, "ROTACAL-RESULTS",
                 fmt::format("ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT MM|INCH", tag, cycle_token,
                             plan.points.size()),
                 std::string(second_header_why));
  PointCollector points(plan, file);
  double k = 1.0;
  while (in.next()) {
    if (in.isHeader()) {
      k = taggedHeaderMmPerUnit(in.s, file, in.number, plan, tag, cycle_token);
      continue;
    }
    if (in.isEnd()) continue;
    in.refuseNotTriggered();
    const auto f = letteredFields(in.s, "XYZ", file, in.number);
    Eigen::Vector3d x;
    for (int i = 0; i < 3; ++i) {
      const auto v = parseNumber(f.fields[static_cast<size_t>(i)]);
      if (!v)
        fail(file, in.number,
             fmt::format("{} '{}' of point {} is not a number", "XYZ"[i], f.fields[static_cast<size_t>(i)], f.id));
      x[i] = *v * k;
    }
    points.add(in.number, static_cast<int>(f.id), x, std::numeric_limits<double>::quiet_NaN());
  }
  in.finish(points);
  return points.finish(in.last());
}

std::string trimmed(double v, int decimals) {
  std::string s = fixed(v, decimals);
  if (s.find('.') != std::string::npos)
    while (!s.empty() && s.back() == '0') s.pop_back();
  if (s == "-0." || s == "-.") s = "0.";
  return s;
}

std::string rotaryLinearWords(const nc::Op& op, nc::Unit unit, const std::string& sep) {
  const int dec = nc::rotaryLinearDecimals(unit);
  std::string s;
  for (char axis : op.axes) {
    if (axis < 'X' || axis > 'Z') throw std::invalid_argument(std::string("rotary-linear move: bad linear axis ") + axis);
    if (!s.empty()) s += sep;
    s += axis + fixed(op.xyz[axis - 'X'], dec);
  }
  for (const auto& [axis, deg] : op.rotary) {
    if (!s.empty()) s += sep;
    s += axis + trimmed(deg, 4);
  }
  if (op.feed > 0) s += sep + "F" + trimmed(op.feed, 4);
  return s;
}

std::string rapidBlock(std::string_view g, const nc::Op& op, int decimals) {
  const Eigen::Vector3d& x = op.xyz;
  if (op.z_only) return fmt::format("{} Z{}", g, fixed(x.z(), decimals));
  return fmt::format("{} X{} Y{} Z{}", g, fixed(x.x(), decimals), fixed(x.y(), decimals), fixed(x.z(), decimals));
}

std::string linearBlock(std::string_view g, const nc::Op& op, int decimals, bool inch) {
  const Eigen::Vector3d& x = op.xyz;
  return fmt::format("{} X{} Y{} Z{} F{}", g, fixed(x.x(), decimals), fixed(x.y(), decimals), fixed(x.z(), decimals),
                     fixed(op.feed, inch ? 3 : 1));
}

void requireRapidIndex(const nc::Op& op, std::string_view dialect) {
  if (op.feed > 0)
    throw std::invalid_argument(fmt::format("the {} program indexes at rapid only; a rotary move at a feed (R-test "
                                            "reciprocation) is written for linuxcnc only",
                                            dialect));
}

std::string inverseTimeRefusal(std::string_view dialect) {
  const Dialect* d = findDialect(dialect);
  if (!d || d->inverseTimeRefusal().empty()) return "";
  std::vector<std::string> writing;
  for (const Dialect* o : dialects())
    if (o->hasPrograms() && o->inverseTimeRefusal().empty()) writing.emplace_back(o->name());
  std::string use;
  for (size_t i = 0; i < writing.size(); ++i)
    use += (i == 0 ? "" : i + 1 == writing.size() ? " or " : ", ") + writing[i];
  return fmt::format("{}: {}, so a program that moves under inverse time is refused for this dialect; use {}", dialect,
                     d->inverseTimeRefusal(), use);
}

void requireInverseTimeAllowed(const nc::Program& program, std::string_view dialect) {
  const std::string why = inverseTimeRefusal(dialect);
  if (why.empty()) return;
  for (const auto& op : program.ops)
    if (op.kind == nc::Op::Kind::Mode && op.inverse_time) throw std::invalid_argument(why);
}

void ModeGuard::apply(const nc::Op& op) {
  switch (op.kind) {
    case nc::Op::Kind::Mode: inverse_time_ = op.inverse_time; break;
    case nc::Op::Kind::Probe:
      if (inverse_time_) throw std::invalid_argument("a probing move under inverse-time feed (G93): switch to G94 first");
      break;
    case nc::Op::Kind::RotaryLinear:
      if (inverse_time_ && !(op.feed > 0))
        throw std::invalid_argument("an inverse-time (G93) move needs its own F word on every block");
      break;
    case nc::Op::Kind::Linear:
      if (inverse_time_) throw std::invalid_argument("a per-minute linear move under inverse-time feed (G93)");
      break;
    case nc::Op::Kind::Comment:
    case nc::Op::Kind::Rapid:
    case nc::Op::Kind::Index:
    case nc::Op::Kind::Pause:
    case nc::Op::Kind::Dwell:
    case nc::Op::Kind::Read:
    case nc::Op::Kind::RepeatBegin:
    case nc::Op::Kind::RepeatEnd: break;
  }
}

int programNumber(const nc::Program& program) {
  // Fanuc and Okuma take O1-O9999; Haas writes the same number in five digits.
  if (program.number < 1 || program.number > 9999)
    throw std::invalid_argument(fmt::format("program '{}' has no program number from 1 to 9999 (got {})", program.name,
                                            program.number));
  return program.number;
}

bool isProbingBlock(const nc::Block& b) {
  return b.hasWord('G', 31) || b.hasWord('G', 38.2) || b.hasWord('G', 38.3) || b.hasWord('G', 38.4) ||
         b.hasWord('G', 38.5) || ctl::upper(b.code).find("MEAS") != std::string::npos;
}

std::optional<EndPointCheck> endPointCheck(std::string_view dialect) {
  const Dialect* d = findDialect(dialect);
  if (!d) return std::nullopt;
  return d->endPointCheck();
}

std::string endPointCheckStatement(const EndPointCheck& form, int axis, double end, int decimals) {
  const auto a = static_cast<size_t>(axis);
  return fmt::format("{}={}{}{}", form.difference.at(a), form.measured[a], end < 0 ? "+" : "-",
                     fixed(std::abs(end), decimals));
}

std::optional<EndPointCheckStatement> parseEndPointCheckStatement(const EndPointCheck& form, std::string_view code) {
  size_t i = 0;
  auto blanks = [&] {
    while (i < code.size() && (code[i] == ' ' || code[i] == '\t')) ++i;
  };
  auto word = [&](std::string_view w) {
    if (upper(code.substr(i, w.size())) != upper(w)) return false;
    i += w.size();
    return true;
  };
  blanks();
  if (i < code.size() && (code[i] == 'N' || code[i] == 'n') && i + 1 < code.size() && std::isdigit(static_cast<unsigned char>(code[i + 1]))) {
    ++i;
    while (i < code.size() && std::isdigit(static_cast<unsigned char>(code[i]))) ++i;
    blanks();
  }
  const size_t start = i;
  for (int a = 0; a < 3; ++a) {
    i = start;
    const auto k = static_cast<size_t>(a);
    if (!word(form.difference[k])) continue;
    blanks();
    if (!word("=")) continue;
    blanks();
    if (!word(form.measured[k])) continue;
    // The next character must end the variable's name: "#50610" is another variable.
    if (i < code.size() && std::isalnum(static_cast<unsigned char>(code[i]))) continue;
    blanks();
    if (i >= code.size() || (code[i] != '+' && code[i] != '-')) continue;
    const bool plus = code[i++] == '+';
    blanks();
    const std::string number = trim(code.substr(i));
    if (number.empty() || number[0] == '+' || number[0] == '-' || number.find_first_of("eE") != std::string::npos)
      continue;
    const auto v = parseNumber(number);
    if (!v) continue;
    const size_t point = number.find('.');
    const int decimals = point == std::string::npos ? 0 : static_cast<int>(number.size() - point - 1);
    return EndPointCheckStatement{a, plus ? -*v : *v, decimals};
  }
  return std::nullopt;
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

}  // namespace rotacal::ctl

namespace rotacal::ctl {

int probeCount(const nc::Program& p) {
  int probes = 0;
  for (const auto& op : p.ops) probes += op.kind == nc::Op::Kind::Probe;
  if (p.point_count != 0 && p.point_count != probes)
    throw std::invalid_argument(fmt::format("program has {} probing moves but point_count {}", probes, p.point_count));
  return probes;
}

void appendLine(std::string& out, const std::string& s, size_t max_chars) {
  if (s.size() > max_chars) throw std::invalid_argument(fmt::format("line longer than {} characters: {}", max_chars, s));
  out += s;
  out += '\n';
}

void refuseRtestOps(std::string_view dialect) {
  throw std::invalid_argument(fmt::format("the {} program cannot express an R-test dwell, logger trigger or loop "
                                          "in this version: generate this program for linuxcnc",
                                          dialect));
}

void writeOps(const nc::Program& p, const WordAddressMoves& moves, LineWriter& w,
              const std::function<void(const nc::Op&)>& own, const std::function<void()>& before_index) {
  const bool inch = p.unit == nc::Unit::Inch;
  ModeGuard guard;
  for (const auto& op : p.ops) {
    guard.apply(op);
    switch (op.kind) {
      case nc::Op::Kind::Rapid: w.line(rapidBlock(moves.rapid, op, moves.decimals)); break;
      case nc::Op::Kind::Linear: w.line(linearBlock(moves.feed, op, moves.decimals, inch)); break;
      case nc::Op::Kind::Index: {
        requireRapidIndex(op, moves.dialect);
        std::string s(moves.rapid);
        for (const auto& [axis, deg] : op.rotary) s += fmt::format(" {}{}", axis, fixed(deg, moves.decimals));
        if (before_index) before_index();
        w.line(s);
        break;
      }
      case nc::Op::Kind::RotaryLinear: w.line(rotaryLinearWords(op, p.unit, moves.rotary_linear_sep)); break;
      case nc::Op::Kind::Dwell:
      case nc::Op::Kind::Read:
      case nc::Op::Kind::RepeatBegin:
      case nc::Op::Kind::RepeatEnd: refuseRtestOps(moves.dialect);
      case nc::Op::Kind::Comment:
      case nc::Op::Kind::Mode:
      case nc::Op::Kind::Pause:
      case nc::Op::Kind::Probe: own(op); break;
    }
  }
}

std::string isoModeBlock(const nc::Op& op) {
  if (op.inverse_time && op.feed > 0)
    return fmt::format("{} G01 G93 F{}", op.incremental ? "G91" : "G90", trimmed(op.feed, 4));
  return fmt::format("{} {}", op.incremental ? "G91" : "G90", op.inverse_time ? "G93" : "G94");
}

void requireSingleTouch(const nc::Op& op, std::string_view dialect) {
  const int id = op.point_id;
  if (!(op.feed > 0)) throw std::invalid_argument(fmt::format("point {}: probing feed must be > 0", id));
  if (op.retract_mm > 0)
    throw std::invalid_argument(fmt::format(
        "point {}: the {} program records a single touch; a double touch (retract_mm > 0) is not implemented", id,
        dialect));
}

namespace {
// The A/B table's offsets have one verified form, LinuxCNC's xyzab_tdr_kins pins; the other
// controls' forms below are written for a tilt axis carrying a C table.
const OffsetRequest& requireTiltAndC(const OffsetRequest& r) {
  if (r.identified.kinematics == Kinematics::TableAB)
    throw std::invalid_argument(
        "a table_ab machine's location errors go into its control's kinematics, and rotacal knows that form only for "
        "LinuxCNC's xyzab_tdr_kins (--dialect linuxcnc, a .hal file); here use rotacal compensate (the program "
        "rewritten for all eight) or enter REPORT.json's values by hand");
  return r;
}
}  // namespace

OffsetBasis::OffsetBasis(const OffsetRequest& r)
    : plan((requirePlausible(requireTiltAndC(r)), *r.plan)),
      machine(plan.machine),
      e(r.identified),
      ac(e.kinematics == Kinematics::TableAC),
      inch(machine.units == LengthUnit::Inch),
      k(inch ? 1.0 / kMmPerInch : 1.0),
      tilt(ac ? 'A' : 'B') {}

Eigen::Vector3d OffsetBasis::pivot() const {
  return ac ? Eigen::Vector3d(e.get("dx_AY"), e.get("dy_AY"), e.get("dz_AY"))
            : Eigen::Vector3d(e.get("dx_BY"), e.get("dy_CB"), e.get("dz_BY"));
}

Eigen::Vector3d OffsetBasis::second() const {
  return ac ? Eigen::Vector3d(0, e.get("dy_CA"), 0) : Eigen::Vector3d(e.get("dx_CB"), 0, 0);
}

double OffsetBasis::zeroDeg(std::string_view dialect) const {
  return (machine.hasRotary(tilt) ? machine.controllerSign(tilt, std::string(dialect)) : 1) *
         radToDeg(e.get(ac ? "a_AY" : "b_BY"));
}

std::string TaggedResultsDialect::writeResults(const ProbePlan& plan, const MeasurementRun& run) const {
  const bool inch = plan.machine.units == LengthUnit::Inch;
  const double k = inch ? 1.0 / kMmPerInch : 1.0;
  const std::string eol(form_.eol);
  std::string out = fmt::format("ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT {}{}", form_.tag,
                                form_.cycle_token(plan.cycle), plan.points.size(), inch ? "INCH" : "MM", eol);
  auto field = [&](double v) {
    std::string s = fixed(v, resultDecimals(inch));
    if (s.size() < static_cast<size_t>(form_.width)) s.insert(0, form_.width - s.size(), ' ');
    return s;
  };
  for (const auto& t : run.points) {
    if (!plan.findPoint(t.point_id)) throw std::invalid_argument(fmt::format("run point {} is not in the plan", t.point_id));
    const Eigen::Vector3d x = t.position_m_mm * k;
    out += fmt::format("P{} X{} Y{} Z{}{}", t.point_id, field(x.x()), field(x.y()), field(x.z()), eol);
  }
  return out + "END" + eol;
}

MeasurementRun TaggedResultsDialect::parseResults(const std::string& text, const std::string& file,
                                                  const ProbePlan& plan) const {
  return parseTaggedResults(text, file, plan, form_.tag, form_.cycle_token(plan.cycle), form_.second_header_why);
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
