#pragma once
// Shared helpers for rotacal's tests: the bundled machine, the Table 4 truth, and one matrix
// comparison that prints the difference.
#include <gtest/gtest.h>

#include <string>

#include "cycles/cycle.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"

namespace rotacal::test {

inline std::string sourcePath(const std::string& rel) { return std::string(ROTACAL_SOURCE_DIR) + "/" + rel; }

inline MachineModel acMachine() { return loadMachine(sourcePath("examples/machines/ac_trunnion.json")); }
inline ProbePlan touch154Plan() { return makePlan("touch154", acMachine(), {}); }

/// A plan's program as `generate` builds it: by the plan's cycle, with its program number.
inline nc::Program cycleProgram(const ProbePlan& plan, const std::string& dialect) {
  return cycleOfPlan(plan).program(plan, dialect);
}
/// What the checkers hold a text written from that program to.
inline nc::Shape shapeOf(const ProbePlan& plan, const std::string& dialect) {
  return nc::shapeOf(cycleProgram(plan, dialect));
}

/// 000 Table 4, mean column: um and mdeg.
inline LocationErrors table4Mean() {
  LocationErrors e;
  e.kinematics = Kinematics::TableAC;
  const double v[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};
  for (int i = 0; i < 8; ++i) e.setReportValue(i, v[i]);
  return e;
}

inline Truth truthWith(const LocationErrors& e) {
  Truth t;
  t.errors = e;
  return t;
}

}  // namespace rotacal::test
