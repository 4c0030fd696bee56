// PLAN.json loader (core/probe_plan.hpp: planFromJson) with the rules each cycle states
// (Cycle::planRules, from each cycle's plan.cpp; the first byte picks the cycle). The harness links
// the cycles' plan.cpp rather than the whole registry, whose analysis code takes most of the
// sanitizer build.
#include "cycles/one_sphere/plan.hpp"
#include "cycles/probe_qual/plan.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/spheres3/plan.hpp"
#include "cycles/tooltip/plan.hpp"
#include "cycles/touch154/plan.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  if (size < 1) return 0;
  // The cycles' own rules (each cycle's plan.cpp states them; spaceframe has the defaults).
  static const PlanRules rules[7] = {touch154PlanRules(), spheres3PlanRules(), rtestPlanRules(), tooltipPlanRules(),
                                     PlanRules{},         spherePlanRules(),   probeQualPlanRules()};
  const PlanRules& rule = rules[data[0] % 7];
  const std::string file = "plan.json";
  fuzz::expectInputErrorOnly(file, [&] {
    const JsonDoc doc = parseJsonText(fuzz::asText(data + 1, size - 1), file);
    (void)planFromJson(doc, rule);
  });
  return 0;
}
