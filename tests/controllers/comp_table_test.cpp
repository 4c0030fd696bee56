// Rotary-axis compensation tables (controllers/comp_table.hpp, docs/dialects.md "Compensation
// tables"). Every table is read back by this test's own parser and compared with the error
// computed another way: a Fourier series evaluated in closed form. The sign is proven on a closed
// loop: a table on its axis, turned by the table's own compensation as the control applies it,
// puts a point of the table where the nominal machine puts it (rotation matrices, the papers'
// definition of E_CC: it turns the table about +Z).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "controllers/comp_table.hpp"

namespace rotacal::ctl {
namespace {

constexpr double kPi = 3.14159265358979323846;
double rad(double deg) { return deg * kPi / 180.0; }

/// E_CC of a machine (mdeg) in the papers' convention, closed form: harmonics 1..5 of a 12-angle
/// identification (k < N/2), no mean.
double eccTrue_mdeg(double c_deg) {
  const double c = rad(c_deg);
  return 3.0 * std::cos(c) - 1.2 * std::sin(c) + 2.0 * std::sin(2 * c) + 0.7 * std::cos(3 * c) - 0.4 * std::sin(5 * c);
}

AngularPositionErrors sampled(int n, double start_deg = 0.0) {
  AngularPositionErrors e;
  for (int j = 0; j < n; ++j) {
    const double c = start_deg + j * 360.0 / n;
    e.angle_deg.push_back(c);
    e.error_mdeg.push_back(eccTrue_mdeg(c));
    e.u_mdeg.push_back(0.01);
  }
  return e;
}

/// The error the control sees, in its own counting (deg): the table reaches the papers' angle
/// C - E(C) (E turns it about +Z, the commanded C turns it by -C), and theta = s C.
double closedFormError_deg(double theta, int s) {
  const double c = s * theta;
  const double actual_c = c - eccTrue_mdeg(c) * 1e-3;
  return s * actual_c - theta;
}

TEST(PeriodicInterpolant, ReproducesAFourierSeriesExactlyBetweenTheSamples) {
  for (const double start : {0.0, 15.0, -40.0}) {
    const auto e = sampled(12, start);
    const PeriodicInterpolant f(e.angle_deg, e.error_mdeg);
    for (double c = -400.0; c <= 400.0; c += 2.5) EXPECT_NEAR(f(c), eccTrue_mdeg(c), 1e-12) << "start " << start << " C " << c;
  }
  // odd N: harmonics up to (N-1)/2 = 5
  const auto e9 = sampled(11, 3.0);
  const PeriodicInterpolant f9(e9.angle_deg, e9.error_mdeg);
  for (double c = 0.0; c < 360.0; c += 7.0) EXPECT_NEAR(f9(c), eccTrue_mdeg(c), 1e-12);
  // samples given out of order
  auto r = sampled(12);
  std::swap(r.angle_deg[2], r.angle_deg[7]);
  std::swap(r.error_mdeg[2], r.error_mdeg[7]);
  const PeriodicInterpolant fr(r.angle_deg, r.error_mdeg);
  EXPECT_NEAR(fr(123.4), eccTrue_mdeg(123.4), 1e-12);
  // the Nyquist term cos(N/2 C) of an even N is reproduced too
  std::vector<double> a, v;
  for (int j = 0; j < 8; ++j) a.push_back(j * 45.0), v.push_back(std::cos(4 * rad(j * 45.0)));
  const PeriodicInterpolant fn(a, v);
  EXPECT_NEAR(fn(10.0), std::cos(4 * rad(10.0)), 1e-12);
}

TEST(PeriodicInterpolant, RefusesSamplesThatAreNotEquallySpacedOverATurn) {
  auto e = sampled(12);
  e.angle_deg[5] += 0.01;
  EXPECT_THROW(PeriodicInterpolant(e.angle_deg, e.error_mdeg), std::invalid_argument);
  EXPECT_THROW(PeriodicInterpolant({0.0, 90.0, 180.0}, {1.0, 2.0, 3.0}), std::invalid_argument);  // 3 over 270 deg
  EXPECT_THROW(PeriodicInterpolant({0.0, 180.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(PeriodicInterpolant({0.0, 120.0, 240.0}, {1.0, NAN, 3.0}), std::invalid_argument);
  EXPECT_THROW(PeriodicInterpolant({0.0, 120.0, 120.0}, {1.0, 2.0, 3.0}), std::invalid_argument);
  EXPECT_NO_THROW(PeriodicInterpolant({0.0, 120.0, 240.0}, {1.0, 2.0, 3.0}));
}

CompTable write(const std::string& dialect, int sign, double step = 0.0) {
  CompTableRequest r;
  r.errors = sampled(12);
  r.dialect = dialect;
  r.controller_sign = sign;
  r.step_deg = step;
  r.source = "REPORT (1).json";
  return writeCompTable(r);
}

// ---- the test's own parsers ----

struct LinuxcncRow {
  double nominal, fwd, rev;
};
/// As LinuxCNC's usrmotLoadComp reads it: triplets until the first line that is not one.
std::vector<LinuxcncRow> parseLinuxcnc(const std::string& text) {
  std::vector<LinuxcncRow> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    LinuxcncRow r{};
    if (std::sscanf(line.c_str(), "%lf %lf %lf", &r.nominal, &r.fwd, &r.rev) != 3) break;
    rows.push_back(r);
  }
  return rows;
}

TEST(CompTable, LinuxcncTypeZeroReadBackIsTheErrorAtEveryNominal) {
  for (const int s : {1, -1}) {
    const CompTable t = write("linuxcnc", s);
    const auto rows = parseLinuxcnc(t.text);
    ASSERT_EQ(rows.size(), 145u) << "-360 .. 360 every 5 deg";
    EXPECT_LE(rows.size(), 256u);
    EXPECT_DOUBLE_EQ(rows.front().nominal, -360.0);
    EXPECT_DOUBLE_EQ(rows.back().nominal, 360.0);
    double worst = 0.0;
    for (size_t i = 0; i < rows.size(); ++i) {
      if (i > 0) {
        EXPECT_GT(rows[i].nominal, rows[i - 1].nominal);  // LinuxCNC refuses a non-increasing nominal
      }
      EXPECT_EQ(rows[i].fwd, rows[i].rev);
      const double want = closedFormError_deg(rows[i].nominal, s);
      EXPECT_NEAR(rows[i].fwd - rows[i].nominal, want, 1.01e-6) << "sign " << s << " nominal " << rows[i].nominal;
      worst = std::max(worst, std::fabs(want));
    }
    EXPECT_GT(worst, 4e-3) << "a table of a few mdeg, not of zeros";
    // the comments come after the data: the loader stops at them, having read every row
    EXPECT_NE(t.text.find("\n# rotacal comp-table"), std::string::npos);
    EXPECT_NE(t.text.find("COMP_FILE_TYPE = 0"), std::string::npos);
    EXPECT_EQ(t.rows.size(), rows.size());
  }
}

struct FanucSheet {
  std::map<std::string, std::string> params;
  std::vector<std::pair<int, long>> points;  // number, value
  std::vector<double> angles;
};
FanucSheet parseFanuc(const std::string& text) {
  FanucSheet s;
  std::istringstream in(text);
  std::string line;
  const std::regex param(R"(^(36\d\d(?:#0)?) = ([-0-9.]+).*)");
  const std::regex point(R"(^\s*(\d+)\s+([-0-9.]+)\s+([-+]\d+)\s*$)");
  bool table = false;
  std::smatch m;
  while (std::getline(in, line)) {
    if (line == "POINT  ANGLE_DEG  VALUE") {
      table = true;
      continue;
    }
    if (line == "END") break;
    if (table) {
      EXPECT_TRUE(std::regex_match(line, m, point)) << line;
      s.points.emplace_back(std::stoi(m[1]), std::stol(m[3]));
      s.angles.push_back(std::stod(m[2]));
    } else if (std::regex_match(line, m, param)) {
      s.params[m[1].str()] = m[2].str();
    }
  }
  return s;
}

TEST(CompTable, FanucIncrementsSumToTheCorrectionAndToZeroOverTheTurn) {
  for (const int s : {1, -1}) {
    const CompTable t = write("fanuc", s, 7.5);
    const FanucSheet f = parseFanuc(t.text);
    ASSERT_EQ(f.points.size(), 49u);  // points 0 .. 48
    EXPECT_EQ(f.params.at("3620"), "0");
    EXPECT_EQ(f.params.at("3621"), "0");
    EXPECT_EQ(f.params.at("3622"), "48");
    EXPECT_EQ(f.params.at("3623"), "1");
    EXPECT_EQ(f.params.at("3624"), "7.500");
    EXPECT_EQ(f.params.at("3625"), "360.000");
    EXPECT_EQ(f.params.at("3605#0"), "0");
    EXPECT_EQ(f.points.front().second, f.points.back().second) << "point 3620 holds the value of point 3622";
    long sum = 0;
    const double e0 = closedFormError_deg(0.0, s);
    for (size_t k = 1; k < f.points.size(); ++k) {
      EXPECT_EQ(f.points[k].first, static_cast<int>(k));
      sum += f.points[k].second;
      // the compensation applied at the point = sum of the increments so far (0.001 deg each);
      // it cancels the error relative to the reference position, within the rounding of both
      const double applied_deg = sum * 1e-3;
      const double want = -(closedFormError_deg(f.angles[k], s) - e0);
      EXPECT_NEAR(applied_deg, want, 1.0e-3 + 1e-12) << "point " << k;
      EXPECT_NEAR(f.angles[k], 7.5 * static_cast<double>(k), 1e-9);
    }
    EXPECT_EQ(sum, 0) << "the increments over one turn must sum to zero (no accumulation per rotation)";
  }
  // a finer detection unit (IS-C, 0.0001 deg): the same sums, ten times finer
  CompTableRequest r;
  r.errors = sampled(12);
  r.dialect = "fanuc";
  r.fanuc_detection_unit_deg = 1e-4;
  const FanucSheet f = parseFanuc(writeCompTable(r).text);
  long sum = 0;
  const double e0 = closedFormError_deg(0.0, 1);
  for (size_t k = 1; k < f.points.size(); ++k) {
    sum += f.points[k].second;
    EXPECT_NEAR(sum * 1e-4, -(closedFormError_deg(f.angles[k], 1) - e0), 1.0e-4 + 1e-12) << "point " << k;
  }
  EXPECT_EQ(sum, 0);
  EXPECT_EQ(f.params.at("3624"), "5.000");
}

TEST(CompTable, SiemensEncCompValuesAreTheErrorOverAModuloTurn) {
  for (const int s : {1, -1}) {
    const CompTable t = write("siemens", s);
    std::istringstream in(t.text);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "%_N_AX_EEC_INI");
    const std::regex value(R"(^\$AA_ENC_COMP\[0,(\d+),C1\]=(-?\d+\.\d{6})$)");
    std::map<std::string, std::string> table_params;
    const std::regex param(R"(^\$AA_ENC_COMP_(STEP|MIN|MAX|IS_MODULO)\[0,C1\]=(\S+)$)");
    std::vector<double> v;
    std::smatch m;
    bool chandata = false, m17 = false;
    while (std::getline(in, line)) {
      if (line.rfind(";", 0) == 0) continue;
      if (line == "CHANDATA(1)") {
        chandata = true;
      } else if (line == "M17") {
        m17 = true;
      } else if (std::regex_match(line, m, value)) {
        EXPECT_EQ(std::stoul(m[1]), v.size());
        v.push_back(std::stod(m[2]));
      } else if (std::regex_match(line, m, param)) {
        table_params[m[1].str()] = m[2].str();
      } else {
        ADD_FAILURE() << "unexpected line " << line;
      }
    }
    EXPECT_TRUE(chandata && m17);
    EXPECT_EQ(table_params["STEP"], "5.0000");
    EXPECT_EQ(table_params["MIN"], "0.0");
    EXPECT_EQ(table_params["MAX"], "360.0");
    EXPECT_EQ(table_params["IS_MODULO"], "1");
    ASSERT_EQ(v.size(), 73u);
    EXPECT_EQ(v.front(), v.back()) << "modulo: the values at 0 and 360 deg are one";
    for (size_t k = 0; k < v.size(); ++k)
      EXPECT_NEAR(v[k], closedFormError_deg(5.0 * static_cast<double>(k), s), 5.01e-7) << "point " << k;
  }
}

TEST(CompTable, CsvIsTheErrorInMdeg) {
  const CompTable t = write("csv", -1, 10.0);
  std::istringstream in(t.text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "controller_angle_deg,error_mdeg");
  int n = 0;
  while (std::getline(in, line)) {
    double th = 0, e = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf", &th, &e), 2) << line;
    EXPECT_NEAR(e, closedFormError_deg(th, -1) * 1e3, 1e-6);
    ++n;
  }
  EXPECT_EQ(n, 36);
}

// ---- the closed loop: the sign, from the physics of E_CC ----

/// Where the machine puts table point p when its axis motor stands at the control's angle
/// theta_m: the table turns about +Z by -C_m + E(C_m), C_m = s theta_m (E_CC turns it about +Z).
Eigen::Vector3d truePosition(double theta_m, int s, const Eigen::Vector3d& p) {
  const double c = s * theta_m;
  return Eigen::AngleAxisd(rad(-c + eccTrue_mdeg(c) * 1e-3), Eigen::Vector3d::UnitZ()) * p;
}
Eigen::Vector3d nominalPosition(double theta, int s, const Eigen::Vector3d& p) {
  return Eigen::AngleAxisd(rad(-s * theta), Eigen::Vector3d::UnitZ()) * p;
}

TEST(CompTable, ClosedLoopEveryDialectsTablePutsTheTableWhereTheNominalMachineDoes) {
  const Eigen::Vector3d p(220.0, 0.0, 100.0);  // a sphere 220 mm from the axis, as spheres3's
  for (const int s : {1, -1}) {
    // LinuxCNC: motor = command + (nominal - actual), interpolated linearly between the rows
    {
      const auto rows = parseLinuxcnc(write("linuxcnc", s).text);
      double before = 0.0, after = 0.0;
      for (double th = -355.0; th <= 355.0; th += 3.7) {
        size_t i = 0;
        while (rows[i + 1].nominal <= th) ++i;
        const double f = (th - rows[i].nominal) / (rows[i + 1].nominal - rows[i].nominal);
        const double trim = (1 - f) * (rows[i].nominal - rows[i].fwd) + f * (rows[i + 1].nominal - rows[i + 1].fwd);
        before = std::max(before, (truePosition(th, s, p) - nominalPosition(th, s, p)).norm());
        after = std::max(after, (truePosition(th + trim, s, p) - nominalPosition(th, s, p)).norm());
      }
      EXPECT_GT(before, 0.015) << "mm: the error moves the point by about 20 um";
      EXPECT_LT(after, 0.02 * before) << "linuxcnc sign " << s << ": " << after * 1e3 << " um left of " << before * 1e3;
      std::printf("linuxcnc, sign %+d: point 220 mm from the axis off by %.3f um before, %.4f um after\n", s,
                  before * 1e3, after * 1e3);
    }
    // Fanuc: at point k the applied compensation is the sum of the increments so far (relative to
    // the reference position, whose own error stays: compare with the nominal turned by it)
    {
      const FanucSheet f = parseFanuc(write("fanuc", s).text);
      double before = 0.0, after = 0.0;
      long sum = 0;
      const double e0 = closedFormError_deg(0.0, s);
      for (size_t k = 1; k < f.points.size(); ++k) {
        sum += f.points[k].second;
        const double th = f.angles[k];
        before = std::max(before, (truePosition(th, s, p) - nominalPosition(th + e0, s, p)).norm());
        after = std::max(after, (truePosition(th + sum * 1e-3, s, p) - nominalPosition(th + e0, s, p)).norm());
      }
      EXPECT_GT(before, 0.01);
      EXPECT_LT(after, 0.004) << "mm: within the 0.001 deg detection unit at 220 mm (3.8 um) for sign " << s;
      std::printf("fanuc, sign %+d: %.3f um before, %.4f um after\n", s, before * 1e3, after * 1e3);
    }
    // Siemens: a positive compensation value moves the axis in the negative direction
    {
      const std::string text = write("siemens", s).text;
      const std::regex value(R"(\$AA_ENC_COMP\[0,(\d+),C1\]=(-?\d+\.\d+))");
      double before = 0.0, after = 0.0;
      for (auto it = std::sregex_iterator(text.begin(), text.end(), value); it != std::sregex_iterator(); ++it) {
        const double th = 5.0 * std::stoi((*it)[1]);
        const double v = std::stod((*it)[2]);
        before = std::max(before, (truePosition(th, s, p) - nominalPosition(th, s, p)).norm());
        after = std::max(after, (truePosition(th - v, s, p) - nominalPosition(th, s, p)).norm());
      }
      EXPECT_GT(before, 0.015);
      EXPECT_LT(after, 1e-5) << "mm, sign " << s;
      std::printf("siemens, sign %+d: %.3f um before, %.5f um after\n", s, before * 1e3, after * 1e3);
    }
  }
}

TEST(CompTable, RefusesWhatItCannotWriteSafely) {
  CompTableRequest r;
  r.errors = sampled(12);
  for (const char* d : {"heidenhain", "okuma", "haas", "klartext"}) {
    r.dialect = d;
    try {
      writeCompTable(r);
      ADD_FAILURE() << d << " was written";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(d), std::string::npos) << e.what();
    }
    EXPECT_FALSE(compTableRefusal(d).empty());
  }
  EXPECT_TRUE(compTableRefusal("linuxcnc").empty());
  r.dialect = "linuxcnc";
  r.step_deg = 7.0;  // 360 / 7 is no whole number
  EXPECT_THROW(writeCompTable(r), std::invalid_argument);
  EXPECT_FALSE(stepRefusal(7.0).empty());
  EXPECT_TRUE(stepRefusal(7.5).empty());
  r.step_deg = 2.0;  // -360 .. 360 every 2 deg: 361 rows > 256
  try {
    writeCompTable(r);
    ADD_FAILURE() << "361 rows written";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("at most 256"), std::string::npos) << e.what();
  }
  r.range_lo_deg = -20.0;  // a finite stroke: 2 deg fits
  r.range_hi_deg = 110.0;
  EXPECT_EQ(parseLinuxcnc(writeCompTable(r).text).size(), 66u);
  // plausibility: an error of 150 mdeg is a blunder unless forced
  r.step_deg = 0.0;
  for (auto& v : r.errors.error_mdeg) v *= 40.0;
  try {
    writeCompTable(r);
    ADD_FAILURE() << "150 mdeg written without force";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("plausibility limit of 100 mdeg"), std::string::npos) << e.what();
  }
  r.force = true;
  EXPECT_GT(writeCompTable(r).max_error_mdeg, 100.0);
}

}  // namespace
}  // namespace rotacal::ctl
