#pragma once
// The tooltip cycle's catalogued causes hidden on heads as their contributors file declares them:
// the head and laser drawn by the independent generator (bench/independent_machine.hpp drawHead /
// measureHead: 004's head, the linear axes carrying the pivot, the tilted beams, the per-reading
// scatter and the laser's zero), the effect added as the change it makes to the readings in
// rotacal's exact tooltip simulator (simulateTooltip, the path `rotacal simulate` takes): the
// readings of a truth holding the drawn head's dR and angular errors with the effect, minus the
// same truth's without it. Superposition: the cross terms are second order (micrometres of
// effect times the declared milliradians of beam tilt, or the effect's own pivot move through the
// axes' error slope of micrometres per 20-50 mm). The machine's part shares no code with what it
// tests, the effect's part is the simulator the clean-world tests already hide effects with.
#include <functional>
#include <string>
#include <vector>

#include "bench/independent_machine.hpp"
#include "core/contributors.hpp"
#include "core/judge.hpp"
#include "core/probe_plan.hpp"
#include "cycles/tooltip/diagnose.hpp"
#include "cycles/tooltip/plan.hpp"

namespace rotacal::independent {

using TooltipEffect = std::function<void(TooltipTruth*)>;

/// Run `run` of `plan` on `head` (run 0 the head's own per-reading draws, run r > 0 its own: a new
/// laser zero and scatter, the same head and axes) with `effect` applied. Throws std::logic_error
/// when the generator and the simulator read different angles in different orders.
TooltipRun measureHeadWithEffect(const ProbePlan& plan, const Head& head, const TooltipEffect& effect, int run = 0);

/// What `rotacal diagnose --contributors` does with the readings of `plans` (one set each, one
/// run, set p's reading draws those of run p) measured on `head` with `effect`: each set's
/// readings screened against the declaration, the kept ones judged together.
TooltipDiagnosis diagnoseDrawnHead(const std::vector<const ProbePlan*>& plans, const Head& head, const TooltipEffect& effect,
                                   const ContributorSet& declared);

/// The standard uncertainty of each parameter of `problem`'s cause `cause` under the declared
/// covariance with the baseline fitted beside it (generalized least squares): the scatter the
/// declared machine alone gives that estimate, so that an effect of a few of them is beyond what
/// the declaration makes.
std::vector<double> declaredCauseU(const JudgeProblem& problem, const std::string& cause);

/// The bench mode `tooltip_drawn` of rotacal_diagnose_bench: printed, not asserted.
void tooltipDrawnBench(int clean_seeds, int effect_seeds);

}  // namespace rotacal::independent
