#pragma once
// The program verifier (`rotacal check`): simulates the motions read back from a
// program's text (controllers/motion_reader.hpp) on the machine's nominal kinematics and proves
// what a probing program must never do wrong on a real machine:
// - no non-probing move brings the probe ball or its stylus (a capsule of the ball's radius from
//   the ball centre up the tool axis for stylus_length_mm) nearer than the required gap to the
//   artefact, the calibration spheres of the plan or the table, swept along the whole move
//   (rotary moves included), except a move that leaves a touch or sets up the next one;
// - every probing move is guarded: followed, before the next move, by its no-trigger check
//   (unless the control alarms by itself, G38.2), and the check compares with that move's own
//   end point (a stale check passes a probe that never triggered);
// - every linear and rotary word lies inside the machine's strokes;
// - a feed is set before every feed move, every inverse-time (G93) block carries F, and no
//   probing move runs under G93;
// - the program number is the one of its cycle.
// The sweep is certified, not merely sampled: the gap is 1-Lipschitz in the position of the
// probe, and no point of the probe moves faster than D mm per unit of the move's parameter
// (linear travel plus each rotary angle in rad times the largest distance of the probe from the
// rotary axes), so a step of max(0.5 (gap - floor), kSweepResolutionMm) / D cannot skip a place
// where the gap falls below the floor by more than kSweepResolutionMm (docs/safety.md).
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/error_model.hpp"
#include "core/geometric_errors.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "gcode/motion.hpp"

namespace rotacal {

/// How finely the sweep resolves the gap (mm): the verifier proves every gap to within this.
constexpr double kSweepResolutionMm = 0.05;
/// What the required gap leaves for `rotacal compensate`'s shifts of a nominal program (the
/// plausibility limit of a length correction, 0.5 mm), at most half the planned gap.
constexpr double kCompensationAllowanceMm = 0.5;
/// Tolerance of a no-trigger check's end point against its move's (program units): the two are
/// printed from one value to 4 decimals, so any larger difference is a different end point.
constexpr double kCheckEndTolerance = 1.5e-4;

struct ProgramCheckSetup {
  const MachineModel* machine = nullptr;   // kinematics, strokes, probe, clearances, artefact
  std::string dialect;                     // the controller's rotary signs (MachineModel::controllerSign)
  const ProbePlan* plan = nullptr;         // optional: its spheres are obstacles and every probe must reach a surface
  bool artefact_on_table = true;           // the machine's artefact stands on the table during this program
  bool numbered = false;                   // the dialect gives programs a number (O word)
  std::optional<int> program_number;       // the number this program must carry (its cycle's)
  std::vector<int> rotacal_numbers;        // without a known cycle: the number must be one of these
  /// The machine's identified location errors: the program is simulated on that machine (a
  /// compensated program is written for it, and keeps its planned gaps there). Unset: nominal.
  std::optional<GeometricErrors> errors;
  /// A part program (it has no probing move): what moves is the tool's controlled point, no probe
  /// ball or stylus; no calibration artefact stands on the table (parts are cut without it); the
  /// table (MachineModel::table_top_z_mm, else the artefact's bottom) is the obstacle, and the
  /// point must not enter it (no required gap: a cut may run down to the table). A move before Z
  /// is known is the operator's set-up, not proven.
  bool part_program = false;
  /// Machine position of the program's zero relative to the rotary-axis intersection (mm): the
  /// program's X Y Z plus this are the machine's (compensate's --program-origin).
  Eigen::Vector3d program_origin_m_mm = Eigen::Vector3d::Zero();
};

struct ProgramViolation {
  int line = 0;
  std::string problem;
};

struct ProgramCheckResult {
  std::vector<ProgramViolation> violations;  // in line order
  int motion_blocks = 0;                     // rapid, feed and probing moves
  int probing_moves = 0;
  int swept_samples = 0;                     // configurations evaluated along the moves
  /// Smallest gap (mm) between the probe and what is modelled over the moves between touches
  /// (not the moves that leave or set up a touch); infinity when nothing is modelled.
  double min_clearance_mm = std::numeric_limits<double>::infinity();
  double required_gap_mm = 0.0;              // what those moves must keep
  int obstacles = 0;                         // artefact, spheres and table modelled
};

/// Throws std::invalid_argument when setup.machine is null.
ProgramCheckResult checkProgram(const std::vector<nc::Motion>& motions, const ProgramCheckSetup& setup);

}  // namespace rotacal
