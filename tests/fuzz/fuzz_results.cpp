// Every dialect's results parser (Dialect::parseResults) against a touch154 and a spheres3
// plan. The first byte picks the pair: plan index * (number of dialects) + dialect index, in the
// registry's order and the plans' below (scripts/fuzz.sh prefixes its seeds the same way).
#include "controllers/dialect.hpp"
#include "tests/fuzz/fuzz_plans.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  static const char* const kPlans[] = {"small.plan.json", "spheres3.plan.json"};
  if (size < 1) return 0;
  const size_t n = dialects().size();
  const Dialect& d = *dialects()[data[0] % n];
  const ProbePlan& plan = fuzz::basePlan(kPlans[(data[0] / n) % 2]);
  const std::string file = "results.txt";
  fuzz::expectInputErrorOnly(file, [&] { (void)d.parseResults(fuzz::asText(data + 1, size - 1), file, plan); });
  return 0;
}
