#pragma once
// The fixed-tool-tip cycle of 004 (Optodyne note): on a spindle head tilting in A (about X) and
// B (about Y) about a pivot, one rotary axis steps while the linear axes move the pivot so that
// the tool tip (the centre of the tester's precision sphere) stays where it started:
//   tip_m = P_m + Rx(A) Ry(B) (0, 0, -R)                       (004 Sec. IV, signs fixed so that
//   A axis, B = b:  P_m(A) = t0 - Rx(A) Ry(b) (0, 0, -R)         Sec. V holds: at b = 0,
//                                                                Yp = -R sin A, Zp = -R (1 - cos A))
// A laser looking at the sphere reads the tip's deviation in the rotation plane (A: Y and Z;
// B: X and Z), zeroed at the sweep's first pose at 0 deg (004: the start, Yp = Zp = A = 0). This header holds the plan, the exact
// head geometry, the simulator and the results file; cycles/tooltip/analyze.hpp the analysis.
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// The cycle options (`--set`), parsed and checked.
struct TooltipOptions {
  char axis = 'A';                  // the stepping axis
  double radius_mm = 381.0;         // R, pivot to tool tip (004: 15 in)
  double step_deg = 5.0;
  double start_deg = 0.0;           // static test: first angle (<= 0; the reading is zeroed at 0)
  double end_deg = 90.0;
  std::vector<double> other_deg{0.0};  // angles of the other axis, one sweep each (004 Sec. VI)
  bool inch = false;                // program units (default: the machine's)
  double move_s = 30.0;             // time of one step: inverse-time F = 60 / move_s (004: F2.)
  double dwell_s = 2.0;             // static test: dwell after each step for the reading (0: none)
  int sweeps = 0;                   // 0: static 0..end; n > 0: dynamic test of 004 Sec. VI,
                                    // 0 -> +end -> -end -> 0, n times, no dwell
  /// Runs of the whole plan in one program, each zeroing the laser anew: one run cannot see a
  /// gross reading along the tip's circle (its angle's own error takes it up), three can. A plan
  /// without the option reads 1 (004's one run); makeTooltipPlan writes kTooltipRepeats for the
  /// static test.
  int repeats = 1;
  double noise_um = 0.254;          // laser_noise_um: the DECLARED noise of a reading component;
                                    // default 004 Sec. VII's laser system error, 0.000010 in
  /// Dynamic test: the largest distance the tool tip may leave its fixed point between the
  /// program's block ends (um). A joint-space block of 5 deg at R = 381 mm sags 363 um mid-block
  /// (more than 004's 0.010 in limit); each step is split into equal moves so that the sag
  /// R (1 - cos(phi / 2)) of a move of phi stays below this. The static test reads at rest at the
  /// block ends and keeps 004 Table 1's blocks.
  double max_sag_um = 1.0;

  char otherAxis() const { return axis == 'A' ? 'B' : 'A'; }
};

TooltipOptions tooltipOptionsFrom(const CycleOptions& options, const MachineModel& machine);

/// The runs a new static plan repeats when `repeats` is not given: the fewest that tell a gross
/// reading from its angle's own error (two readings of a value predict each other alike; a third
/// breaks the tie: docs/real_machines.md).
constexpr int kTooltipRepeats = 3;

/// Moves per step of the program (1 for the static test) and the tool tip's largest departure
/// from its fixed point between them, um (the chord's sagitta).
int tooltipPiecesPerStep(const TooltipOptions& options);
double tooltipSagUm(const TooltipOptions& options);

/// The plan: one point per commanded angle (the reading), pose = commanded angles, trigger_m_mm =
/// commanded pivot position, contact_w_mm = the fixed tool tip, approach_m = the laser's
/// tangential read direction, pose_name = "<other axis><angle>" naming the sweep.
ProbePlan makeTooltipPlan(const MachineModel& machine, const CycleOptions& options);

/// Tool-tip offset from the pivot, machine frame: Rx(A) Ry(B) (0, 0, -R) (mm; angles in rad).
Eigen::Vector3d tipOffset_m(double a_rad, double b_rad, double r_mm);

