#pragma once
// The one-sphere cycle's uncertainty budget (core/uncertainty_budget.hpp's rules):
//  - u_A: the per-touch scatter by the shared rule (readingScatter; declared: the contributors'
//    per-touch part, repeatability and roughness, else the machine's probe repeatability) through
//    the fit's covariance;
//  - u_B: the declared probe and linear-axis contributors (pretravel by direction, scale,
//    random, squareness: drawProbeAxes) drawn on the exact simulator (full HTMs, exact
//    ball-on-sphere contact) around the identified errors, the triggers' deviations run through
//    the fit linearised at its solution (runTypeB, the Monte Carlo every cycle shares).
// The sphere's set-up is fitted, so a set-up contributor does not act; others are listed as left out.
#include "core/contributors.hpp"
#include "core/uncertainty_budget.hpp"
#include "cycles/one_sphere/analyze.hpp"

namespace rotacal {

UncertaintyBudget sphereBudget(const ProbePlan& plan, const SphereCycleResult& r, const ContributorSet* contributors,
                               const BudgetOptions& options);

}  // namespace rotacal
