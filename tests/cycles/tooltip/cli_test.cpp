// The tooltip cycle through the rotacal command: plan -> generate (every dialect; Heidenhain and
// Okuma refuse) -> simulate with a known pivot-length and angular error -> analyze (REPORT.json with
// the injected dR, figures) -> diagnose (pivot_length confounded with the scale: one tool); and the contract's error form.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/cli_run.hpp"
#include "test_util.hpp"
#include "dialect_lists.hpp"

namespace rotacal::test {
namespace {

TEST(TooltipCli, PlanGenerateSimulateAnalyzeDiagnose) {
  const fs::path dir = test::freshDir("tooltip_cli");
  const std::string d = dir.string();
  const std::string machine = test::sourcePath("examples/machines/head_ab.json");
  CliRun r = sh("plan --cycle tooltip --machine " + machine +
             " --set units=inch --set radius_mm=381 --set step_deg=5 --set end_deg=90 -o " + d + "/plan.json");
  ASSERT_EQ(r.code, 0) << r.out;
  for (const std::string& dialect : test::inverseTimeDialects()) {
    r = sh("generate --plan " + d + "/plan.json --dialect " + dialect + " -o " + d + "/p_" + dialect);
    EXPECT_EQ(r.code, 0) << dialect << ": " << r.out;
  }
  // G93 is UNVERIFIED for these two controls: refused with the reason, nothing written.
  for (const char* dialect : {"heidenhain", "okuma"}) {
    r = sh("generate --plan " + d + "/plan.json --dialect " + dialect + " -o " + d + "/p_" + dialect);
    EXPECT_EQ(r.code, 1) << dialect << ": " << r.out;
    EXPECT_NE(r.out.find("inverse-time"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(d + "/p_" + dialect));
  }

  std::ofstream(d + "/truth.json") << R"({"format": "rotacal-truth/1",
    "tooltip": {"dR_um": 40.0, "angular_error": {"offset_mdeg": 2.0, "sin_mdeg": -3.0}}})";
  r = sh("simulate --plan " + d + "/plan.json --truth " + d + "/truth.json --dialect csv -o " + d + "/r.csv");
  ASSERT_EQ(r.code, 0) << r.out;
  r = sh("analyze --plan " + d + "/plan.json --results " + d + "/r.csv --dialect csv --json " + d + "/REPORT.json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto rep = loadJson(d + "/REPORT.json");
  EXPECT_EQ(rep["format"], "rotacal-report/1");
  EXPECT_EQ(rep["cycle"], "tooltip");
  // The results file rounds to 1e-4 um: the recovered dR is the truth to far better than 1e-3 x 40 um.
  EXPECT_NEAR(rep["location_errors"]["dR"]["value"].get<double>(), 40.0, 0.04);
  EXPECT_EQ(rep["location_errors"]["dR"]["unit"], "um");
  ASSERT_EQ(rep["figures"].size(), 2u);
  EXPECT_EQ(rep["figures"][1]["y"]["unit"], "mdeg");
  // 90 deg: 004's formula has no value, the joint fit has one: 2 - 3 sin 90 = -1 mdeg.
  EXPECT_EQ(rep["figures"][1]["series"][0]["x"].size(), 18u);
  EXPECT_NEAR(rep["angular_error"][18]["value"].get<double>(), -1.0, 0.01);

  // diagnose tests against what head_ab.json's contributors declare (004 Sec. VII): the machine
  // positioning's 12.7 um per move, shared between readings, leaves 40 um of pivot error within
  // the declared noise; the diagnosis says so and names the declaration.
  r = sh("diagnose --plan " + d + "/plan.json --results " + d + "/r.csv --dialect csv --json " + d + "/DIAG40.json");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(loadJson(d + "/DIAG40.json")["verdict"], "no_significant_effect") << r.out;
  EXPECT_NE(r.out.find("shared between readings"), std::string::npos) << r.out;
  std::ofstream(d + "/truth200.json") << R"({"format": "rotacal-truth/1",
    "tooltip": {"dR_um": 200.0, "angular_error": {"offset_mdeg": 2.0, "sin_mdeg": -3.0}}})";
  r = sh("simulate --plan " + d + "/plan.json --truth " + d + "/truth200.json --dialect csv -o " + d + "/r200.csv");
  ASSERT_EQ(r.code, 0) << r.out;
  r = sh("diagnose --plan " + d + "/plan.json --results " + d + "/r200.csv --dialect csv --json " + d + "/DIAG.json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto dg = loadJson(d + "/DIAG.json");
  // One tool: a 200 um pivot error moves the tip exactly as an isotropic scale of -1000 x 200 / 381
  // um/m would: never "effect found: pivot_length" alone; one finding that names both,
  // with what separates them, and the pair's entry says the finding carries its signal.
  ASSERT_EQ(dg["findings"].size(), 1u) << r.out;
  const auto& f = dg["findings"][0];
  std::vector<std::string> named = {f["cause"].get<std::string>()};
  for (const auto& c : f["confounded_with"]) named.push_back(c.get<std::string>());
  EXPECT_NE(std::find(named.begin(), named.end(), "pivot_length"), named.end());
  EXPECT_NE(std::find(named.begin(), named.end(), "linear_axis_scale"), named.end());
  EXPECT_NE(f["separate_with"].get<std::string>().find("second tool length"), std::string::npos);
  EXPECT_TRUE(r.out.find("pivot_length or linear-axis scale: the plan cannot tell them apart") != std::string::npos ||
              r.out.find("linear-axis scale or pivot_length: the plan cannot tell them apart") != std::string::npos)
      << r.out;
  ASSERT_FALSE(dg["confounded"].empty());
  EXPECT_EQ(dg["confounded"][0]["signal"], false);
  EXPECT_EQ(dg["confounded"][0]["finding"], f["cause"]);
  const auto causes = dg["confounded"][0]["causes"].get<std::vector<std::string>>();
  EXPECT_NE(std::find(causes.begin(), causes.end(), "pivot_length"), causes.end());
  EXPECT_NE(std::find(causes.begin(), causes.end(), "linear_axis_scale"), causes.end());

  // A machine drawn from the contributors: what was drawn is in --truth-out, the noise is the
  // declared per-reading scatter.
  r = sh("simulate --plan " + d + "/plan.json --truth " + d + "/truth.json --contributors " +
         test::sourcePath("examples/contributors/tooltip_004.json") + " --machine-seed 4 --truth-out " + d +
         "/drawn.json --dialect csv -o " + d + "/rd.csv");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto drawn = loadJson(d + "/drawn.json");
  EXPECT_EQ(drawn["drawn"]["seed"], 4);
  EXPECT_TRUE(drawn["drawn"].contains("linear_axes"));
  EXPECT_TRUE(drawn["drawn"].contains("laser_alignment_urad"));
  EXPECT_NEAR(drawn["noise_um"].get<double>(), 1.905, 1e-3);

  // Bad input: FILE:LINE, exit 1, nothing written.
  std::ofstream(d + "/bad.csv") << "angle_deg,dy_um,dz_um\n0,0,0\n5,1.0,oops\n";
  r = sh("analyze --plan " + d + "/plan.json --results " + d + "/bad.csv --dialect csv --json " + d + "/BAD.json");
  EXPECT_TRUE(refused(r, 1, "bad.csv:3:", d + "/BAD.json"));
  r = sh("plan --cycle tooltip --machine " + machine + " --set step_deg=7 -o " + d + "/p2.json");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("head_ab.json"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace rotacal::test
