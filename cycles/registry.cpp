// The only list of cycles. A new cycle is a folder cycles/<name>/ whose cycle.cpp defines
// `const Cycle& <name>Cycle()`, plus one line here.
#include <stdexcept>
#include <string>

#include "cycles/cycle.hpp"

#define ROTACAL_CYCLES(X) \
  X(touch154)             \
  X(spheres3)             \
  X(rtest)                \
  X(spaceframe)           \
  X(tooltip)

namespace rotacal {

#define ROTACAL_DECLARE_CYCLE(n) const Cycle& n##Cycle();
ROTACAL_CYCLES(ROTACAL_DECLARE_CYCLE)
#undef ROTACAL_DECLARE_CYCLE

const std::vector<const Cycle*>& cycles() {
#define ROTACAL_LIST_CYCLE(n) &n##Cycle(),
  static const std::vector<const Cycle*> all{ROTACAL_CYCLES(ROTACAL_LIST_CYCLE)};
#undef ROTACAL_LIST_CYCLE
  return all;
}

std::vector<std::string> cycleNames() {
  std::vector<std::string> names;
  for (const Cycle* c : cycles()) names.emplace_back(c->name());
  return names;
}

namespace {

std::string namesList() {
  std::string s;
  for (const auto& n : cycleNames()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace

const Cycle& cycleByName(std::string_view name) {
  for (const Cycle* c : cycles())
    if (c->name() == name) return *c;
  throw std::invalid_argument("unknown cycle '" + std::string(name) + "' (known: " + namesList() + ")");
}

const Cycle& cycleOfPlan(const ProbePlan& plan) {
  for (const Cycle* c : cycles()) {
    if (c->name() == plan.cycle) return *c;
    for (const auto& a : c->aliases())
      if (a == plan.cycle) return *c;
  }
  throw std::invalid_argument("the plan's cycle '" + plan.cycle + "' is not one rotacal knows (" + namesList() + ")");
}

ProbePlan makePlan(const std::string& cycle, const MachineModel& machine, const CycleOptions& options) {
  return cycleByName(cycle).plan(machine, options);
}

}  // namespace rotacal
