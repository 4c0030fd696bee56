#pragma once
// Checks every results parser applies besides its own format: the file is text (no binary
// bytes), and each trigger lies on the probing move it claims to come from. The second one
// catches what a well-formed file can still get wrong: lines of another plan, values moved to
// the wrong point id, a coordinate printed in the wrong unit.
#include <Eigen/Core>
#include <string>
#include <string_view>

#include "core/probe_plan.hpp"

namespace rotacal::ctl {

/// How far (mm) a trigger may lie from the segment of its probing move: the move runs from
/// trigger - approach_mm * u to trigger + overtravel_mm * u (u = approach_m). A controller
/// latches the axes of that move, so the only deviation is the servo's following error (a few
/// um across the move, far less along a single-axis move) and the printed rounding (<= 2.5 um
/// at 4 inch decimals); 0.1 mm is 20x that and still 50x smaller than the 5 mm that separates
/// the closest targets of the 154-point plan (000), so a misplaced value cannot pass.
constexpr double kTriggerOffMoveTolMm = 0.1;

/// Throws InputError(file, line, ...) at the first byte that is neither printable ASCII
/// (0x20-0x7E) nor a tab or a line end: results files are plain ASCII text on every control,
/// so such a byte means a damaged transfer or the wrong file. Lines are counted as splitLines
/// counts them (LF, CR LF, lone CR).
void requireText(std::string_view text, const std::string& file);

/// Throws InputError(file, line, ...) when `position_m_mm` (mm, machine frame, papers'
/// convention) is farther than kTriggerOffMoveTolMm from the probing move of `point`.
void requireOnProbingMove(const ProbePlan& plan, const ProbePoint& point, const Eigen::Vector3d& position_m_mm,
                          const std::string& file, int line);

}  // namespace rotacal::ctl
