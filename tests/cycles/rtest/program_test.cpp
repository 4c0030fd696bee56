// The R-test program (002): LinuxCNC text through the strict checker and LinuxCNC's own
// interpreter (rs274 -g; skipped when not installed), the thermal schedule's loops counted in
// what the interpreter executes; the dialects that cannot spell it refuse it.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rs274_run.hpp"
#include "test_util.hpp"
#include "cycles/cycle.hpp"
#include "controllers/dialect.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/rtest/program.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;

using test::kRs274;

ProbePlan plan(const CycleOptions& o) {
  return makePlan("rtest", loadMachine(std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/bc_trunnion.json"), o);
}

size_t count(const std::string& text, const std::string& what) { return test::countOf(text, what); }

std::string run(const std::string& program, int* exit_code) {
  const test::Rs274Run r = test::runRs274(program);
  *exit_code = r.exit_code;
  return r.out;
}

TEST(RtestProgram, LinuxCncPassesCheckerAndRs274WithTheThermalLoops) {
  // A short thermal schedule so that rs274 runs it in a moment: a cycle every 4 min for 0.4 h.
  const ProbePlan p = plan({{"thermal", "1"}, {"interval_min", "4"}, {"duration_h", "0.4"}});
  const RtestSchedule s = rtestSchedule(p);
  ASSERT_EQ(s.cycles(), 7);  // 24 min / 4 min + 1
  const int recips = rtestReciprocations(p);
  ASSERT_GT(recips, 0);
  const Dialect& d = dialectByName("linuxcnc");
  const std::string text = d.writeProgram(test::cycleProgram(p, "linuxcnc"));
  const auto problems = d.check(text, p, test::shapeOf(p, "linuxcnc"));
  EXPECT_TRUE(problems.empty()) << problems.front();
  // The first cycle and the loop body's cycle, each: the reset (pose 0), 25 poses, the re-read.
  EXPECT_EQ(count(text, "M64 P0"), 54u);
  EXPECT_EQ(count(text, "R-test reset reading"), 2u);
  EXPECT_EQ(count(text, "R-test re-read of the reset"), 2u);
  // In each cycle the reset comes before the first pose's reading and the re-read after the last.
  EXPECT_LT(text.find("R-test reset reading"), text.find("R-test reading pose 1 "));
  EXPECT_GT(text.find("R-test re-read of the reset"), text.find("R-test reading pose 25 "));
  EXPECT_LT(text.find("R-test re-read of the reset"), text.find("warm-up"));
  if (!fs::exists(kRs274)) GTEST_SKIP() << "rs274 not installed";
  int rc = -1;
  const std::string out = run(text, &rc);
  EXPECT_EQ(rc, 0);
  // What the interpreter executes: one trigger per pose per cycle, a dwell before each, and the
  // reciprocation (two feed moves of B per round trip) between the cycles.
  EXPECT_EQ(count(out, "SET_AUX_OUTPUT_BIT(0)"), 27u * 7u);
  EXPECT_EQ(count(out, "DWELL(2.0000)"), 27u * 7u);
  EXPECT_EQ(count(out, "PROGRAM_END()"), 1u);
  // The reciprocation moves: B at +60 / +90 (controller sign -1 for linuxcnc on this machine),
  // executed as STRAIGHT_FEEDs; each round trip ends at the -90 deg (paper) end.
  size_t b90 = 0;
  std::istringstream in(out);
  for (std::string l; std::getline(in, l);)
    if (l.find("STRAIGHT_FEED(") != std::string::npos && l.find(", 90.0000,") != std::string::npos) ++b90;
  EXPECT_EQ(b90, static_cast<size_t>(recips) * 6u);
}

TEST(RtestProgram, CheckerRejectsAReadingWithoutDwellAndTheWrongCount) {
  const ProbePlan p = plan({});
  const Dialect& d = dialectByName("linuxcnc");
  std::string text = d.writeProgram(test::cycleProgram(p, "linuxcnc"));
  ASSERT_TRUE(d.check(text, p, test::shapeOf(p, "linuxcnc")).empty());
  std::string no_dwell = text;
  no_dwell.replace(no_dwell.find("G4 P2.000"), 9, "G0 Z263.2670");
  EXPECT_FALSE(d.check(no_dwell, p, test::shapeOf(p, "linuxcnc")).empty());
  std::string missing = text;
  const size_t at = missing.find("M64 P0\n");
  missing.erase(at, 7);
  EXPECT_FALSE(d.check(missing, p, test::shapeOf(p, "linuxcnc")).empty());
  // The re-read removed: the count is the neutral program's (27 per written cycle; the old
  // "multiple of the plan's poses" rule would refuse every program with reset reads).
  std::string no_reread = text;
  const size_t rr = no_reread.find("M64 P0\n", no_reread.find("R-test re-read of the reset"));
  no_reread.erase(rr, 7);
  EXPECT_FALSE(d.check(no_reread, p, test::shapeOf(p, "linuxcnc")).empty());
  // A plan written before the reset reads (no option) keeps 25 readings per cycle.
  ProbePlan old = p;
  old.options.erase("reset_reads");
  const std::string old_text = d.writeProgram(test::cycleProgram(old, "linuxcnc"));
  EXPECT_EQ(count(old_text, "M64 P0"), 25u);
  EXPECT_TRUE(d.check(old_text, old, test::shapeOf(old, "linuxcnc")).empty());
}

TEST(RtestProgram, DialectsWithoutLoopsRefuse) {
  const ProbePlan p = plan({});
  for (const char* name : {"fanuc", "haas", "siemens", "heidenhain", "okuma"})
    EXPECT_THROW(dialectByName(name).writeProgram(test::cycleProgram(p, name)), std::invalid_argument) << name;
}

}  // namespace
}  // namespace rotacal
