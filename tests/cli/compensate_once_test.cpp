// `rotacal compensate` applies each error once, from the right report, to what the program is:
// - a part program (no probing move) is checked as one: the calibration artefact is not on the
//   table when parts are cut, the tool is not a probe, the table is still there;
// - a report of another machine, and a residual report (`analyze --compensated-with`), are
//   refused; a report's date is recorded and an old one is flagged;
// - what a controller table holds (`--table-holds ECC`) is left out of the program;
// - a LinuxCNC program compensated once carries a statement that survives stripping its comments;
// - one_sphere's report (its covariance is of a larger fit, in the fit's names) can be used.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "postproc/report_errors.hpp"
#include "test_util.hpp"

namespace rotacal::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The modal X, Y and C at every probing move (G38) of a LinuxCNC program.
struct XYC {
  double x = NAN, y = NAN, c = NAN;
  bool moved = false;  // this line sets X or Y
};
std::vector<XYC> modalXYC(const std::string& text) {
  std::vector<XYC> out;
  const std::regex word(R"(\b([XYC])(-?[0-9]+\.[0-9]*))");
  std::istringstream in(text);
  std::string line;
  XYC cur;
  while (std::getline(in, line)) {
    cur.moved = false;
    if (!line.empty() && line[0] != '(' && line[0] != '#' && line[0] != 'o')
      for (std::sregex_iterator it(line.begin(), line.end(), word), e; it != e; ++it) {
        const double v = std::stod((*it)[2]);
        const char k = (*it)[1].str()[0];
        if (k == 'X') cur.x = v, cur.moved = true;
        if (k == 'Y') cur.y = v, cur.moved = true;
        if (k == 'C') cur.c = v;
      }
    // Only the probing moves: neither program splits them, so they pair one to one.
    if (line.rfind("G38", 0) == 0) out.push_back(cur);
  }
  return out;
}

// A five-axis part program for the bundled A/C table in LinuxCNC's counting: a ring of radius
// 30 mm cut with the table tilted 30 deg, around the point where the calibration column stands
// in MACHINE.json (its top centre (0, -200, 170) mm, 150 mm tall: the ring at z 120 lies inside
// it). `depth_w_mm`: the ring's height in the workpiece frame.
std::string tiltedRing(const MachineModel& m, double depth_w_mm) {
  std::string s = "%\n(A TILTED RING, FIVE-AXIS)\nG21 G90 G94\nG0 Z300.0000\n";
  const int sa = m.controllerSign('A', "linuxcnc"), sc = m.controllerSign('C', "linuxcnc");
  const double A = -30.0;
  bool first = true;
  for (int k = 0; k <= 36; ++k) {
    const double C = 10.0 * k, th = C * kPi / 180.0;
    const Eigen::Vector3d pw(30.0 * std::cos(th), -200.0 + 30.0 * std::sin(th), depth_w_mm);
    const Eigen::Vector3d pm = T_m_w_nominal(m.kinematics, Pose{A, 0.0, C}) * pw;
    if (first) {
      s += fmt::format("G0 A{:.4f} C{:.4f}\nG0 X{:.4f} Y{:.4f}\nG1 Z{:.4f} F500.0\n", sa * A, sc * C, pm.x(), pm.y(),
                       pm.z());
      first = false;
    } else {
      s += fmt::format("G1 X{:.4f} Y{:.4f} Z{:.4f} A{:.4f} C{:.4f} F500.0\n", pm.x(), pm.y(), pm.z(), sa * A, sc * C);
    }
  }
  s += "G0 Z300.0000\nM2\n%\n";
  return s;
}

