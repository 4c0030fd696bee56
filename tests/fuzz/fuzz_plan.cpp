// PLAN.json loader (core/probe_plan.hpp: planFromJson) with the rules each cycle states
// (Cycle::planRules, cycles/*/cycle.cpp; the first byte picks the cycle). The harness links the
// cycles' option readers (touch154, rtest, tooltip, one_sphere, probe_qual plan.cpp) rather than the whole registry, whose
// analysis code takes most of the sanitizer build: keep the rules below as the cycles state them.
#include "cycles/one_sphere/plan.hpp"
#include "cycles/probe_qual/plan.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/tooltip/plan.hpp"
#include "cycles/touch154/plan.hpp"
#include "tests/fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rotacal;
  if (size < 1) return 0;
  PlanRules rules;
  switch (data[0] % 7) {
    case 0:  // touch154
      rules.check_options = [](const ProbePlan& p) {
        if (p.cycle == "touch154") (void)Touch154Layout::fromOptions(p.options);
      };
      break;
    case 1: rules.spheres = 3; break;  // spheres3
    case 2:                            // rtest
      rules.artefact_touched = false;
      rules.check_options = rtestCheckPlanOptions;
      break;
    case 3:  // tooltip
      rules.heights = false;
      rules.check_options = [](const ProbePlan& p) { (void)tooltipOptionsFrom(p.options, p.machine); };
      break;
    case 5:  // one_sphere
      rules.spheres = 1;
      rules.check_options = [](const ProbePlan& p) { (void)sphereLayoutOf(p); };
      break;
    case 6:  // probe_qual
      rules.spheres = 1;
      rules.safe_height_over_artefact = false;
      rules.check_options = [](const ProbePlan& p) { (void)probeQualLayoutOf(p); };
      break;
    default: break;  // spaceframe: the defaults
  }
  const std::string file = "plan.json";
  fuzz::expectInputErrorOnly(file, [&] {
    const JsonDoc doc = parseJsonText(fuzz::asText(data + 1, size - 1), file);
    (void)planFromJson(doc, rules);
  });
  return 0;
}
