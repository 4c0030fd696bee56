#pragma once
// A hidden effect on top of an R-test machine as its contributors file declares it: the machine
// drawn by the independent generator (bench/independent_rtest.hpp: 002's B/C table, the nest's
// three sensors, the sphere's offset, the per-cycle drift, the linear axes), the effect added as
// the change it makes to the readings in rotacal's R-test simulator (simulateRtest, what
// `rotacal simulate` runs for rtest): the readings with the effect minus the same machine's
// readings without it. Superposition: the cross terms are second order (micrometres of effect
// times the declared 0.1 % of sensor gain, 2 mrad of sensor direction, tens of mdeg of location
// errors). The machine's part shares no code with what it tests; the effect's part is the
// simulator the clean-world tests already hide effects with.
#include <functional>
#include <vector>

#include "bench/independent_rtest.hpp"
#include "core/contributors.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "cycles/rtest/diagnose.hpp"
#include "cycles/rtest/plan.hpp"

namespace rotacal::independent {

/// A change of the simulator's truth: the table's errors (Truth: drift, pose_dependent) or what
/// the R-test adds (RtestTruthExtras: sensor steps, the sphere's drift).
using RtestEffect = std::function<void(Truth*, RtestTruthExtras*)>;

/// The plan's whole series measured on `drawn` (measureRtest) with `effect` added: per reading the
/// simulator's readings with the effect minus without it, both on a truth holding the drawn
/// location errors and sphere offset, noise-free, on the same clock (cycle k at k x the
/// schedule's interval). Throws std::logic_error when the generator's and the simulator's
/// readings are not the same readings (pose, time).
RtestSeries measureRtestWithEffect(const ProbePlan& plan, const RtestMachine& drawn, const RtestEffect& effect);

/// The diagnosis as `rotacal diagnose` runs it (cycles/rtest/cycle.cpp): the declared per-reading
/// scatter (sensors, sphere form) and the structured part taken about the first cycle's
/// readings, from `declared`, at family-wise `alpha`.
RtestDiagnosis diagnoseAsDeclared(const ProbePlan& plan, const ContributorSet& declared,
                                  const std::vector<RtestCycle>& cycles, double alpha);

/// The sphere's drift the generator drew, as the rate (um/h, machine frame) the judge's
/// thermal_drift family reads it as: a sphere moving by v reads as the table's dx_BY, dy_CB, dz_BY
/// moving by -v at every tilt (the B/C table's translations are in the machine frame).
Eigen::Vector3d drawnSphereDriftUmPerH(const RtestMachine& drawn);

/// rotacal_diagnose_bench rtest_drawn: the rtest catalog on drawn machines, printed
/// (docs/diagnosis.md).
void rtestDrawnBench(int clean_seeds, int effect_seeds);

}  // namespace rotacal::independent
