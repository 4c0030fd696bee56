// `rotacal comp-table` (docs/compensation.md "Controller tables"): a spheres3 report's E_CC into
// the control's table; a report without component errors refused at its line, nothing written;
// the previous table kept as .bak; the plausibility limit and --force; refused dialects.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

class CompTableCli : public ScratchTest {
 protected:
  void SetUp() override {
    ScratchTest::SetUp();
    machine = test::sourcePath("examples/machines/ac_trunnion.json");
    const std::string truth = test::sourcePath("examples/truth/table4_c_radial2.json");
    ASSERT_EQ(sh("-q plan --cycle spheres3 --machine " + machine + " -o " + p("plan.json")).code, 0);
    ASSERT_EQ(sh("-q simulate --plan " + p("plan.json") + " --truth " + truth + " --noise-um 0 --dialect csv -o " +
                 p("run.csv")).code,
              0);
    const auto r = sh("-q analyze --plan " + p("plan.json") + " --results " + p("run.csv") + " --dialect csv --json " +
                      p("report.json"));
    ASSERT_EQ(r.code, 0) << r.out;
    // the same report with a known E_CC: 2 cos C - 1.5 sin 2C mdeg at its angles
    nlohmann::json j = nlohmann::json::parse(slurp(p("report.json")));
    auto& ecc = j["component_errors"]["ECC"];
    std::vector<double> v;
    for (double c : ecc["c_deg"].get<std::vector<double>>()) v.push_back(eccOf(c));
    ecc["values"] = v;
    std::ofstream(p("known.json")) << j.dump(1) << "\n";
  }
  static double eccOf(double c_deg) {
    const double c = c_deg * 3.14159265358979323846 / 180.0;
    return 2.0 * std::cos(c) - 1.5 * std::sin(2 * c);
  }
  std::string machine;
};

TEST_F(CompTableCli, WritesTheSpheres3ReportsEccAsALinuxcncTableAndKeepsTheOldOne) {
  const std::string out = p("c.comp");
  fs::remove(out);
  fs::remove(out + ".bak");
  auto r = sh("comp-table --report " + p("known.json") + " --dialect linuxcnc -o " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("COMP_FILE_TYPE = 0"), std::string::npos) << r.out;
  // the bundled machine counts C the other way on LinuxCNC (dialect_sign -1): e(theta) = +E(-theta)
  std::istringstream in(slurp(out));
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    double nom = 0, fwd = 0, rev = 0;
    if (std::sscanf(line.c_str(), "%lf %lf %lf", &nom, &fwd, &rev) != 3) break;
    EXPECT_NEAR(fwd - nom, eccOf(-nom) * 1e-3, 1.01e-6) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 145);
  const std::string first = slurp(out);
  // a second run with another spacing keeps the first table as .bak
  r = sh("-q comp-table --report " + p("known.json") + " --dialect linuxcnc --step-deg 10 -o " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(slurp(out + ".bak"), first);
  EXPECT_NE(slurp(out), first);
  // the analysed report itself (no E_CC injected: a table of noise within its U at every angle) is
  // refused, nothing written, and written only on request
  r = sh("-q comp-table --report " + p("report.json") + " --dialect siemens -o " + p("c.ini"));
  EXPECT_TRUE(refused(r, 1, "within its expanded uncertainty", p("c.ini")));
  r = sh("-q comp-table --report " + p("report.json") + " --dialect siemens --write-insignificant -o " + p("c.ini"));
  EXPECT_EQ(r.code, 0) << r.out;
  r = sh("-q comp-table --report " + p("known.json") + " --dialect fanuc --machine " + machine + " -o " + p("c.txt"));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(slurp(p("c.txt")).find("3622 = 72"), std::string::npos);
}

TEST_F(CompTableCli, RefusesAReportWithoutComponentErrorsAtItsLineAndWritesNothing) {
  // a touch154-like report: location errors only
  std::ofstream(p("loc.json")) << "{\n \"format\": \"rotacal-report/1\",\n \"location_errors\": {}\n}\n";
  const std::string out = p("never.comp");
  fs::remove(out);
  auto r = sh("comp-table --report " + p("loc.json") + " --dialect linuxcnc --machine " + machine + " -o " + out);
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_EQ(r.out, "rotacal: error: " + p("loc.json") + ":1: the report has no component_errors (the angular "
                   "positioning error ECC comes from a cycle that identifies the component errors of C, e.g. the "
                   "three-sphere cycle's analyze)\n");
  EXPECT_FALSE(fs::exists(out));
  // ECC with a value that is no number: its line
  nlohmann::json j = nlohmann::json::parse(slurp(p("known.json")));
  j["component_errors"]["ECC"]["values"][3] = "x";
  std::ofstream(p("bad.json")) << j.dump(1) << "\n";
  r = sh("comp-table --report " + p("bad.json") + " --dialect linuxcnc -o " + out);
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find(p("bad.json") + ":"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ECC.values holds '\"x\"', not a finite number"), std::string::npos) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1);
  EXPECT_FALSE(fs::exists(out));
  // angles that are not a full turn
  j = nlohmann::json::parse(slurp(p("known.json")));
  j["component_errors"]["ECC"]["c_deg"][5] = 151.0;
  std::ofstream(p("spacing.json")) << j.dump(1) << "\n";
  r = sh("comp-table --report " + p("spacing.json") + " --dialect linuxcnc -o " + out);
  EXPECT_TRUE(refused(r, 1, "not equally spaced", out));
}

TEST_F(CompTableCli, PlausibilityLimitForceAndRefusedDialects) {
  nlohmann::json j = nlohmann::json::parse(slurp(p("known.json")));
  std::vector<double> v = j["component_errors"]["ECC"]["values"];
  for (auto& x : v) x *= 60.0;  // 120 mdeg
  j["component_errors"]["ECC"]["values"] = v;
  std::ofstream(p("big.json")) << j.dump(1) << "\n";
  const std::string out = p("big.comp");
  fs::remove(out);
  auto r = sh("comp-table --report " + p("big.json") + " --dialect linuxcnc -o " + out);
  EXPECT_TRUE(refused(r, 1, "exceeds the plausibility limit of 100 mdeg", out));
  r = sh("-q comp-table --report " + p("big.json") + " --dialect linuxcnc --force -o " + out);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(out));
  for (const std::string d : {"heidenhain", "okuma", "haas"}) {
    r = sh("comp-table --report " + p("known.json") + " --dialect " + d + " -o " + p("x.tab"));
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find(d + ": no"), std::string::npos) << r.out;
  }
  r = sh("comp-table --report " + p("known.json") + " --dialect linuxcnc --step-deg 7 -o " + p("x.tab"));
  EXPECT_EQ(r.code, 2) << r.out;
  r = sh("comp-table --report " + p("known.json") + " --dialect linuxcnc --axis A -o " + p("x.tab"));
  EXPECT_EQ(r.code, 2) << r.out;
  r = sh("comp-table --report " + p("known.json") + " --dialect linuxcnc -o " + p("known.json"));
  EXPECT_EQ(r.code, 2) << r.out;  // the output on the input
  EXPECT_FALSE(fs::exists(p("x.tab")));
}

}  // namespace
}  // namespace rotacal::test
