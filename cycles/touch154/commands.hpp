#pragma once
// The cycle's `uncertainty` and `design` verbs: the Monte Carlo of 000 Sec. 5 over its chain,
// and a plan for a probe budget compared with the full plan by the same Monte Carlo.
#include "cycles/cycle.hpp"

namespace rotacal {

CycleDocuments touch154Uncertainty(const UncertaintyRequest& request);
DesignedPlan touch154Design(const DesignRequest& request, const ProbePlan* full_plan);

}  // namespace rotacal
