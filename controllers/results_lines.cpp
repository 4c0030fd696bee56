#include "controllers/results_lines.hpp"

#include <fmt/format.h>

#include <cmath>

#include "controllers/result_checks.hpp"
#include "core/errors.hpp"
#include "core/limits.hpp"

namespace rotacal::ctl {

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

}  // namespace rotacal::ctl
