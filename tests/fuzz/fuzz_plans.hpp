#pragma once
// The plans the results harnesses read against: the valid plans of the bad-input corpus
// (tests/data/bad/base/), loaded once. scripts/fuzz.sh simulates its seed results on the same
// files.
#include <map>
#include <string>

#include "core/probe_plan.hpp"
#include "tests/fuzz/fuzz_common.hpp"

namespace rotacal::fuzz {

/// `rules`: the plan's cycle's (Cycle::planRules), e.g. no probing heights for tooltip.
inline const ProbePlan& basePlan(const std::string& file, const PlanRules& rules = {}) {
  static std::map<std::string, ProbePlan> plans;
  auto it = plans.find(file);
  if (it == plans.end()) it = plans.emplace(file, loadPlan(sourcePath("tests/data/bad/base/" + file), rules)).first;
  return it->second;
}

/// One input of a cycle's own results harness: the fuzzer's bytes read by `parse` (the cycle's
/// parser: text, file name, plan) as `cycle`.csv against the corpus's `cycle`.plan.json, loaded with
/// the cycle's `rules`; anything but an InputError is a finding.
template <class Parse>
int cycleResultsInput(const uint8_t* data, size_t size, const std::string& cycle, const PlanRules& rules, Parse parse) {
  const ProbePlan& plan = basePlan(cycle + ".plan.json", rules);
  const std::string file = cycle + ".csv";
  expectInputErrorOnly(file, [&] { (void)parse(asText(data, size), file, plan); });
  return 0;
}

}  // namespace rotacal::fuzz
