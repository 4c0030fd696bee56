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
#include "core/json_io.hpp"
#include "core/machine.hpp"

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
  std::vector<std::string> header;  // provenance lines written as comments at the top
};

struct ProgramCompensation {
  std::string text;
  int motion_blocks = 0;        // blocks with axis words
  int compensated_blocks = 0;   // rewritten
  int uncompensated_blocks = 0; // passed unchanged: machine-coordinate moves (G53, G28, G30) or
                                // before every axis had a known position
  double max_shift_mm = 0.0;             // largest change of a linear endpoint
  double max_rotary_change_deg = 0.0;    // largest change of a rotary word
  double max_direction_residual_rad = 0.0;  // tool direction the rotary axes could not restore
  int rewritten_checks = 0;              // no-trigger check statements given the new end point
  double max_check_shift_mm = 0.0;       // largest move of a probing move's end point (and its check)
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
/// The identified location errors of a REPORT.json (contract.md), in mm / rad. All of the
/// kinematics' location errors must be there (a missing one would be compensated as 0 under a
/// header that claims the report's errors), and each must be plausible as a correction unless
/// `force`. Throws InputError(report file, line, why).
LocationErrors errorsFromReport(const JsonDoc& doc, Kinematics k, bool force);

ProgramCompensation compensateProgram(const std::string& text, const std::string& file, const MachineModel& machine,
                                      const LocationErrors& errors, const NcSyntax& syntax,
                                      const ProgramCompensationOptions& options);

}  // namespace rotacal
