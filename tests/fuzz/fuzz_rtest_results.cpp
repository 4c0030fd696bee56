// The R-test logger's CSV (cycles/rtest: parseRtestResults) against the corpus's rtest plan.
#include "cycles/rtest/plan.hpp"
#include "tests/fuzz/fuzz_plans.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  static const PlanRules rules = [] {
    PlanRules r;
    r.artefact_touched = false;  // as cycles/rtest/cycle.cpp states
    return r;
  }();
  const ProbePlan& plan = fuzz::basePlan("rtest.plan.json", rules);
  const std::string file = "rtest.csv";
  fuzz::expectInputErrorOnly(file, [&] { (void)parseRtestResults(fuzz::asText(data, size), file, plan); });
  return 0;
}
