#pragma once
// REPORT.json (contract) and the readable summary of an analysis.
#include <string>
#include <vector>

#include "cycles/touch154/closed_form.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/json_io.hpp"
#include "core/report_envelope.hpp"
#include "core/uncertainty_budget.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct Analysis {
  const ProbePlan* plan = nullptr;
  std::vector<std::string> result_files;
  IdentificationResult main;                  // all runs together
  std::vector<IdentificationResult> per_run;  // each repeat alone (000 Table 4 columns)
  std::vector<IdentificationResult> other_methods;  // the same data by the other estimators
  std::vector<PatternEquation> patterns;      // closed form, first run (000's plan)
  UncertaintyBudget budget;                   // what the report signs (cycles/touch154/budget.hpp)
};

Json analysisToJson(const Analysis& analysis);
std::string analysisText(const Analysis& analysis);

}  // namespace rotacal
