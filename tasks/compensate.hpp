#pragma once
// `rotacal compensate` on texts already read: the errors of the reports, the rewrite with the
// verifier on its input and on its output, and what the command says. The command line reads
// and writes the files around these; the public library (api/) passes texts.
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "postproc/compensate_program.hpp"
#include "postproc/report_errors.hpp"

namespace rotacal {

/// The syntax the rewrite needs from a word-address dialect. Throws std::invalid_argument for
/// heidenhain, csv and a name that is no dialect (the message says what to do instead).
NcSyntax ncSyntaxOf(const std::string& dialect);

struct CompensationInputs {
  MachineModel machine;
  ReportErrors read;
  std::vector<std::string> header;  // the rewritten program's provenance lines
};

/// What compensate checks of its reports beyond their content.
struct ReportChecks {
  /// Component errors a controller table holds (e.g. ECC): left out (errorsFromReports).
  std::vector<std::string> table_holds;
  /// Now (s since 1970, UTC): a report analyzed longer ago than kReportAgeFlagDays is flagged in
  /// the notes; unset, age is not judged.
  std::optional<double> now_s;
  /// The machine file's name, for the refusal of a report of another machine.
  std::string machine_file = "the machine given";
};

/// A name in ReportChecks::table_holds that is no component error of the machine's rotary axes.
struct UnknownHeldError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// A report older than this is flagged: a machine's location errors move with crashes,
/// maintenance and the seasons, and a compensation for last quarter's machine is a guess.
constexpr double kReportAgeFlagDays = 30.0;

/// The errors of `reports` (errorsFromReports) on `machine`, or without it on the machine the
/// first report carries (InputError at that report when it carries none). With `machine`, every
/// report must be of it (its name and kinematics as analyze recorded them), else InputError.
CompensationInputs compensationInputs(const std::vector<JsonDoc>& reports, const std::optional<MachineModel>& machine,
                                      bool force, const ReportChecks& checks = {});

/// compensateProgram, then the verifier on the input (the nominal machine it was written for,
/// named `program_file`) and on the rewrite (the machine with the errors, named `out`): throws
/// InputError rather than return a program that fails it. A program without a probing move is a
/// part program and is checked as one (ProgramCheckSetup::part_program, from its origin);
/// ProgramCompensation::part_program says which.
ProgramCompensation compensateVerified(const std::string& text, const std::string& program_file, const std::string& out,
                                       const std::string& dialect, const NcSyntax& syntax, const CompensationInputs& in,
                                       const ProgramCompensationOptions& options);

/// What `compensate` prints once `out` is written: the notes, then the summary; each line ends in '\n'.
std::vector<std::string> compensateMessages(const CompensationInputs& in, const ProgramCompensation& r,
                                            const std::string& out, double max_deviation_um);

}  // namespace rotacal
