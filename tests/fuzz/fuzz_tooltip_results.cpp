// The tool-tip cycle's results (cycles/tooltip: parseTooltipResults) against the corpus's
// tooltip plan.
#include "cycles/tooltip/plan.hpp"
#include "tests/fuzz/fuzz_plans.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  static const PlanRules rules = [] {
    PlanRules r;
    r.heights = false;  // as cycles/tooltip/cycle.cpp states
    return r;
  }();
  const ProbePlan& plan = fuzz::basePlan("tooltip.plan.json", rules);
  const std::string file = "tooltip.csv";
  fuzz::expectInputErrorOnly(file, [&] { (void)parseTooltipResults(fuzz::asText(data, size), file, plan); });
  return 0;
}
