#pragma once
// A hidden effect on top of a machine as its contributors file declares it: the machine drawn by
// the independent generator (bench/independent_machine.hpp), the effect added as the change it
// makes to the triggers in rotacal's exact simulator (the triggers with the effect minus the same
// location errors' triggers without it). Superposition: the cross terms are second order
// (micrometres of effect times the declared milliradians of set-up and squareness). The
// acceptance benches and tests use it to ask whether a catalogued effect is still found on such a
// machine; the machine's part shares no code with what it tests, the effect's part is the
// simulator the clean-world tests already hide effects with.
#include <functional>
#include <vector>

#include "bench/independent_machine.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"

namespace rotacal::independent {

/// `repeats` runs of `plan` on `drawn`, run r starting at r x cycle_s (new per-touch draws, the
/// same machine), with `effect` applied to a truth holding the drawn location errors. The touches'
/// times are the simulator's (the effect may depend on them). Throws std::logic_error when the
/// generator's and the simulator's touches are not in the same order.
std::vector<MeasurementRun> measureWithEffect(const ProbePlan& plan, const Machine& drawn,
                                              const std::function<void(Truth*)>& effect, int repeats, double cycle_s);

}  // namespace rotacal::independent
