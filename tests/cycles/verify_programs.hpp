#pragma once
// Every touch dialect's program of a plan through the program verifier (postproc/program_check):
// no violation, and every touch of the plan a probing move the verifier saw reach its surface.
#include <gtest/gtest.h>

#include <string>

#include "controllers/common.hpp"
#include "controllers/dialect.hpp"
#include "controllers/motion_reader.hpp"
#include "cycles/check_rules.hpp"
#include "cycles/cycle.hpp"
#include "postproc/program_check.hpp"

namespace rotacal::test {

/// The number of programs written (each dialect's).
inline int expectEveryDialectProgramPasses(const ProbePlan& plan) {
  const Cycle& cycle = cycleOfPlan(plan);
  int written = 0;
  for (const std::string d : {"linuxcnc", "fanuc", "haas", "siemens", "heidenhain", "okuma"}) {
    const std::string text = dialectByName(d).writeProgram(cycle.program(plan, d));
    const ProgramCheckSetup s = programCheckSetup(plan.machine, d, ctl::numbersPrograms(d), &plan, true);
    const ProgramCheckResult r = checkProgram(ctl::readMotions(d, text), s);
    EXPECT_TRUE(r.violations.empty()) << d << ": " << (r.violations.empty() ? "" : r.violations.front().problem);
    EXPECT_EQ(static_cast<size_t>(r.probing_moves), plan.points.size()) << d;
    ++written;
  }
  return written;
}

}  // namespace rotacal::test
