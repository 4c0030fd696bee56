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

}  // namespace rotacal::fuzz
