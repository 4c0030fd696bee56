#pragma once
// rotacal diagnose for fixed-tool-tip readings (004), through the one judge
// (core/judge.hpp).
//
// The problem handed to the judge:
//  - y: every laser reading component (transverse and Z, um) minus 004's model (one angular
//    error per commanded angle, the pivot length as programmed) at its least-squares solution;
//    J0: that model's Jacobian there (cycles/tooltip/analyze.hpp, analytic, checked against
//    finite differences). With several tool lengths (sets) the angular errors are shared by
//    commanded angle (one axis) and the baseline is linearised at the first set's solution.
//  - the noise: the DECLARED one, never the fit's own scatter. With the machine's contributors,
//    their declaration (cycles/tooltip/noise.hpp: the per-reading laser contributors, and what the
//    linear axes and the beams' alignment move the readings by, shared between readings, as the
//    judge's full covariance); without, the plan's `laser_noise_um` alone (default 0.254 um: 004
//    Sec. VII's laser system error, 0.000010 in). Either way each sweep's laser zero, read with
//    the same per-reading scatter, is shared by the values of its sweep and direction in one run
//    (a new zero in every run and tool). A value the screen of gross readings left out (NaN) is
//    not in the problem.
//  - groups: the repeats (results files) when there are at least 3, else the commanded angles
//    (leave one angle out: its own error is refitted on it by the judge); factors: angle,
//    component, repeat, time, tool.
// The catalog:
//  - pivot_length (dR, um): the tip is farther from the pivot than programmed;
//  - linear_axis_scale (s_t, s_Z in um/m): the linear axes in the read plane position with a
//    scale error about the machine origin; the pivot moves by s x its command, so the tip reads
//    s (F(ref) - F(theta)). An isotropic s is dR = -s R exactly with one tool: the judge finds
//    the pair exactly confounded from the columns and withholds both;
//  - thermal_drift (dt/h, dz/h, um/h) where an angle is read more than once (repeats, or a
//    dynamic test): the tip moves in the read plane with the time since its sweep's zero reading
//    (the plan's reading times; a results file carries no clock).
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/judge.hpp"
#include "core/json_io.hpp"
#include "cycles/tooltip/analyze.hpp"
#include "cycles/tooltip/plan.hpp"

namespace rotacal {

/// One tool length: a plan and its repeats.
struct TooltipSet {
  const ProbePlan* plan = nullptr;
  std::vector<TooltipRun> runs;
};

struct TooltipDiagnosisOptions {
  JudgeOptions judge;
  double noise_um = 0.0;  // declared laser noise; 0: the first plan's laser_noise_um
  /// The machine's declared contributors (null: the laser noise above alone).
  const ContributorSet* contributors = nullptr;
  bool validate(std::string* why) const;  // false, and why naming the field, when out of range
};

struct TooltipJudgeSetup {
  JudgeProblem problem;
  std::vector<double> angles_deg;  // the shared angular errors' angles, ascending
  TooltipFit baseline;             // 004's model fitted to the first set (the linearisation point)
};
TooltipJudgeSetup tooltipJudgeSetup(const std::vector<TooltipSet>& sets, double noise_um,
                                    const ContributorSet* contributors = nullptr);

struct TooltipDiagnosis {
  int sets = 0, runs = 0;
  std::vector<double> radius_mm;
  TooltipJudgeSetup setup;
  JudgeSummary summary;
};

TooltipDiagnosis diagnoseTooltip(const std::vector<TooltipSet>& sets, const TooltipDiagnosisOptions& options);
Json tooltipDiagnosisJson(const TooltipDiagnosis& d);
std::string tooltipDiagnosisText(const TooltipDiagnosis& d);

}  // namespace rotacal
