#pragma once
// One place per controller dialect: how a probing program is spelled, what the controller
// writes back and how to read it, how compensation is written in the controller's own form,
// and a strict checker for generated programs. core/ never sees any of this.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
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
  std::vector<ParameterEstimate> parameters;  // a head machine's own, by ISO name (identified unused)
  std::string report_file;                  // provenance, for the file's header
  std::string previous_text;                // the existing offsets file, if any ("" = none)
  bool force = false;                       // allow corrections beyond the plausibility limit
  std::string path;                         // the output file: a dialect may pick its form by extension
};

namespace ctl {
struct CompTableRequest;
class PeriodicInterpolant;
struct CompTable;
}  // namespace ctl

/// The language a dialect's programs are written in: which reader follows a program back
/// (controllers/motion_reader.hpp) and whether `compensate` can rewrite one.
enum class ProgramLanguage {
  None,       // no NC programs: the neutral results and offsets only
  IsoGcode,   // word-address G-code, comments in parentheses, G20/G21 for the unit
  Sinumerik,  // word-address G-code with MEAS= probing, G70/G700 for inch, comments after ';'
  Klartext,   // Heidenhain conversational: not word-address, never rewritten
};

/// Word-address G-code, the language `compensate` rewrites and the word-address reader follows.
constexpr bool isWordAddress(ProgramLanguage l) { return l == ProgramLanguage::IsoGcode || l == ProgramLanguage::Sinumerik; }

/// The variables of a no-trigger check written as an end-point comparison after each probing
/// move (the probe's stop minus the programmed end, per axis, then a test on the differences).
struct EndPointCheck {
  std::array<std::string, 3> difference;  // variables holding stop - end, X Y Z
  std::array<std::string, 3> measured;    // variables holding the probe's stop, X Y Z
};

/// What a dialect is, as data: what the code outside the dialect asks of it (the verifier, the
/// program rewriter, the compensation tables, the command line) reads it here, never its name.
struct DialectIdentity {
  ProgramLanguage language = ProgramLanguage::IsoGcode;
  /// Whether its programs carry a program number (O word): the control stores them by number.
  bool numbers_programs = false;
  /// The no-trigger check's variables; nullopt where the probing move raises the error itself
  /// (G38.2), where the check is written otherwise (Klartext's cycle 0) or there is no program.
  std::optional<EndPointCheck> end_point_check;
  /// Whether G28 / G30 of Z alone through the current position (G91 Z0) and G53 of Z alone reach
  /// the Z reference at the top of the Z stroke, machine coordinates counted from it (Fanuc's
  /// reference position with parameter 1240 = 0, Haas' machine zero): a retract the verifier can
  /// follow. False where the reference is a stored position (LinuxCNC's G28 reads parameters
  /// 5161-5169) or the language has no such word.
  bool z_reference_at_stroke_top = false;
  /// Why a program moving under inverse-time feed (G93) is refused; empty where it is written.
  std::string_view inverse_time_refusal;
  /// Why `compensate` does not rewrite its programs, when they are not word-address G-code.
  std::string_view rewrite_refusal;
  /// The rotary compensation table in the dialect's form; nullptr where there is none.
  ctl::CompTable (*comp_table)(const ctl::CompTableRequest& request, const ctl::PeriodicInterpolant& error_mdeg,
                               double step_deg) = nullptr;
  /// Why there is no compensation table (comp_table == nullptr), and what to do instead.
  std::string_view comp_table_refusal;
};

class Dialect {
 public:
  explicit Dialect(DialectIdentity identity) : identity_(std::move(identity)) {}
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

  ProgramLanguage language() const { return identity_.language; }
  bool hasPrograms() const { return identity_.language != ProgramLanguage::None; }
  bool numbersPrograms() const { return identity_.numbers_programs; }
  const std::optional<EndPointCheck>& endPointCheck() const { return identity_.end_point_check; }
  std::string_view inverseTimeRefusal() const { return identity_.inverse_time_refusal; }
  std::string_view rewriteRefusal() const { return identity_.rewrite_refusal; }
  bool hasCompTable() const { return identity_.comp_table != nullptr; }
  const DialectIdentity& identity() const { return identity_; }

 private:
  DialectIdentity identity_;
};

/// The dialect by name. Throws std::invalid_argument listing the names for others.
const Dialect& dialectByName(std::string_view name);
/// The same, nullptr for a name no dialect has.
const Dialect* findDialect(std::string_view name);
/// Every dialect, in the registry's order, and their names.
const std::vector<const Dialect*>& dialects();
std::vector<std::string> dialectNames();

}  // namespace rotacal