/// The machine's true head (simulate): a pivot-length error dR and an angular positioning
/// error of the stepping axis e(theta) = offset + slope theta/90deg + s1 sin theta + s2 sin 2 theta.
struct TooltipTruth {
  double dR_um = 0.0;
  double offset_mdeg = 0.0;
  double slope_mdeg_per_90deg = 0.0;
  double sin_mdeg = 0.0;
  double sin2_mdeg = 0.0;
  double noise_um = 0.0;  // laser reading, standard deviation per component
  // Linear axes in the read plane positioning with a scale error (the transverse axis: Y for A,
  // X for B; and Z), about the machine origin: the pivot goes to (1 + s) x its command.
  double scale_t_um_m = 0.0, scale_z_um_m = 0.0;
  // The tip drifting in the read plane with time (um/h), from the plan's reading times.
  double drift_t_um_h = 0.0, drift_z_um_h = 0.0;

  double angularErrorMdeg(double theta_deg) const;
};
/// The "tooltip" object of TRUTH.json (dR_um, angular_error, scale_um_m: both read-plane axes);
/// missing fields are zero.
TooltipTruth tooltipTruthFrom(const JsonDoc& doc, const Json& truth);

/// One reading: the commanded angle and the deviation of the tip (actual - nominal, machine
/// frame) in the rotation plane: `t` = the transverse component (Y for A, X for B), `z` = Z.
struct TooltipReading {
  double angle_deg = 0.0;
  double t_um = 0.0;
  double z_um = 0.0;  // NaN when the laser read the transverse direction alone (004)
};
using TooltipRun = std::vector<TooltipReading>;

/// Exact forward model: deviation of every plan point, zeroed at the first point of its sweep.
/// `start_s`: the clock at the run's start (a repeat's drift), added to the plan's reading times.
TooltipRun simulateTooltip(const ProbePlan& plan, const TooltipTruth& truth, std::uint64_t seed);

/// What a machine drawn from its contributors adds (simulate --contributors, budget.hpp's
/// drawTooltip): the linear axes put the pivot off its command by `pivot_error_mm(command)`, and
/// the laser reads along the unit directions `beam_t` and `beam_z` (machine frame).
struct TooltipMachine {
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> pivot_error_mm;  // empty: none
  Eigen::Vector3d beam_t = Eigen::Vector3d::Zero(), beam_z = Eigen::Vector3d::UnitZ();  // beam_t zero: the transverse axis
};
TooltipRun simulateTooltip(const ProbePlan& plan, const TooltipTruth& truth, std::uint64_t seed, const TooltipMachine& machine,
                           double start_s = 0.0);
/// The plan's `repeats` runs on one machine, as its program measures them: run r from its own
/// reading seed (run 0: `seed` itself) and starting when the one before ends (tooltipRunSeconds).
std::vector<TooltipRun> simulateTooltipRepeats(const ProbePlan& plan, const TooltipTruth& truth, std::uint64_t seed,
                                               const TooltipMachine& machine, double start_s = 0.0);
/// The time one run of the plan takes, s: its last reading plus the move back to the next start.
double tooltipRunSeconds(const ProbePlan& plan);

/// Index of the zero reading (the first pose at 0 deg of the same sweep) of every plan point.
std::vector<int> tooltipReferences(const ProbePlan& plan);

/// The neutral results file `angle_deg,dy_um,dz_um` (axis B: `angle_deg,dx_um,dz_um`): one row
/// per plan point, run after run (the program's repeats), a `# run r` line before each from the
/// second on.
std::string tooltipResultsText(const ProbePlan& plan, const TooltipRun& run);
std::string tooltipResultsText(const ProbePlan& plan, const std::vector<TooltipRun>& runs);
/// Reads it: the runs it holds, a whole number of the plan's points each, at most the plan's
/// `repeats`; throws InputError(file, line, ...) on a wrong header, count or angle.
std::vector<TooltipRun> parseTooltipResults(const std::string& text, const std::string& file, const ProbePlan& plan);

/// What a PLAN.json of this cycle must satisfy beyond the format (the cycle's identity).
PlanRules tooltipPlanRules();

}  // namespace rotacal
