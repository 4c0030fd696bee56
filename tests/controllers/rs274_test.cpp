// The generated LinuxCNC program through LinuxCNC's own interpreter (rs274 -g, Debian package
// linuxcnc-uspace). rs274's stand-alone canon never trips the probe (#5070 = 0, position = end
// point), so: the unmodified program must stop at the first probe with rotacal's ABORT and no
// other error; a copy with every #5070 replaced by 1 (a probe that trips) must run to the end,
// probe once per plan point, and its LOG lines must be a results file our parser accepts,
// holding the probe end points. Skipped when rs274 is not installed.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "cycles/cycle.hpp"
#include "controllers/dialect.hpp"
#include "ctl_test_util.hpp"
#include "postproc/probe_program.hpp"
#include "rs274_run.hpp"

namespace rotacal::test {
namespace {

namespace fs = std::filesystem;

size_t count(const std::string& text, const std::string& what) { return test::countOf(text, what); }

// rs274 logs the end point as the interpreter read it from the program (4 decimals, so exact
// to the printed value), through %.6f: half a unit of the 6th decimal, plus the program's own
// rounding of the plan's end point to 4 decimals.
constexpr double kEndPointTolMm = 0.5e-4 + 0.5e-6 + 1e-12;

class Rs274 : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kRs274)) GTEST_SKIP() << kRs274 << " not found: install linuxcnc-uspace to run this test";
  }
  ProbePlan plan = test::acPlan();
  std::string program = dialectByName("linuxcnc").writeProgram(test::cycleProgram(plan, "linuxcnc"));
};

TEST_F(Rs274, UntrippedProbeStopsAtTheFirstPointWithOurAbort) {
  const Rs274Run r = runRs274(program);
  EXPECT_EQ(count(r.out, "STRAIGHT_PROBE("), 1u) << r.out;
  EXPECT_EQ(count(r.out, "PROGRAM_END"), 0u);
  EXPECT_NE(r.err.find("(ABORT, rotacal: point 1 did not trigger)"), std::string::npos) << r.err;
  // Nothing else on stderr than rs274's "executing" banner and the abort message itself.
  std::string rest = std::regex_replace(r.err, std::regex(R"(executing|\(ABORT, rotacal: point 1 did not trigger\)|rotacal: point 1 did not trigger|\s)"), "");
  EXPECT_EQ(rest, "") << r.err;
  EXPECT_NE(r.exit_code, 0);
}

TEST_F(Rs274, TrippingProbeRunsToTheEndAndLogsAParsableResultsFile) {
  const std::string tripped = std::regex_replace(program, std::regex("#5070"), "1");
  const Rs274Run r = runRs274(tripped);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(std::regex_replace(r.err, std::regex(R"(executing|\s)"), ""), "") << r.err;
  EXPECT_EQ(count(r.out, "STRAIGHT_PROBE("), plan.points.size());
  EXPECT_EQ(count(r.out, "PROGRAM_END()"), 1u);
  EXPECT_EQ(count(r.out, "LOGOPEN(\"rotacal_touch154.txt\")"), 1u);
  EXPECT_EQ(count(r.out, "LOGCLOSE()"), 1u);
  // The canon LOG("...") calls are the lines LinuxCNC would write to the LOGOPEN file.
  std::string results;
  const std::regex log(R"re(LOG\("([^"]*)"\))re");
  for (auto it = std::sregex_iterator(r.out.begin(), r.out.end(), log); it != std::sregex_iterator(); ++it)
    results += (*it)[1].str() + "\n";
  const MeasurementRun run = dialectByName("linuxcnc").parseResults(results, "rs274_log.txt", plan);
  ASSERT_EQ(run.points.size(), plan.points.size());
  for (const auto& t : run.points) {
    const ProbePoint& p = *plan.findPoint(t.point_id);
    EXPECT_LE((t.position_m_mm - p.end_m(plan.machine.overtravel_mm)).cwiseAbs().maxCoeff(), kEndPointTolMm)
        << "point " << t.point_id;
  }
}

// The three-sphere cycle (001): 180 probing moves at 12 C angles, through the interpreter.
TEST(Rs274Spheres3, TrippingProbeRunsToTheEnd) {
  if (!fs::exists(kRs274)) GTEST_SKIP() << kRs274 << " not found: install linuxcnc-uspace to run this test";
  const ProbePlan plan = makePlan("spheres3", test::acTestMachine(), {});
  const std::string program = dialectByName("linuxcnc").writeProgram(test::cycleProgram(plan, "linuxcnc"));
  const Rs274Run r = runRs274(std::regex_replace(program, std::regex("#5070"), "1"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(std::regex_replace(r.err, std::regex(R"(executing|\s)"), ""), "") << r.err;
  EXPECT_EQ(count(r.out, "STRAIGHT_PROBE("), plan.points.size());
  EXPECT_EQ(count(r.out, "LOGOPEN(\"rotacal_spheres3.txt\")"), 1u);
  EXPECT_EQ(count(r.out, "PROGRAM_END()"), 1u);
}

}  // namespace
}  // namespace rotacal::test
