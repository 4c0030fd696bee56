#pragma once
// The uncertainty the tooltip cycle signs for its angular errors e_k (mdeg) and the pivot-length
// error dR (um), on core/uncertainty_budget:
//   Type A  the per-reading scatter (the laser's own error, the sphere's form, lateral coupling:
//           004 Sec. VII) through the fit's own map, sigma^2 (J^T J)^-1, plus the same scatter
//           of each sweep's zero reading, which every value of the sweep and direction in its
//           run is read less (sigma^2 A Z A^T, A = (J^T J)^-1 J^T, Z = 1 between the values of
//           one zero); sigma from the residual less what the Type B contributors leave in it,
//           on the per-reading scale (the zero's share of the residual taken out), floored at
//           the declared scatter; repeats raise a parameter to the scatter of the repeats' mean;
//   Type B  the declared contributors the data cannot show (004 Sec. VII's machine positioning,
//           on the linear-axis model; the laser's alignment), by Monte Carlo: each run draws them,
//           simulates the readings on the exact head geometry around the identified errors, and
//           runs them through fitTooltip (Gauss-Newton on the exact model): deviation = estimate -
//           truth, so an estimator's bias counts.
// docs/uncertainty.md (tooltip) states the rules and the coverage measured.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/contributors.hpp"
#include "core/linear_axes.hpp"
#include "core/rng.hpp"
#include "core/uncertainty_budget.hpp"
#include "cycles/tooltip/analyze.hpp"

namespace rotacal {

struct TooltipBudgetOptions : BudgetOptions {};

/// Contributors that act independently at every reading: u_A measures them.
bool tooltipTypeA(const ContributorInfo& c);
/// Contributors that act on the readings through the machine or the set-up (the linear axes
/// carrying the pivot, the beams' alignment): Type B, drawn by drawTooltip.
bool tooltipTypeB(const ContributorInfo& c);

/// One drawn realisation of the tooltip cycle's Type B contributors (internal units).
struct TooltipDraw {
  bool linear = false;
  LinearAxisErrors linear_errors;  // the pivot lands at command + error(command)
  // Beam directions: the transverse beam tilted toward Z (in_t) and toward the unread axis
  // (out_t); the Z beam tilted toward the transverse axis (in_z) and the unread axis (out_z); rad.
  double in_t = 0, out_t = 0, in_z = 0, out_z = 0;
};

/// Draws run `run` of `seed` from `set` (Type A contributors skipped); with `only` >= 0 every
/// contributor but set.items[only] is zero. The same (seed, run) draws the same values whether
/// alone or combined (one stream per contributor).
void drawTooltip(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, int run, int only, TooltipDraw* out);

/// The draw as the simulator's machine: the linear axes' error at the pivot's command, the beams.
TooltipMachine tooltipMachineOf(const ProbePlan& plan, const TooltipDraw& draw);

/// What `draw` is, for TRUTH.json's `drawn` (report units: um, um/m, urad).
Json tooltipDrawJson(const TooltipDraw& draw);

/// A head with an angular error per distinct commanded angle (mdeg, the fit's ascending order of
/// `angles_deg`) and a pivot-length error (um).
struct TooltipHead {
  std::vector<double> angles_deg;
  std::vector<double> e_mdeg;
  double dR_um = 0.0;
};

/// The exact readings of `plan` for `head` with the draw acting (the pivot off its command, the
/// beams tilted), zeroed at each sweep's zero pose as the laser is; `read_z` false: the transverse
/// direction alone (z NaN, 004). With `rng`, every reading component gets noise_um x N(0, 1),
/// and so does each sweep's zero reading (drawn first, in plan order), which every later reading
/// of its sweep is read less: the laser is zeroed on a reading.
TooltipRun simulateTooltipHead(const ProbePlan& plan, const TooltipHead& head, const TooltipDraw& draw, bool read_z,
                               double noise_um, Rng* rng);

/// The budget of the analysis `a` of `runs`: the angular errors e_<axis><angle> that the fit
/// estimates (in the transverse-only case not the zero pose's, fixed at 0), then dR when it is
/// identified. `declared_noise_um`: the plan's laser_noise_um, replaced by `laser_resolution` when
/// the contributors declare it. `contributors` null: u_B not evaluated (said in words).
UncertaintyBudget tooltipBudget(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipAnalysis& a,
                                double declared_noise_um, const ContributorSet* contributors,
                                const TooltipBudgetOptions& options);

/// The budget's values (report units) from the analysis, in the budget's order.
Eigen::VectorXd tooltipBudgetValues(const TooltipAnalysis& a, const UncertaintyBudget& b);

}  // namespace rotacal
