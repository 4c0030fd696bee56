// The only list of cycles. A new cycle is a folder cycles/<name>/ whose cycle.cpp defines
// `const Cycle& <name>Cycle()`, plus one line here.
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "core/limits.hpp"
#include "cycles/check_rules.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"

#define ROTACAL_CYCLES(X) \
  X(touch154)             \
  X(spheres3)             \
  X(rtest)                \
  X(spaceframe)           \
  X(tooltip)              \
  X(one_sphere)           \
  X(probe_qual)

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

ProgramCheckSetup programCheckSetup(const MachineModel& machine, const std::string& dialect, bool numbered,
                                    const ProbePlan* plan, bool any_rotacal_number) {
  ProgramCheckSetup s;
  s.machine = &machine;
  s.dialect = dialect;
  s.plan = plan;
  s.numbered = numbered;
  if (plan) {
    const Cycle& cycle = cycleOfPlan(*plan);
    s.artefact_on_table = cycle.planRules().artefact_touched;
    if (s.numbered) s.program_number = cycle.programNumber();
  } else if (any_rotacal_number) {
    for (const Cycle* c : cycles()) s.rotacal_numbers.push_back(c->programNumber());
  }
  return s;
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

nc::Program Cycle::program(const ProbePlan& plan, const std::string& dialect) const {
  nc::Program p = identity_.build_program(plan, dialect);
  p.number = programNumber();
  return p;
}

Simulated Cycle::simulate(const SimulateRequest& request) const { return simulateProbing(request); }

CycleDocuments Cycle::uncertainty(const UncertaintyRequest&) const {
  throw std::invalid_argument(fmt::format("cycle {} has no Monte Carlo of its calibration chain", name()));
}

DesignedPlan Cycle::design(const DesignRequest&) const {
  throw std::invalid_argument(fmt::format("cycle {} designs no plans", name()));
}

ProbePlan makePlan(const std::string& cycle, const MachineModel& machine, const CycleOptions& options) {
  ProbePlan plan = cycleByName(cycle).plan(machine, options);
  // Each cycle checks its own options before building; this holds whatever they missed to the
  // limits the plan loader enforces, so that a plan written is a plan that loads.
  requirePlanSize("cycle " + cycle, static_cast<double>(plan.points.size()), static_cast<double>(plan.poses.size()));
  // Likewise the planned times (dwells and move times are options): the loader takes t_s up to
  // the controllers' clock.
  for (const auto& p : plan.points)
    if (!(p.t_s >= 0 && p.t_s <= kMaxClockSeconds))
      throw std::invalid_argument(fmt::format("cycle {}: point {} would be reached after {:g} s; a plan may last at most "
                                              "{:g} s (check the time options: dwell_s, move_s, ...)",
                                              cycle, p.id, p.t_s, kMaxClockSeconds));
  return plan;
}

ProbePlan loadCyclePlan(const std::string& path) { return cyclePlanFromJson(readJsonFile(path)); }

ProbePlan cyclePlanFromJson(const JsonDoc& doc) {
  PlanRules rules;
  if (doc.value.is_object() && doc.value.contains("cycle") && doc.value["cycle"].is_string()) {
    ProbePlan named;
    named.cycle = doc.value["cycle"].get<std::string>();
    const Cycle* cycle = nullptr;
    try {
      cycle = &cycleOfPlan(named);
    } catch (const std::invalid_argument& e) {
      // A plan of a cycle this rotacal does not know: named at its "cycle" (after the format).
      if (doc.value.contains("format") && doc.value["format"] == "rotacal-plan/1") doc.fail(doc.value, "cycle", e.what());
    }
    if (cycle) rules = cycle->planRules();
  }
  return planFromJson(doc, rules);
}

}  // namespace rotacal
