#pragma once
// rotacal diagnose for R-test series (002), through the one judge (core/judge.hpp).
//
// The problem handed to the judge:
//  - y: every sensor reading (um, workpiece frame, 3 per pose and cycle, and per reset and
//    re-read of the reset pose where the results have them), as the sensors' counts since the
//    zero at the first cycle's reset. The baseline is 002 Eq. (6) over all cycles: the six errors
//    of 002 Table 2 at each tilt, constant over the series, read against that zero (dz and c at
//    tilt 0 fixed to 0, the convention of analyze; a reset row's model is 0). It is linear in the
//    errors, so the judge's baseline residual is the per-reading residual of that fit.
//  - sigma: the DECLARED sensor noise, the plan's `sensor_noise_um` (default 0.2 um: 002's
//    stated system accuracy), never the fit's own scatter.
//  - groups: cycles (leave one cycle out); factors: time, tilt, C, sensor direction, cycle.
// The catalog (candidates the judge tests, each a family of columns tested jointly):
//  - thermal_drift: every one of the 6 x (tilts) errors changes linearly with the hours since
//    the reset (the columns tau J_j, not referenced: the reset happened once, at t0);
//  - sensor_step_cycle_K (K = 2..cycles): from cycle K's first reading on the sensors read a
//    constant offset (dx, dy, dz in the workpiece frame, where the nest's sensors sit): a step
//    between cycles K-1 and K;
//  - sensor_step_in_cycle_K (K = 1..cycles, cycles with a re-read): the offset from cycle K's
//    re-read on: a step during cycle K (the poses of cycle K read after the step
//    are not modelled). Both are the contract's `sensor_step`.
// Confounds of the table drift (002 Sec. 4.3: the R-test sees the sphere against the nest only):
//  - spindle_growth: the sphere rises along machine Z linearly with time;
//  - linear_axis_drift: the sphere drifts along machine X, Y, Z linearly with time.
// They are not candidates beside thermal_drift (their columns lie in its span: as candidates
// they would withhold every drift finding as ambiguous). Instead the judge, run with the table
// drift in the model, reports how each is read as table drift (the `confounded` entry, from the
// Jacobians), and two nested judgements say whether one alone explains the drift signal
// (it passes against the baseline and the table drift adds nothing significant beyond it); the
// finding's wording then names the spindle or the linear axes instead of the table.
#include <string>
#include <vector>

#include "core/judge.hpp"
#include "core/json_io.hpp"
#include "core/probe_plan.hpp"
#include "cycles/rtest/analyze.hpp"
#include "cycles/rtest/plan.hpp"

namespace rotacal {

struct RtestDiagnosisOptions {
  JudgeOptions judge;             // alpha and the rules (docs/diagnosis.md)
  double sensor_sigma_um = 0.2;   // the declared sensor noise (the re-read check of analyze)
  /// The declared scatter of one reading (rtestDeclaredNoise: sensors and sphere form), what the
  /// judge whitens by; 0: the sensors alone.
  double reading_sigma_um = 0.0;
  std::string declaration;        // what it is, named in the verdict
  /// The declared structured part of one cycle (rtestDeclaredNoise), the same machine in every
  /// cycle: the judge whitens by it beside reading_sigma_um (and the screen). Empty: none.
  Eigen::MatrixXd structured_um2;
  Eigen::MatrixXd structured_draws_um;  // its draws (rtestStructuredDrawsUm): the screen's threshold
  double readingSigmaUm() const { return reading_sigma_um > 0 ? reading_sigma_um : sensor_sigma_um; }
  bool validate(std::string* why) const;  // false, and why naming the field, when out of range
};

/// The judge's problem for a series, with the confounds' columns beside it (same rows).
struct RtestJudgeSetup {
  JudgeProblem problem;           // baseline + candidates (thermal_drift first, then the steps)
  std::vector<JudgeCause> confounds;  // spindle_growth, linear_axis_drift
  std::vector<double> t_h;        // hours since the reset, per observation
  std::vector<int> cycle;         // 0-based cycle, per observation (reset and re-read rows included)
  std::vector<int> plan_row;      // 3 x (plan point index) + axis, per observation (reset, re-read: the reset pose's)
};
/// `excluded`: the pose readings' values the screen left out, (cycle, 3 x plan point index + axis)
/// as RtestScreen::excluded gives them: their rows are not in the problem.
RtestJudgeSetup rtestJudgeSetup(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, double sensor_sigma_um,
                                const std::vector<std::pair<int, int>>& excluded = {});

/// What the nested judgements say about one confound of the table drift.
struct RtestConfound {
  JudgeConfounded entry;        // from the judge with thermal_drift in the model: how it is read
  JudgeCandidate alone;         // its test against the baseline
  JudgeCandidate drift_beyond;  // thermal_drift's test with the confound in the model
  bool explains = false;        // alone passes and the table drift adds nothing beyond it
};

struct RtestDiagnosis {
  RtestAnalysis analysis;
  int cycles = 0;
  JudgeSummary summary;
  std::vector<RtestConfound> confounds;
};

RtestDiagnosis diagnoseRtest(const ProbePlan& plan, const std::vector<RtestCycle>& cycles,
                             const RtestDiagnosisOptions& options);
/// The finding's one sentence (contract `summary`); names the spindle or the linear axes when
/// one of them explains the same signal.
std::string rtestFindingSummary(const ProbePlan& plan, const RtestDiagnosis& d, const JudgeFinding& f);
Json rtestDiagnosisJson(const ProbePlan& plan, const RtestDiagnosis& d);
std::string rtestDiagnosisText(const ProbePlan& plan, const RtestDiagnosis& d);

}  // namespace rotacal
