// The space-frame plan (003) through every dialect: each program passes its strict checker,
// each results file round-trips to the same analysis, and LinuxCNC's own interpreter (rs274)
// runs the LinuxCNC program, one probe per plan touch.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "cycles/cycle.hpp"
#include "controllers/dialect.hpp"
#include "core/simulation.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "controllers/ctl_test_util.hpp"
#include "postproc/probe_program.hpp"
#include "rs274_run.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;

ProbePlan spaceframePlan(const CycleOptions& o = {}) {
  return makePlan("spaceframe", loadMachine(std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/ac_trunnion_a120.json"), o);
}

TEST(SpaceframeDialects, EveryProgramPassesItsCheckerAndResultsRoundTrip) {
  const ProbePlan plan = spaceframePlan({{"theta_list", "0,90,180,270"}, {"phi_list", "-90,0,90"}});
  Truth truth;
  truth.errors.kinematics = Kinematics::TableAC;
  const double table4_mean[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};  // 000 Table 4, um and mdeg
  for (int i = 0; i < 8; ++i) truth.errors.setReportValue(i, table4_mean[i]);
  const MeasurementRun run = simulate(plan, truth, {1});
  const SpaceframeAnalysis ref = analyzeSpaceframe(plan, {run});
  for (const std::string& name : dialectNames()) {
    const Dialect& d = dialectByName(name);
    if (std::string(name) != "csv") {
      const std::string text = d.writeProgram(test::cycleProgram(plan, name));
      const auto problems = d.check(text, plan, test::shapeOf(plan, std::string(d.name())));
      EXPECT_TRUE(problems.empty()) << name << ": " << (problems.empty() ? "" : problems.front());
    }
    const MeasurementRun back = d.parseResults(d.writeResults(plan, run), "results", plan);
    ASSERT_EQ(back.points.size(), run.points.size()) << name;
    const SpaceframeAnalysis a = analyzeSpaceframe(plan, {back});
    // Results files carry 4 decimals of mm (0.05 um rounding): the location errors agree to 0.1 um / mdeg.
    for (int i = 0; i < kNumLocationErrors; ++i)
      EXPECT_NEAR(a.model.errors.reportValue(i), ref.model.errors.reportValue(i), 0.1) << name << " parameter " << i;
  }
}

using test::kRs274;

TEST(SpaceframeRs274, TheFullMapRunsInLinuxCncsInterpreter) {
  if (!fs::exists(kRs274)) GTEST_SKIP() << kRs274 << " not found";
  const ProbePlan plan = spaceframePlan();
  const std::string program = std::regex_replace(
      dialectByName("linuxcnc").writeProgram(test::cycleProgram(plan, "linuxcnc")), std::regex("#5070"), "1");  // probe trips
  const test::Rs274Run r = test::runRs274(program);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(std::regex_replace(r.err, std::regex(R"(executing|\s)"), ""), "") << r.err;
  const std::string& o = r.out;
  size_t probes = 0;
  for (size_t p = o.find("STRAIGHT_PROBE("); p != std::string::npos; p = o.find("STRAIGHT_PROBE(", p + 1)) ++probes;
  EXPECT_EQ(probes, plan.points.size());
  EXPECT_NE(o.find("PROGRAM_END()"), std::string::npos);
}

}  // namespace
}  // namespace rotacal
