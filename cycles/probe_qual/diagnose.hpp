#pragma once
// What the probe's qualification gets wrong: the shared judge (core/judge.hpp) on the touches'
// scatter about each direction's mean, against the machine's declared noise (the probe's
// repeatability, or the contributors' per-touch scatter and shared linear-axis errors: is it what
// the data show?), with the one cause a qualification can show beyond it:
//  - thermal_drift: the sphere (or the spindle) moving linearly in time in X, Y, Z over the
//    cycle; the directions repeat in the same order, so a drift follows the clock.
// Leave one repeat out for the held-out test.
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/json_io.hpp"
#include "core/judge.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "cycles/judge_contract.hpp"

namespace rotacal {

using ProbeQualDiagnosis = JudgedFit;

/// `declared`: the contributors the judge's noise is declared by: the per-touch scatter
/// (perTouchDeclaration) and, shared between touches, the linear axes and the pretravel to first
/// order (probeAxesCovariance at the plan's nominal triggers); null: the probe's repeatability
/// alone. Throws std::invalid_argument when the two repeatabilities contradict each other.
ProbeQualDiagnosis diagnoseProbeQual(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const JudgeOptions& options, const ContributorSet* declared = nullptr);

}  // namespace rotacal
