#pragma once
// What the one-sphere model gets wrong: the shared judge (core/judge.hpp) on the fit's residual,
// against the declared noise (the machine's contributors), with the causes a sphere cycle can show:
//  - thermal_drift: the sphere (or the spindle) moving linearly in time in X, Y, Z over the cycle;
//  - pretravel_by_direction: the probe's trigger distance differing between its approach
//    directions (lobing), beyond the one effective radius the model fits.
// Leave one pose out for the held-out test. Confounding comes from the Jacobians of this plan.
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/json_io.hpp"
#include "core/judge.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "cycles/judge_contract.hpp"

namespace rotacal {

using SphereDiagnosis = JudgedFit;

/// `declared`: the contributors the judge's noise is declared by (sphereDeclaredNoise: the
/// per-touch scatter and the shared part of the pretravel and linear axes); null: the probe's
/// repeatability alone.
SphereDiagnosis diagnoseSphere(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const JudgeOptions& options,
                               const ContributorSet* declared = nullptr);

}  // namespace rotacal
