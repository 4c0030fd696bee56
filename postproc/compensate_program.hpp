#pragma once
// Compensation by rewriting an NC program (the post-processor route): every motion endpoint of a
// word-address program (LinuxCNC, Fanuc Custom Macro B, Haas, Okuma, Siemens G-code) is replaced
// by the command that puts the controlled point, with the nominal tool direction, on the same
// workpiece point on the machine with the identified location errors (core/compensation.hpp).
// The program must command machine coordinates (work offset at a known position relative to the
// rotary-axis intersection) without tool-centre-point control; anything the rewrite cannot keep
// exact is refused with FILE:LINE: why.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/compensation.hpp"
#include "core/geometric_errors.hpp"
#include "core/machine.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// How the program spells what the rewrite writes (from the dialect, chosen in the CLI).
struct NcSyntax {
  std::string dialect;            // the rotary axes' counting sign (MachineModel::controllerSign)
  int length_decimals_mm = 4;
  int length_decimals_inch = 5;
  int angle_decimals = 4;
  enum class Comment { Parentheses, Semicolon } comment = Comment::Parentheses;
};

struct ProgramCompensationOptions {
  /// Machine position (mm) of the program zero relative to the rotary-axis intersection (0 when
  /// the work offset sits at the intersection, as in rotacal's own programs).
  Eigen::Vector3d program_origin_m_mm = Eigen::Vector3d::Zero();
  CompensationOptions pose;
  /// Feed moves (G1) whose rotary axes turn are split where the compensated straight joint-space
  /// move would leave the nominal path by more than subdivision.max_deviation_mm (core/
  /// compensation.hpp). Rapids (G0) are not split: their path is the control's, only their end
  /// points are cutting-relevant. Probing moves never turn a rotary axis, so never need it.
  std::vector<std::string> header;  // provenance lines written as comments at the top
  SubdivisionOptions subdivision;
  bool subdivide = true;
};

struct ProgramCompensation {
  std::string text;
  bool part_program = false;    // no probing move: checked as a part program (tasks/compensate.hpp)
  int motion_blocks = 0;        // blocks with axis words
  int compensated_blocks = 0;   // rewritten
  int uncompensated_blocks = 0; // passed unchanged: machine-coordinate moves (G53, G28, G30) or
                                // before every axis had a known position
  double max_shift_mm = 0.0;             // largest change of a linear endpoint
  double max_rotary_change_deg = 0.0;    // largest change of a rotary word
  double max_direction_residual_rad = 0.0;  // tool direction the rotary axes could not restore
  int rewritten_checks = 0;              // no-trigger check statements given the new end point
  double max_check_shift_mm = 0.0;       // largest move of a probing move's end point (and its check)
  int split_blocks = 0;                  // feed moves split into pieces
  int added_blocks = 0;                  // lines the splitting added
  double max_unsplit_deviation_mm = 0.0; // largest path deviation a move would have had unsplit
  double max_path_deviation_mm = 0.0;    // largest path deviation of a written feed move (evaluated)
  /// Largest standard uncertainty (k = 1) of the compensated controlled point from the location
  /// errors' covariance (largest axis of J C J^T over the block ends); 0 without a covariance.
  double max_position_u_mm = 0.0;
};

/// Rewrites `text` (read from `file`, for messages). Throws InputError(file, line, why) on what
/// cannot be compensated exactly: arcs, tool-centre-point control, tilted work planes, offset
/// changes inside the program, incremental rotary moves, axis words that are expressions, a
/// compensated linear or rotary word outside the machine's strokes, a probing move whose
/// no-trigger check (ctl::EndPointCheck) is not where the dialect writes it, a program already
/// compensated (it carries the ROTACAL-COMPENSATED comment this function writes first), and a
/// rewrite that the dialect's own checker finds a problem in that the input does not have.
/// Lines longer than 1024 characters and exponent notation (X1e2) are refused too. Throws
/// std::invalid_argument for heidenhain or csv (not word-address G-code) or an unknown dialect.
/// The errors come from postproc/report_errors.hpp (one or several REPORT.json). All-zero errors
/// return the program byte for byte (no mark, no header).
ProgramCompensation compensateProgram(const std::string& text, const std::string& file, const MachineModel& machine,
                                      const GeometricErrors& errors, const NcSyntax& syntax,
                                      const ProgramCompensationOptions& options);

/// The results of a plan's program compensated for `errors` (compensateProgram with `syntax` and
/// `options`), read back as the original program's: each trigger x' recorded at the compensated
/// pose q' of its point's nominal pose q (recomputed and rounded exactly as the rewrite printed
/// it) is mapped to T_m_w(0, q) T_m_w(errors, q')^-1 x', where the nominal machine would have
/// recorded the same contact. Analyzed with the original plan, these results identify what the
/// compensation left: the true errors minus `errors`, to first order (`analyze
/// --compensated-with`, docs/compensation.md). Throws std::invalid_argument when the results are
/// the uncompensated program's: most touches where the two programs' probing lines lie 1 um or
/// more apart across the approach lie on the uncompensated line (a controller records positions
/// on the line it ran).
MeasurementRun undoCompensation(const ProbePlan& plan, const MeasurementRun& run, const GeometricErrors& errors,
                                const NcSyntax& syntax, const ProgramCompensationOptions& options = {});

}  // namespace rotacal
