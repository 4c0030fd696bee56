#pragma once
// Every touch dialect's program of a plan through the program verifier (postproc/program_check):
// no violation, and every touch of the plan a probing move the verifier saw reach its surface.
#include <gtest/gtest.h>

#include <string>

#include "controllers/dialect.hpp"
#include "controllers/motion_reader.hpp"
#include "cycles/check_rules.hpp"
#include "cycles/cycle.hpp"
#include "postproc/program_check.hpp"
#include "dialect_lists.hpp"

namespace rotacal::test {

/// The number of programs written (each dialect's). `refused`: a dialect that must refuse the
/// plan instead (with a reason containing the given text).
inline int expectEveryDialectProgramPasses(const ProbePlan& plan, const std::string& refused = "",
                                           const std::string& reason = "") {
  const Cycle& cycle = cycleOfPlan(plan);
  int written = 0;
  for (const std::string& d : test::programDialects()) {
    if (d == refused) {
      try {
        (void)dialectByName(d).writeProgram(cycle.program(plan, d));
        ADD_FAILURE() << d << " wrote a program it should refuse (" << reason << ")";
      } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << d << ": " << e.what();
      }
      continue;
    }
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