class CompensateOnce : public AcTrunnionTest {
 protected:
  // A touch154 report of the bundled machine (000 Table 4's errors, 0.7 um noise).
  void touchReport() {
    ASSERT_EQ(sh("-q plan --cycle touch154 --machine " + machine + " -o " + p("plan.json")).code, 0);
    ASSERT_EQ(sh("-q simulate --plan " + p("plan.json") + " --truth " + truth + " --noise-um 0.7 --seed 3 --dialect "
                 "linuxcnc -o " + p("run.txt")).code,
              0);
    const auto r = sh("-q analyze --plan " + p("plan.json") + " --results " + p("run.txt") +
                      " --dialect linuxcnc --json " + p("report.json"));
    ASSERT_EQ(r.code, 0) << r.out;
  }
  std::string compensate(const std::string& program, const std::string& report, const std::string& out,
                         const std::string& extra = "") {
    last = sh("compensate --program " + program + " --report " + report + " --dialect linuxcnc -o " + out + extra);
    return last.out;
  }
  CliRun last;
};

TEST_F(CompensateOnce, APartProgramThroughWhereTheArtefactStoodIsCompensatedWithTheCalibrationsMachineFile) {
  touchReport();
  const MachineModel m = loadMachine(machine);
  std::ofstream(p("ring.ngc")) << tiltedRing(m, 120.0);
  compensate(p("ring.ngc"), p("report.json"), p("ring_c.ngc"), " --machine " + machine);
  ASSERT_EQ(last.code, 0) << last.out;
  EXPECT_NE(last.out.find("a part program"), std::string::npos) << last.out;
  // The same program checked as a probing program would hit the column the machine file declares:
  // that is what part programs were refused for.
  const auto probing = sh("check " + p("ring.ngc") + " --dialect linuxcnc --machine " + machine);
  EXPECT_NE(probing.code, 0) << probing.out;
  EXPECT_NE(probing.out.find("the artefact"), std::string::npos) << probing.out;
  // `check --part-program` checks it as compensate does.
  const auto part = sh("check " + p("ring.ngc") + " --dialect linuxcnc --machine " + machine + " --part-program");
  EXPECT_EQ(part.code, 0) << part.out;
  EXPECT_NE(part.out.find("checked as a part program"), std::string::npos) << part.out;

  // The table is still there: the ring cut 30 mm below the table's top (the column's bottom,
  // z 20 mm) is refused, naming the first move that enters it, and nothing is written.
  std::ofstream(p("deep.ngc")) << tiltedRing(m, -10.0);
  compensate(p("deep.ngc"), p("report.json"), p("deep_c.ngc"), " --machine " + machine);
  EXPECT_TRUE(refused(last, 1, "the table", p("deep_c.ngc")));
  EXPECT_NE(last.out.find("deep.ngc:7:"), std::string::npos) << last.out;  // G1 Z down to the ring
  const auto deep = sh("check " + p("deep.ngc") + " --dialect linuxcnc --machine " + machine + " --part-program");
  EXPECT_EQ(deep.code, 1) << deep.out;
  EXPECT_NE(deep.out.find("deep.ngc:7:"), std::string::npos) << deep.out;
}

