// `rotacal` on the space-frame cycle (003) end to end: plan -> generate -> simulate -> analyze,
// checked against the injected truth and 003's counts, and the contract's error behaviour.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/cli_run.hpp"
#include "test_util.hpp"

namespace rotacal::test {
namespace {

using Run = test::CliRun;

class SpaceframeCli : public ScratchTest {
 protected:
  const std::string machine = test::sourcePath("examples/machines/ac_trunnion_a120.json");
};

TEST_F(SpaceframeCli, IsotropicScaleErrorEndToEnd) {
  // 50 um/m on every linear axis and nothing else, no noise: dL = -50e-6 Ln / (1 + 50e-6).
  std::ofstream(p("truth.json")) << R"({"format": "rotacal-truth/1",
    "linear_axis_scale": {"X_um_per_m": 50, "Y_um_per_m": 50, "Z_um_per_m": 50}})";
  auto r = sh("plan --cycle spaceframe --machine " + machine + " --set mpe_a_um=2 --set mpe_k_um_per_m=40 -o " + p("plan.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  // The program passes rotacal check (docs/safety.md): at A = -90 deg the touches whose access
  // passes another sphere are left out of the plan.
  r = sh("generate --plan " + p("plan.json") + " --dialect linuxcnc -o " + p("sf.ngc"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(p("sf.ngc")));
  r = sh("simulate --plan " + p("plan.json") + " --truth " + p("truth.json") + " --dialect fanuc -o " + p("results.txt"));
  ASSERT_EQ(r.code, 0) << r.out;
  r = sh("analyze --plan " + p("plan.json") + " --results " + p("results.txt") + " --dialect fanuc --json " + p("REPORT.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(p("REPORT.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["cycle"], "spaceframe");
  // 003's 315 centres less those another sphere blocks (docs/safety.md); every pair is a length.
  const int centres = j["lengths"]["points"].get<int>();
  EXPECT_EQ(static_cast<size_t>(centres), j["frame_points"].size());
  EXPECT_GT(centres, 270);
  EXPECT_LE(centres, 315);
  EXPECT_EQ(j["lengths"]["count"].get<int>(), centres * (centres - 1) / 2);
  // Largest nominal length of the map: the largest |dL| is 50e-6 of it (Fanuc results carry 4
  // decimals of mm: 0.1 um).
  double Lmax = 0.0;
  const auto& pts = j["frame_points"];
  for (size_t a = 0; a < pts.size(); ++a)
    for (size_t b = a + 1; b < pts.size(); ++b) {
      double d2 = 0.0;
      for (int i = 0; i < 3; ++i) {
        const double d = pts[a]["centre_m_mm"][i].get<double>() - pts[b]["centre_m_mm"][i].get<double>();
        d2 += d * d;
      }
      Lmax = std::max(Lmax, std::sqrt(d2));
    }
  EXPECT_NEAR(j["lengths"]["max_abs_dL_um"].get<double>(), 50e-6 * Lmax * 1e3, 0.1);
  // 50 um/m against A = 2 um, K = 40 um/m: fails beyond L = 2 / (50 - 40) m = 200 mm.
  EXPECT_EQ(j["lengths"]["verdict"], "fail");
  EXPECT_GT(Lmax, 200.0);
  for (const char* ax : {"X", "Y", "Z"})
    EXPECT_NEAR(j["linear_axis_scale"][ax]["value"].get<double>(), 50.0, 0.5) << ax;  // 0.1 um rounding over 0.3 m
  for (const auto& [name, e] : j["location_errors"].items()) EXPECT_NEAR(e["value"].get<double>(), 0.0, 0.2) << name;
  ASSERT_TRUE(j.contains("figures"));
  EXPECT_EQ(j["figures"][0]["id"], "spaceframe_dl_vs_l");
  EXPECT_EQ(j["figures"][0]["bands"][0]["lo"].size(), j["figures"][0]["bands"][0]["x"].size());
  // Histogram counts add up to all the lengths (003 Fig. 5).
  int n = 0;
  for (const auto& c : j["figures"][1]["series"][0]["y"]) n += c.get<int>();
  EXPECT_EQ(n, centres * (centres - 1) / 2);
}

TEST_F(SpaceframeCli, TiltOutsideTheStrokeAndOffsetsAreClearErrors) {
  auto r = sh("plan --cycle spaceframe --machine " + test::sourcePath("examples/machines/ac_trunnion.json") + " -o " + p("plan.json"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("ac_trunnion.json:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("outside the A stroke"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(p("plan.json")));
  r = sh("plan --cycle spaceframe --machine " + machine + " --set mpe_k_um_per_m=-3 -o " + p("plan.json"));
  EXPECT_EQ(r.code, 1) << r.out;
  r = sh("plan --cycle spaceframe --machine " + machine + " --set theta_list=0,180 --set phi_list=0,90 -o " + p("plan.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  std::ofstream(p("truth.json")) << R"({"format": "rotacal-truth/1"})";
  r = sh("simulate --plan " + p("plan.json") + " --truth " + p("truth.json") + " --dialect csv -o " + p("r.csv"));
  ASSERT_EQ(r.code, 0) << r.out;
  r = sh("analyze --plan " + p("plan.json") + " --results " + p("r.csv") + " --dialect csv --offsets " + p("off.txt"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_FALSE(fs::exists(p("off.txt")));
}

}  // namespace
}  // namespace rotacal::test
