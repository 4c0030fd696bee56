#pragma once
// One place per controller dialect: how a probing program is spelled, what the controller
// writes back and how to read it, how compensation is written in the controller's own form,
// and a strict checker for generated programs. core/ never sees any of this.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/error_model.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "gcode/program.hpp"

namespace rotacal {

/// Corrections to write back (000 Sec. 4.5: the ones applied by shifting).
struct OffsetRequest {
  const ProbePlan* plan = nullptr;          // machine, units, controller signs
  LocationErrors identified;                // mm / rad, papers' convention
  ErrorVector u = ErrorVector::Zero();      // standard uncertainties, mm / rad
  std::string report_file;                  // provenance, for the file's header
  std::string previous_text;                // the existing offsets file, if any ("" = none)
  bool force = false;                       // allow corrections beyond the plausibility limit
  std::string path;                         // the output file: a dialect may pick its form by extension
};

class Dialect {
 public:
  virtual ~Dialect() = default;
  virtual std::string_view name() const = 0;
  virtual std::string_view programExtension() const = 0;  // ".ngc", ".nc", ...
  virtual std::string_view resultsExtension() const = 0;  // ".txt", ".csv", ...

  /// The program text. Throws std::invalid_argument when the program cannot be expressed.
  virtual std::string writeProgram(const nc::Program& program) const = 0;

  /// What the program of `plan` writes when the controller records `run` (used by simulate).
  virtual std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const = 0;

  /// Reads what the program writes. Throws InputError("FILE:LINE: what is wrong") on anything
  /// else: missing, extra or repeated points, wrong counts, non-numbers, untriggered points.
  /// Positions come back in the papers' machine frame, mm.
  virtual MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const = 0;

  /// The offsets file. Throws std::invalid_argument when a correction exceeds the plausibility
  /// limit and !request.force.
  virtual std::string writeOffsets(const OffsetRequest& request) const = 0;

  /// `text` as comment lines of this dialect's programs. Outside text (a report's path, a
  /// machine's name) goes through here: only the dialect's safe characters survive, so no line
  /// end, comment delimiter or nested parenthesis reaches the control, and the lines obey the
  /// dialect's checker (upper case, line length). Heidenhain lines come without their block
  /// number. Throws std::invalid_argument for a dialect without programs (csv).
  virtual std::vector<std::string> commentLines(std::string_view text) const = 0;

  /// Strict checks of a program's text against the dialect's rules, the plan and what the
  /// neutral program it was written from shows (nc::shapeOf: its probing moves, readings,
  /// inverse-time feed, number); returns "LINE: problem" strings, empty when clean.
  virtual std::vector<std::string> check(const std::string& program_text, const ProbePlan& plan,
                                         const nc::Shape& shape) const = 0;

  /// A statement the control executes without effect on the machine, which `compensate` writes
  /// into every program it rewrites and refuses to find in its input: evidence of a compensated
  /// program that survives stripping its comments. Empty where the dialect has no such statement
  /// (every variable there is shared with the machine's own macros): the comment mark is then
  /// the only evidence, and a program stripped of it cannot be told from an original.
  virtual std::string compensationMark() const { return {}; }
};

/// The dialect by name: csv, linuxcnc, fanuc. Throws std::invalid_argument for others.
const Dialect& dialectByName(std::string_view name);
std::vector<std::string> dialectNames();

}  // namespace rotacal