TEST_F(CompensateOnce, AReportOfAnotherMachineOrAResidualReportIsRefusedAndAnOldOneIsFlagged) {
  touchReport();
  const std::string program = sourcePath("examples/programs/linuxcnc/touch154.ngc");
  nlohmann::json j = loadJson(p("report.json"));
  // analyze records when it analyzed (UTC, ISO 8601), honouring SOURCE_DATE_EPOCH.
  ASSERT_TRUE(j.contains("analyzed_utc"));
  EXPECT_TRUE(std::regex_match(j["analyzed_utc"].get<std::string>(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
  compensate(program, p("report.json"), p("x.ngc"), " --machine " + sourcePath("examples/machines/bc_trunnion.json"));
  EXPECT_TRUE(refused(last, 1, "the report was measured on machine 'ac_trunnion'", p("x.ngc")));
  // A residual: what a compensation left is not the machine's errors.
  nlohmann::json residual = j;
  residual["compensated_with"] = {"first.json"};
  std::ofstream(p("residual.json")) << residual.dump(1) << "\n";
  compensate(program, p("residual.json"), p("x.ngc"));
  EXPECT_TRUE(refused(last, 1, "a residual report", p("x.ngc")));
  EXPECT_NE(last.out.find("compensate the original program for first.json"), std::string::npos) << last.out;
  // 89 days before the run: flagged, still written.
  const auto old = sh("-q analyze --plan " + p("plan.json") + " --results " + p("run.txt") +
                      " --dialect linuxcnc --json " + p("old.json"));
  ASSERT_EQ(old.code, 0);
  nlohmann::json o = loadJson(p("old.json"));
  o["analyzed_utc"] = "2020-01-01T00:00:00Z";
  std::ofstream(p("old.json")) << o.dump(1) << "\n";
  compensate(program, p("old.json"), p("old.ngc"));
  ASSERT_EQ(last.code, 0) << last.out;
  EXPECT_NE(last.out.find("analyzed 2020-01-01T00:00:00Z"), std::string::npos) << last.out;
  EXPECT_NE(last.out.find("more than 30"), std::string::npos) << last.out;
}

TEST_F(CompensateOnce, ALinuxcncProgramStrippedOfItsCommentsIsNotCompensatedAgain) {
  touchReport();
  const std::string program = sourcePath("examples/programs/linuxcnc/touch154.ngc");
  compensate(program, p("report.json"), p("once.ngc"));
  ASSERT_EQ(last.code, 0) << last.out;
  // What a DNC filter or a hand edit does: every comment removed.
  std::string stripped;
  {
    std::istringstream in(slurp(p("once.ngc")));
    std::string line;
    while (std::getline(in, line)) {
      const std::string s = std::regex_replace(line, std::regex(R"(\([^)]*\))"), "");
      if (s.find_first_not_of(' ') != std::string::npos) stripped += s + "\n";
    }
  }
  ASSERT_EQ(stripped.find("ROTACAL"), std::string::npos);
  std::ofstream(p("stripped.ngc")) << stripped;
  compensate(p("stripped.ngc"), p("report.json"), p("twice.ngc"));
  EXPECT_TRUE(refused(last, 1, "the program is already compensated (statement #<rotacal_compensated> = 1)",
                      p("twice.ngc")));
}

// spheres3's report with a known E_CC (comp_table_cli_test's): with --table-holds ECC the program
// no longer carries it. spheres3 touches at A = 0, where C is parallel to the probe and the
// compensation turns the table's error into X and Y (C is the singular axis there): the full
// compensation less the held one is the table's turn by E_CC about C, eps z x p at the machine
// point p, eps = E_CC at the papers' angle (LinuxCNC counts C the other way on this machine).
TEST_F(CompensateOnce, WhatTheControllersTableHoldsIsLeftOutOfTheProgram) {
  ASSERT_EQ(sh("-q plan --cycle spheres3 --machine " + machine + " -o " + p("s3.json")).code, 0);
  ASSERT_EQ(sh("-q simulate --plan " + p("s3.json") + " --truth " + sourcePath("examples/truth/table4_c_radial2.json") +
               " --noise-um 0 --dialect linuxcnc -o " + p("s3.txt")).code,
            0);
  ASSERT_EQ(sh("-q analyze --plan " + p("s3.json") + " --results " + p("s3.txt") + " --dialect linuxcnc --json " +
               p("s3r.json")).code,
            0);
  auto ecc = [](double c_deg) {
    const double c = c_deg * kPi / 180.0;
    return 2.0 * std::cos(c) - 1.5 * std::sin(2 * c);  // mdeg, papers' C
  };
  nlohmann::json j = loadJson(p("s3r.json"));
  std::vector<double> v;
  for (double c : j["component_errors"]["ECC"]["c_deg"].get<std::vector<double>>()) v.push_back(ecc(c));
  j["component_errors"]["ECC"]["values"] = v;
  std::ofstream(p("known.json")) << j.dump(1) << "\n";
  ASSERT_EQ(sh("-q generate --plan " + p("s3.json") + " --dialect linuxcnc -o " + p("s3.ngc")).code, 0);
  compensate(p("s3.ngc"), p("known.json"), p("full.ngc"));
  ASSERT_EQ(last.code, 0) << last.out;
  compensate(p("s3.ngc"), p("known.json"), p("held.ngc"), " --table-holds ECC");
  ASSERT_EQ(last.code, 0) << last.out;
  EXPECT_NE(last.out.find("ECC is held by the controller's compensation table"), std::string::npos) << last.out;
  const auto full = modalXYC(slurp(p("full.ngc"))), held = modalXYC(slurp(p("held.ngc")));
  ASSERT_EQ(full.size(), held.size());
  ASSERT_EQ(full.size(), modalXYC(slurp(p("s3.ngc"))).size());
  const int sc = loadMachine(machine).controllerSign('C', "linuxcnc");
  double worst = 0.0, largest = 0.0;
  int rows = 0;
  for (size_t i = 0; i < full.size(); ++i) {
    if (!held[i].moved || std::isnan(held[i].x + held[i].y + held[i].c)) continue;
    const double eps = ecc(sc * held[i].c) * kPi / 180.0 / 1000.0;  // rad
    const double want_x = -eps * held[i].y * 1000.0, want_y = eps * held[i].x * 1000.0;  // um
    const double dx = (full[i].x - held[i].x) * 1000.0, dy = (full[i].y - held[i].y) * 1000.0;
    worst = std::max({worst, std::abs(dx - want_x), std::abs(dy - want_y)});
    largest = std::max(largest, std::hypot(want_x, want_y));
    ++rows;
  }
  EXPECT_GT(rows, 100);
  EXPECT_GT(largest, 3.0);
  // two words printed to 0.1 um each (half a unit rounding), and eps x (the 40 um compensation)
  EXPECT_LE(worst, 0.1 + 0.01) << rows << " rows, largest " << largest;
  // A name that is no component error of the machine is a usage error.
  compensate(p("s3.ngc"), p("known.json"), p("bad.ngc"), " --table-holds EBB");
  EXPECT_TRUE(refused(last, 2, "--table-holds", p("bad.ngc")));
}

// one_sphere's covariance is of its whole fit (15 parameters under ISO names): each location
// error's row is found under the name its entry gives, so the 8 x 8 block's diagonal is each
// location error's own u, as the report prints it beside the value.
TEST_F(CompensateOnce, OneSpheresReportIsUsedWithItsCovariance) {
  const std::string bc = sourcePath("examples/machines/bc_trunnion.json");
  ASSERT_EQ(sh("-q plan --cycle one_sphere --machine " + bc + " -o " + p("os.json")).code, 0);
  ASSERT_EQ(sh("-q simulate --plan " + p("os.json") + " --truth " + sourcePath("tests/e2e/linuxcnc/truth_bc.json") +
               " --noise-um 0.7 --seed 2 --dialect linuxcnc -o " + p("os.txt")).code,
            0);
  ASSERT_EQ(sh("-q analyze --plan " + p("os.json") + " --results " + p("os.txt") + " --dialect linuxcnc --json " +
               p("osr.json")).code,
            0);
  ASSERT_EQ(sh("-q generate --plan " + p("os.json") + " --dialect linuxcnc -o " + p("os.ngc")).code, 0);
  compensate(p("os.ngc"), p("osr.json"), p("os_c.ngc"));
  ASSERT_EQ(last.code, 0) << last.out;
  EXPECT_NE(slurp(p("os_c.ngc")).find("with their covariance"), std::string::npos);
  const JsonDoc doc = readJsonFile(p("osr.json"));
  const GeometricErrors e = errorsFromReport(doc, Kinematics::TableBC, false);
  ASSERT_TRUE(e.location_covariance.has_value());
  const auto& params = locationParameters(Kinematics::TableBC);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const std::string name(params[static_cast<size_t>(i)].name);
    const double u_report = doc.value["location_errors"][name]["u"].get<double>();
    const double s = std::sqrt((*e.location_covariance)(i, i));
    const double u_cov = params[static_cast<size_t>(i)].kind == ParamKind::Length ? s * 1e3 : s * 180.0 / kPi * 1e3;
    EXPECT_NEAR(u_cov, u_report, 1e-3 * u_report + 1e-6) << name;
  }
}

}  // namespace
}  // namespace rotacal::test
