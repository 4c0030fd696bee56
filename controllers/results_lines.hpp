#pragma once
// How every line-based results reader walks a results file: the lines with the rules they share
// (header first and once, nothing after END, a NOT-TRIGGERED line named), a point's lettered
// fields "P<id> X.. Y.. Z..", and the points collected against the plan (each id of the plan,
// once, all present). Every error is an InputError naming FILE:LINE.
#include <Eigen/Core>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "controllers/text.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal::ctl {

/// Throws rotacal::InputError(file, line, what).
[[noreturn]] void fail(const std::string& file, int line, const std::string& what);

/// Collects the points of one results file and enforces: ids in the plan, each once, all
/// present. Errors are rotacal::InputError(file, line, message).
class PointCollector {
 public:
  PointCollector(const ProbePlan& plan, std::string file);
  /// Records point `id` read at `line`. Throws on an id not in the plan or a repeated id.
  void add(int line, int id, const Eigen::Vector3d& position_m_mm, double t_s);
  /// Throws naming the first plan point not seen (at `last_line`), else returns the run in
  /// file order.
  MeasurementRun finish(int last_line) const;
  /// First plan point not seen yet, or 0.
  int firstMissing() const;
  size_t size() const { return run_.points.size(); }

 private:
  const ProbePlan& plan_;
  std::string file_;
  MeasurementRun run_;
  std::map<int, int> seen_line_;  // id -> line
};

/// The text after each letter of `letters` in a line "P<id> X.. Y.. Z.. ...": the line starts
/// with 'P' and the id digits, then each letter of `letters` in order, each followed by its
/// field (spaces between a letter and its field, and between fields, are allowed; a field ends
/// at the next space after its first character or at the next expected letter). Throws
/// InputError(file, line, ...) naming what is wrong. Returns the id and the field texts.
struct LetteredLine {
  long id = 0;
  std::vector<std::string> fields;
};
LetteredLine letteredFields(const std::string& s, std::string_view letters, const std::string& file, int line);

/// The lines of a results file as every line-based reader takes them (tagged, Macro B,
/// Heidenhain): trimmed, blank lines and `skip` lines passed over, with the rules they share: the
/// header first and once, nothing after the END line, a NOT-TRIGGERED line where the program
/// stopped, and at the end an empty file or a missing END named. Errors are InputError(file, line).
class ResultLines {
 public:
  ResultLines(const std::string& text, std::string file, std::string header_token, std::string expected_header,
              std::string second_header_why, std::string skip = "");
  /// Moves to the next line (number, s, t); false after the last. Throws at text after END, at a
  /// line before the header and at a second header.
  bool next();
  /// This line is the header (its checks are the reader's).
  bool isHeader() const { return !t.empty() && t[0] == header_token_; }
  /// This line is "END": marks it, and anything after it is refused.
  bool isEnd();
  /// Throws at a "NOT-TRIGGERED P<id>" line, naming the point where the program stopped.
  void refuseNotTriggered() const;
  /// After the last line: throws for an empty file, or a file without END (naming the first plan
  /// point not read, and `stopped_why` after "the program stopped early").
  void finish(const PointCollector& points, std::string_view stopped_why = "") const;
  int last() const { return last_; }

  int number = 0;
  std::string s;
  std::vector<std::string> t;

 private:
  std::vector<TextLine> lines_;
  size_t at_ = 0;
  std::string file_, header_token_, expected_header_, second_header_why_, skip_;
  bool header_ = false;
  int end_line_ = 0;
  int last_ = 1;
};

}  // namespace rotacal::ctl
