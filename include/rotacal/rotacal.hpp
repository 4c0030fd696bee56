#pragma once
// rotacal's public library (librotacal.so, docs/library.md): what a CAM post-processor needs to
// cancel the location errors that `rotacal analyze` identified, on texts it already has.
//   compensate()  an NC program rewritten for one or several REPORT.json, as `rotacal compensate`
//                 writes it (the same text), both programs through the verifier;
//   check()       the program verifier of `rotacal check` (without a plan);
//   Compensator   the errors of the reports, to compensate single poses the post computes.
// Only standard-library types cross this interface, so a post does not depend on the libraries
// rotacal is built with. Every failure is a rotacal::Error.
#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "rotacal/export.hpp"
#include "rotacal/version.hpp"

namespace rotacal {

/// Bad input (a program, a report, a machine, a dialect, an option), a program that cannot be
/// compensated exactly, or one that fails the verifier. what() is one line: "NAME:LINE: why" when
/// the failure has a place in an input (NAME as the request names that input), else "why".
class ROTACAL_API Error : public std::runtime_error {
 public:
  Error(const std::string& input, int line, const std::string& why);
  ~Error() override;
  /// The name of the input at fault ("" when none), and its 1-based line (0 when none).
  const std::string& input() const noexcept { return input_; }
  int line() const noexcept { return line_; }

 private:
  std::string input_;
  int line_;
};

/// A text and the name messages give it (a file name, usually).
struct NamedText {
  std::string name;
  std::string text;
};

struct CompensateRequest {
  NamedText program;               // machine coordinates, no tool-centre-point control
  std::vector<NamedText> reports;  // REPORT.json of analyze; several combine (location errors from one, component errors from another)
  std::string dialect;             // linuxcnc | fanuc | haas | siemens | okuma
  std::optional<NamedText> machine;  // MACHINE.json; default: the machine the first report carries
  /// Machine position (mm) of the program zero relative to the rotary-axis intersection.
  std::array<double, 3> program_origin_mm{0.0, 0.0, 0.0};
  /// A feed move that turns a rotary axis is split where it would leave the nominal path by more (um, 0.001 to 1000).
  double max_deviation_um = 0.2;
  /// Compensate location errors beyond the plausibility limit of a correction (0.5 mm, 100 mdeg).
  bool force = false;
  /// How the messages and the verifier name the rewritten program.
  std::string output_name = "compensated program";
  /// Component errors a controller table holds (e.g. "ECC"): left out, so each is compensated once.
  std::vector<std::string> table_holds;
  /// Now (s since 1970, UTC): a report analyzed more than 30 days before is noted; unset, not judged.
  std::optional<double> now_unix_s;
};

struct CompensateResult {
  std::string text;  // the rewritten program
  int motion_blocks = 0;
  int compensated_blocks = 0;
  int uncompensated_blocks = 0;  // machine-coordinate moves, or before every axis was known
  int rewritten_checks = 0;      // no-trigger check statements moved with their probing moves
  int split_blocks = 0;          // feed moves split to follow the nominal path
  int added_blocks = 0;          // lines the splitting added
  double max_shift_um = 0.0;
  double max_rotary_change_mdeg = 0.0;
  double max_direction_residual_urad = 0.0;  // tool direction the rotary axes could not restore
  double max_check_shift_um = 0.0;
  double max_unsplit_deviation_um = 0.0;
  double max_path_deviation_um = 0.0;
  /// The compensated tool point's uncertainty from the identification (k = 2), when the report has a covariance.
  std::optional<double> position_uncertainty_k2_um;
  std::vector<std::string> notes;     // what combining the reports found or could not decide
  std::vector<std::string> messages;  // the lines `rotacal compensate` prints, without their line ends
};

/// `rotacal compensate` on texts. Throws Error.
ROTACAL_API CompensateResult compensate(const CompensateRequest& request);

struct CheckRequest {
  NamedText program;
  NamedText machine;    // MACHINE.json
  std::string dialect;  // linuxcnc | fanuc | haas | siemens | heidenhain | okuma
  /// The program must carry the number of one of rotacal's cycles, as `rotacal check` without
  /// --plan asks; false for a post's own program.
  bool rotacal_program = false;
};

struct Violation {
  int line = 0;
  std::string problem;
};

struct CheckResult {
  std::vector<Violation> violations;  // in line order; none: the program passes
  int motion_blocks = 0;
  int probing_moves = 0;
  int obstacles = 0;  // artefact and table modelled
  /// Smallest gap (mm) kept to what is modelled; infinity when nothing is.
  double min_clearance_mm = 0.0;
  double required_gap_mm = 0.0;
  std::string summary;  // `rotacal check`'s line for a clean program, without its line end
  bool ok() const noexcept { return violations.empty(); }
};

/// The verifier on a program. Throws Error for bad input (machine, dialect), never for a
/// violation: those are the result.
ROTACAL_API CheckResult check(const CheckRequest& request);

/// A pose of the controlled point: machine coordinates (mm) relative to the rotary-axis
/// intersection, and the two rotary angles (deg) in the order of the machine's rotary axes,
/// counted as the Compensator's dialect counts them.
struct MachinePose {
  double x = 0.0, y = 0.0, z = 0.0;
  std::array<double, 2> angles{0.0, 0.0};
};

struct CompensatedPose {
  /// The command: the angles rounded to a program's 4 decimals, the position exact for them.
  MachinePose pose;
  double shift_um = 0.0;  // how far the position moved
  /// Angle between the tool direction the rounded angles give and the nominal one: the rounding
  /// and, where a rotary axis is parallel to the tool, the tilt no rotary axis can undo.
  double tool_direction_residual_urad = 0.0;
};

/// One identified error, as analyze reports it.
struct ErrorValue {
  std::string name;  // dx_AY, ...
  double value = 0.0;
  std::string unit;  // um | mdeg
};

/// The error motions of one rotary axis (component errors), where a report has them.
struct ComponentErrorSummary {
  char axis = 'C';
  std::size_t angles = 0;  // sampled angles
};

/// The errors of one or several reports, for compensating poses one at a time (a post that
/// writes its own program). Cheap to copy.
class ROTACAL_API Compensator {
 public:
  /// The reports as compensate() reads them; `dialect` is the control whose counting of the
  /// angles MachinePose uses ("": the convention of the ISO 230-7 papers). Throws Error.
  Compensator(const std::vector<NamedText>& reports, const std::string& dialect,
              const std::optional<NamedText>& machine = std::nullopt, bool force = false);
  ~Compensator();
  Compensator(const Compensator&);
  Compensator& operator=(const Compensator&);

  std::string machineName() const;
  std::string kinematics() const;          // table_ac, ...
  std::array<char, 2> rotaryAxes() const;  // in the order of MachinePose::angles
  std::vector<ErrorValue> locationErrors() const;
  std::vector<ComponentErrorSummary> componentErrors() const;

  /// The command that puts the controlled point, with the nominal tool direction, where the
  /// nominal pose puts it on the nominal machine. Throws Error (input "", line 0) when a
  /// compensated angle leaves its stroke.
  CompensatedPose compensate(const MachinePose& nominal) const;

 private:
  struct State;
  std::shared_ptr<const State> state_;
};

}  // namespace rotacal
