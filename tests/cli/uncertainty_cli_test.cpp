// `rotacal uncertainty` and `rotacal design` end to end: the contract's OUT.json, the flags, the
// exit codes, and a designed plan that the other commands accept. The figures themselves are
// checked against independent computations in tests/core/uncertainty_test.cpp; here only what
// the command line adds.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "test_util.hpp"

namespace rotacal::test {
namespace {

using Run = test::CliRun;

class UncertaintyCli : public AcTrunnionTest {
 protected:
  void SetUp() override {
    ScratchTest::SetUp();
    contrib = test::sourcePath("examples/contributors/table5.json");
    ASSERT_EQ(sh("plan --cycle touch154 --machine " + machine + " -o " + p("plan.json")).code, 0);
  }
  std::string contrib;
};

TEST_F(UncertaintyCli, WritesTheContractsOutJson) {
  const auto r = sh("uncertainty --plan " + p("plan.json") + " --contributors " + contrib + " --runs 1000 --seed 7 --json " +
                    p("out.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = loadJson(p("out.json"));
  EXPECT_EQ(j["format"], "rotacal-uncertainty/1");
  EXPECT_EQ(j["runs"], 1000);
  EXPECT_EQ(j["seed"], 7);
  for (const char* m : {"closed_form", "least_squares"}) {
    const auto& method = j["methods"][m];
    EXPECT_EQ(method["combined"]["dx_AY"]["unit"], "um") << m;
    EXPECT_EQ(method["combined"]["b_CA"]["unit"], "mdeg") << m;
    EXPECT_GT(method["combined"]["dy_AY"]["u"].get<double>(), 0.0) << m;
    // Every contributor of the file has its row, every row all eight parameters.
    EXPECT_EQ(method["contributors"].size(), 21u) << m;
    EXPECT_EQ(method["contributors"]["S_yz"].size(), 8u) << m;
  }
  // 000 Table 5's S_yz on dy_AY (5.5 um) through the command line, within 15 %.
  EXPECT_NEAR(j["methods"]["closed_form"]["contributors"]["S_yz"]["dy_AY"]["u"].get<double>() / 5.5, 1.0, 0.15);
  // The text names the reference beside the figures.
  EXPECT_NE(r.out.find("000 Table 6"), std::string::npos);
}

TEST_F(UncertaintyCli, SeededRunsAreReproducibleAndCombinedOnlyDropsTheTable) {
  const std::string base = "uncertainty --plan " + p("plan.json") + " --contributors " + contrib + " --runs 300 --seed 3";
  ASSERT_EQ(sh(base + " --threads 1 --json " + p("a.json")).code, 0);
  ASSERT_EQ(sh(base + " --threads 2 --json " + p("b.json")).code, 0);
  ASSERT_EQ(sh(base + " --combined-only --methods closed_form --json " + p("c.json")).code, 0);
  const auto a = loadJson(p("a.json")), b = loadJson(p("b.json")), c = loadJson(p("c.json"));
  EXPECT_EQ(a["methods"], b["methods"]);  // bit-identical whatever the thread count
  EXPECT_FALSE(c["methods"]["closed_form"].contains("contributors"));
  EXPECT_FALSE(c["methods"].contains("least_squares"));
  // The same runs: --combined-only sums the contributors in another order (rounding only).
  for (const auto& [name, e] : a["methods"]["closed_form"]["combined"].items())
    EXPECT_NEAR(c["methods"]["closed_form"]["combined"][name]["u"].get<double>(), e["u"].get<double>(),
                1e-12 * e["u"].get<double>())
        << name;
}

TEST_F(UncertaintyCli, BadInputAndUsage) {
  const std::string base = "uncertainty --plan " + p("plan.json") + " --json " + p("o.json");
  EXPECT_EQ(sh(base + " --contributors " + contrib + " --runs 1").code, 2);
  EXPECT_EQ(sh(base + " --contributors " + contrib + " --runs 10 --methods closed").code, 2);
  std::ofstream(p("bad.json")) << "{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"S_xy\": {\"u\": 3}}}\n";
  const auto r = sh(base + " --contributors " + p("bad.json") + " --runs 10");
  EXPECT_TRUE(refused(r, 1, "rotacal: error: " + p("bad.json") + ":3: 'S_xy' lacks its unit", p("o.json")));
  EXPECT_EQ(sh(base + " --contributors " + p("missing.json") + " --runs 10").code, 1);
}

TEST_F(UncertaintyCli, DesignedPlanFeedsTheOtherCommands) {
  const auto d = sh("design --machine " + machine + " --contributors " + contrib + " --points 40 --runs 200 -o " +
                    p("designed.json") + " --json " + p("design.json"));
  ASSERT_EQ(d.code, 0) << d.out;
  const auto plan = loadJson(p("designed.json"));
  EXPECT_EQ(plan["format"], "rotacal-plan/1");
  EXPECT_LE(plan["points"].size(), 40u);
  const auto design = loadJson(p("design.json"));
  EXPECT_EQ(design["format"], "rotacal-design/1");
  EXPECT_EQ(design["comparison"].size(), 2u);  // touch154 and the design
  // The plan generates a LinuxCNC program that passes the dialect's checker ...
  const auto g = sh("generate --plan " + p("designed.json") + " --dialect linuxcnc -o " + p("designed.ngc"));
  EXPECT_EQ(g.code, 0) << g.out;
  // ... and the Monte Carlo runs on it (the closed forms need the touch154 poses: left out).
  const auto u = sh("uncertainty --plan " + p("designed.json") + " --contributors " + contrib +
                    " --runs 200 --combined-only --json " + p("du.json"));
  ASSERT_EQ(u.code, 0) << u.out;
  const auto j = loadJson(p("du.json"));
  EXPECT_TRUE(j["methods"].contains("least_squares"));
  EXPECT_FALSE(j["methods"].contains("closed_form"));
  EXPECT_TRUE(j.contains("closed_form_not_applicable"));
}

}  // namespace
}  // namespace rotacal::test
