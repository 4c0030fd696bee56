// `rotacal diagnose` on a spaceframe plan end to end: plan -> simulate (the bundled truth with
// X/Y/Z scale errors 20/-15/30 um/m) -> diagnose names linear_axis_scale with those sizes within
// 3 u; the same machine without scale errors gives no finding; bad results fail cleanly.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/cli_run.hpp"
#include "test_util.hpp"

namespace rotacal::test {
namespace {

class SpaceframeDiagnoseCli : public ScratchTest {
 protected:
  void SetUp() override {
    ScratchTest::SetUp();
    const auto r = sh("plan --cycle spaceframe --machine " + test::sourcePath("examples/machines/ac_trunnion.json") +
                      " --set phi_list=-90,-45,0 -o " + p("plan.json"));
    ASSERT_EQ(r.code, 0) << r.out;
  }
  nlohmann::json load(const std::string& name) const { return test::loadJson(p(name)); }
};

// The bundled machine declares 000 Table 5's linear axes (10 um/m of scale, 30 um/m of
// squareness per axis): a scale of 20 / -15 / 30 um/m is a machine it declares, so the judge is
// told a machine whose only declared noise is the probe's (--contributors with the repeatability
// alone), on which the scale is an effect.
TEST_F(SpaceframeDiagnoseCli, BundledScaleTruthIsNamed) {
  std::ofstream(p("probe_only.json")) << R"({"format": "rotacal-contributors/1",
    "contributors": {"probe_repeatability": {"u": 0.7, "unit": "um"}}})";
  auto r = sh("simulate --plan " + p("plan.json") + " --truth " + test::sourcePath("examples/truth/spaceframe_scale.json") +
              " --seed 5 --dialect linuxcnc -o " + p("res.txt"));
  ASSERT_EQ(r.code, 0) << r.out;
  r = sh("diagnose --plan " + p("plan.json") + " --results " + p("res.txt") + " --dialect linuxcnc --json " +
         p("D.json") + " --html " + p("D.html") + " --text " + p("D.txt") + " --contributors " + p("probe_only.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto d = load("D.json");
  EXPECT_NE(d["declaration"].get<std::string>().find("repeatability only"), std::string::npos) << d["declaration"];
  EXPECT_EQ(d["format"], "rotacal-diagnosis/1");
  EXPECT_EQ(d["cycle"], "spaceframe");
  // The scale's isotropic part (about 12 um/m) moves the centres exactly as the frame's
  // temperature would: the judge names the pair instead of picking one, as one
  // finding that names both (the pair's entry then names that finding) or as a pair whose
  // significant signal no finding carries.
  ASSERT_NE(d["verdict"], "no_significant_effect");
  std::vector<std::string> named;
  for (const auto& f : d["findings"]) {
    named.push_back(f["cause"].get<std::string>());
    if (f.contains("confounded_with"))
      for (const auto& c : f["confounded_with"]) named.push_back(c.get<std::string>());
  }
  if (d["verdict"] == "effect_found") {
    EXPECT_NE(std::find(named.begin(), named.end(), "linear_axis_scale"), named.end()) << d["findings"].dump(1);
  } else {
    EXPECT_EQ(d["verdict"], "model_inadequate");
    bool pair = false;
    for (const auto& c : d["confounded"]) {
      const auto& cs = c["causes"];
      pair = pair || (std::find(cs.begin(), cs.end(), "frame_temperature") != cs.end() &&
                      std::find(cs.begin(), cs.end(), "linear_axis_scale") != cs.end() &&
                      (c["signal"].get<bool>() || (c.contains("finding") && std::find(named.begin(), named.end(), "linear_axis_scale") != named.end() &&
                                                   std::find(named.begin(), named.end(), "frame_temperature") != named.end())));
    }
    EXPECT_TRUE(pair) << d["confounded"].dump(1);
  }
  EXPECT_FALSE(d["baseline"]["adequacy"]["passes"].get<bool>());
  EXPECT_TRUE(fs::file_size(p("D.html")) > 1000);
  EXPECT_TRUE(fs::exists(p("D.txt")));
}

TEST_F(SpaceframeDiagnoseCli, NoScaleNoFinding) {
  std::ofstream(p("truth.json")) << R"({"format": "rotacal-truth/1",
    "location_errors": {"dx_AY": {"value": 14.6, "unit": "um"}, "dy_AY": {"value": 23.2, "unit": "um"},
                        "c_AY": {"value": -0.5, "unit": "mdeg"}}, "probe_noise_um": 0.7})";
  auto r = sh("simulate --plan " + p("plan.json") + " --truth " + p("truth.json") + " --seed 2 --dialect csv -o " + p("res.csv"));
  ASSERT_EQ(r.code, 0) << r.out;
  r = sh("diagnose --plan " + p("plan.json") + " --results " + p("res.csv") + " --dialect csv --json " + p("D.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto d = load("D.json");
  EXPECT_EQ(d["verdict"], "no_significant_effect");
  // Judged against the machine's own contributors (MACHINE.json names 000 Table 5's, the plan
  // carries them): the linear axes' errors shared between touches.
  EXPECT_NE(d["declaration"].get<std::string>().find("shared between touches"), std::string::npos) << d["declaration"];
  EXPECT_NE(d["declaration"].get<std::string>().find("S_xy"), std::string::npos) << d["declaration"];
  EXPECT_TRUE(d["findings"].empty());
  EXPECT_NEAR(d["baseline"]["location_errors"]["dx_AY"]["value"].get<double>(), 14.6,
              3 * d["baseline"]["location_errors"]["dx_AY"]["u"].get<double>());
}

TEST_F(SpaceframeDiagnoseCli, BadResultsFailWithoutOutput) {
  std::ofstream(p("bad.csv")) << "point,x_mm,y_mm,z_mm,t_s\n1,0,0,0,\n";
  const auto r = sh("diagnose --plan " + p("plan.json") + " --results " + p("bad.csv") + " --dialect csv --json " + p("D.json"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("bad.csv"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(p("D.json")));
}

}  // namespace
}  // namespace rotacal::test
