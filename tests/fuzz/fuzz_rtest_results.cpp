// The R-test logger's CSV (cycles/rtest: parseRtestResults) against the corpus's rtest plan.
#include "cycles/rtest/plan.hpp"
#include "tests/fuzz/fuzz_plans.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  PlanRules rules;
  rules.artefact_touched = false;  // as cycles/rtest/cycle.cpp states
  return fuzz::cycleResultsInput(data, size, "rtest", rules, parseRtestResults);
}
