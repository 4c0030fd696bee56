#pragma once
// The uncertainty `analyze` signs for touch154 (core/uncertainty_budget.hpp): u_A
// from the data, u_B from the declared contributors propagated by the linearised Monte Carlo of
// cycles/touch154/uncertainty.hpp through the estimator that made the estimate, around the
// identified location errors.
#include <cstdint>
#include <vector>

#include "core/contributors.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/probe_plan.hpp"
#include "core/uncertainty_budget.hpp"

namespace rotacal {

struct Touch154BudgetOptions : BudgetOptions {
  // Its budget table's shares from 500 runs each (the touch154 default).
  Touch154BudgetOptions() { alone_runs = 500; }
};

/// The budget of `main` (identified from `per_run.size()` repeats, or one run when per_run is
/// empty). `contributors` null: Type B is not evaluated and the budget says so.
UncertaintyBudget touch154Budget(const ProbePlan& plan, const IdentificationResult& main,
                                 const std::vector<IdentificationResult>& per_run, const ContributorSet* contributors,
                                 const Touch154BudgetOptions& options);

/// The contributors Type A already measures: they act independently at every touch, so the
/// residual shows them (repeatability, surface roughness). Type B leaves them out.
bool measuredByTypeA(const ContributorInfo& contributor);

}  // namespace rotacal
