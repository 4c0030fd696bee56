// The tool-tip cycle's results (cycles/tooltip: parseTooltipResults) against the corpus's
// tooltip plan.
#include "cycles/tooltip/plan.hpp"
#include "tests/fuzz/fuzz_plans.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  PlanRules rules;
  rules.heights = false;  // as cycles/tooltip/cycle.cpp states
  return fuzz::cycleResultsInput(data, size, "tooltip", rules, parseTooltipResults);
}
