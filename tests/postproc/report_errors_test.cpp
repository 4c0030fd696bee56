// Reading the errors to compensate from reports: what each kind of report gives, how two combine,
// and what is refused (with the report's file and line).
#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"
#include "core/units.hpp"
#include "postproc/report_errors.hpp"

namespace rotacal {
namespace {

JsonDoc doc(const std::string& file, const Json& j) {
  JsonDoc d;
  d.value = j;
  d.file = file;
  d.text = j.dump(1);
  return d;
}

Json fullReport(double scale = 1.0) {
  const char* names[8] = {"dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA"};
  const double v[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};
  Json le = Json::object();
  for (int i = 0; i < 8; ++i) le[names[i]] = {{"value", v[i] * scale}, {"unit", i < 4 ? "um" : "mdeg"}, {"u", 0.5}};
  return {{"format", "rotacal-report/1"}, {"location_errors", le}};
}

// A three-sphere report: the C axis's location and error motions EXC = 2 um cos 2C, ECC = 0.1 mdeg sin C.
Json sphereReport() {
  Json le = {{"Oxc", {{"value", 14.0}, {"unit", "um"}, {"u", 0.4}, {"iso", "X0C"}}},
             {"Oyc", {{"value", 27.5}, {"unit", "um"}, {"u", 0.4}, {"iso", "Y0C"}}},
             {"Sxc", {{"value", -0.45}, {"unit", "mdeg"}, {"u", 0.1}, {"iso", "A0C"}}},
             {"Syc", {{"value", 0.12}, {"unit", "mdeg"}, {"u", 0.1}, {"iso", "B0C"}}}};
  Json ce = Json::object();
  const char* names[6] = {"EXC", "EYC", "EZC", "EAC", "EBC", "ECC"};
  for (int k = 0; k < 6; ++k) {
    Json c = Json::array(), v = Json::array();
    for (int i = 0; i < 12; ++i) {
      const double a = 30.0 * i;
      c.push_back(a);
      v.push_back(k == 0 ? 2.0 * std::cos(2 * degToRad(a)) : k == 5 ? 0.1 * std::sin(degToRad(a)) : 0.0);
    }
    ce[names[k]] = {{"unit", k < 3 ? "um" : "mdeg"}, {"c_deg", c}, {"values", v}};
  }
  return {{"format", "rotacal-report/1"}, {"location_errors", le}, {"component_errors", ce}};
}

TEST(ReportErrors, AFullReportGivesTheEightLocationErrors) {
  const ReportErrors r = errorsFromReports({doc("t.json", fullReport())}, Kinematics::TableAC, false);
  EXPECT_NEAR(r.errors.location.get("dz_AY"), umToMm(27.7), 1e-15);
  EXPECT_NEAR(r.errors.location.get("b_CA"), mdegToRad(0.2), 1e-15);
  EXPECT_TRUE(r.errors.components.empty());
  EXPECT_TRUE(r.notes.empty());
}

TEST(ReportErrors, TheSphereReportAloneActsAtTheTiltAxisZeroAndSaysSo) {
  const ReportErrors r = errorsFromReports({doc("s.json", sphereReport())}, Kinematics::TableAC, false);
  EXPECT_NEAR(r.errors.location.get("dx_AY"), umToMm(14.0), 1e-15);
  EXPECT_NEAR(r.errors.location.get("dy_CA"), umToMm(27.5), 1e-15);
  EXPECT_NEAR(r.errors.location.get("a_AY"), mdegToRad(-0.45), 1e-15);
  EXPECT_NEAR(r.errors.location.get("b_CA"), mdegToRad(0.12), 1e-15);
  EXPECT_EQ(r.errors.location.get("dz_AY"), 0.0);
  ASSERT_EQ(r.errors.components.size(), 1u);
  // Between the samples: the series, EXC = 2 cos 2C um at C = 45 + 10 deg.
  EXPECT_NEAR(mmToUm(r.errors.components[0].at(55.0)[0]), 2.0 * std::cos(2 * degToRad(55.0)), 1e-12);
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("tilt axis's zero only"), std::string::npos);
  // On a B/C table the same report fills the B/C chain's terms.
  const ReportErrors b = errorsFromReports({doc("s.json", sphereReport())}, Kinematics::TableBC, false);
  EXPECT_NEAR(b.errors.location.get("dy_CB"), umToMm(27.5), 1e-15);
  EXPECT_NEAR(b.errors.location.get("b_BY"), mdegToRad(0.12), 1e-15);
}

TEST(ReportErrors, CombinedTheCAxisLocationComesWithItsErrorMotions) {
  const ReportErrors r =
      errorsFromReports({doc("t.json", fullReport()), doc("s.json", sphereReport())}, Kinematics::TableAC, false);
  const LocationErrors& L = r.errors.location;
  // The sums at A = 0 are the sphere report's; the A axis's own terms the full report's.
  EXPECT_NEAR(L.get("dx_AY"), umToMm(14.0), 1e-15);
  EXPECT_NEAR(L.get("dy_AY") + L.get("dy_CA"), umToMm(27.5), 1e-15);
  EXPECT_NEAR(L.get("dy_AY"), umToMm(23.2), 1e-15);
  EXPECT_NEAR(L.get("b_AY") + L.get("b_CA"), mdegToRad(0.12), 1e-15);
  EXPECT_NEAR(L.get("dz_AY"), umToMm(27.7), 1e-15);
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("X0C -0.60 um"), std::string::npos) << r.notes[0];  // 14.0 - 14.6
  EXPECT_EQ(r.sources.size(), 2u);
}

TEST(ReportErrors, AmbiguousIncompleteOrImplausibleReportsAreRefused) {
  auto refused = [](const std::vector<JsonDoc>& d, const std::string& what) {
    try {
      (void)errorsFromReports(d, Kinematics::TableAC, false);
      ADD_FAILURE() << "accepted, expected: " << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused({doc("a.json", fullReport()), doc("b.json", fullReport())}, "given twice (also by a.json)");
  refused({doc("a.json", sphereReport()), doc("b.json", sphereReport())}, "given twice");
  Json missing = sphereReport();
  missing["component_errors"].erase("EBC");
  refused({doc("m.json", missing)}, "lacks EBC");
  Json big = fullReport(100.0);  // 2.77 mm of dz_AY
  refused({doc("big.json", big)}, "--force");
  Json angles = sphereReport();
  angles["component_errors"]["EYC"]["c_deg"][3] = 91.0;
  refused({doc("g.json", angles)}, "same angles");
  EXPECT_NO_THROW((void)errorsFromReports({doc("big.json", big)}, Kinematics::TableAC, true));
}

// A head machine's report, even one carrying location_errors, is refused at its line: no head
// kinematics has the papers' table errors that compensate rewrites programs with (before head_table
// was refused here, its location-error lookup threw std::invalid_argument without a file).
TEST(ReportErrors, AHeadMachinesReportIsRefusedAtItsLine) {
  for (const Kinematics k : {Kinematics::HeadAB, Kinematics::HeadTable, Kinematics::HeadCB}) {
    const std::string text = std::string(R"({"format": "rotacal-report/1", "cycle": "x",
 "machine_model": ")") + std::string(kinematicsName(k)) + R"(",
 "location_errors": {"dx_AY": {"value": 3.0, "u": 0.2, "unit": "um"}}})";
    try {
      (void)errorsFromReports({parseJsonText(text, "r.json")}, k, false);
      FAIL() << kinematicsName(k) << " was compensated";
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), 2) << e.what();
      EXPECT_NE(std::string(e.what()).find(kinematicsName(k)), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace rotacal
