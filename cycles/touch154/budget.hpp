#pragma once
// The uncertainty `analyze` signs for touch154 (issue 17; core/uncertainty_budget.hpp): u_A
// from the data, u_B from the declared contributors propagated by the linearised Monte Carlo of
// cycles/touch154/uncertainty.hpp through the estimator that made the estimate, around the
// identified location errors.
#include <cstdint>
#include <vector>

#include "core/contributors.hpp"
#include "core/identification.hpp"
#include "core/probe_plan.hpp"
#include "core/uncertainty_budget.hpp"

namespace rotacal {

struct Touch154BudgetOptions {
  int runs = 2000;        // Monte Carlo runs with every contributor
  int alone_runs = 500;   // runs of each contributor alone (the budget table)
  std::uint64_t seed = 1;
  int threads = 0;        // 0: all cores
  bool validate(std::string* why) const;
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
