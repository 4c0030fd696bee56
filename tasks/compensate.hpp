#pragma once
// `rotacal compensate` on texts already read: the errors of the reports, the rewrite with the
// verifier on its input and on its output, and what the command says. The command line reads
// and writes the files around these; the public library (api/) passes texts.
#include <optional>
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

/// The errors of `reports` (errorsFromReports) on `machine`, or without it on the machine the
/// first report carries (InputError at that report when it carries none).
CompensationInputs compensationInputs(const std::vector<JsonDoc>& reports, const std::optional<MachineModel>& machine,
                                      bool force);

/// compensateProgram, then the verifier on the input (the nominal machine it was written for,
/// named `program_file`) and on the rewrite (the machine with the errors, named `out`): throws
/// InputError rather than return a program that fails it.
ProgramCompensation compensateVerified(const std::string& text, const std::string& program_file, const std::string& out,
                                       const std::string& dialect, const NcSyntax& syntax, const CompensationInputs& in,
                                       const ProgramCompensationOptions& options);

/// What `compensate` prints once `out` is written: the notes, then the summary; each line ends in '\n'.
std::vector<std::string> compensateMessages(const CompensationInputs& in, const ProgramCompensation& r,
                                            const std::string& out, double max_deviation_um);

}  // namespace rotacal
