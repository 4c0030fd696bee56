// The battery every dialect with its own results text passes (dialect_battery.hpp): the round
// trip within the printed digits in mm and in inch, the recovery of injected errors, and the
// checker on the generated programs.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "dialect_battery.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

struct Printed {
  std::string dialect;
  int mm_decimals;      // the decimals of a mm machine's results
  double inch_unit_mm;  // the unit an inch machine's results are printed in
  int inch_decimals;
  test::Clock clock;
  /// What the controller prints first for point 1 at (53.58401, -235, 150) mm triggered
  /// 750000000.9 s after 2000-01-01 (2023-10-07 13:20:00.9, Python's datetime): the header, and
  /// the point's lines where they do not depend on the plan's times (haas's clock lines are
  /// relative to the first trigger: haas_test).
  std::vector<std::string> first_lines;
  /// The file's last line ("": none after the last point's).
  std::string last_line = "END";
  /// Point 1's lines as the control may also print them (index in the file, text), read back as
  /// (53.584, -235, 150) mm at `accepted_t_s` (NaN: the dialect prints no clock).
  std::vector<std::pair<size_t, std::string>> accepted = {};
  double accepted_t_s = std::numeric_limits<double>::quiet_NaN();
};

class EveryDialect : public ::testing::TestWithParam<Printed> {
 protected:
  const Dialect& d() const { return dialectByName(GetParam().dialect); }
};

TEST_P(EveryDialect, RoundTripWithinThePrintedDigits) {
  const Printed& p = GetParam();
  test::expectRoundTrip(d(), test::acPlan(), 1.0, p.mm_decimals, p.clock);
  test::expectRoundTrip(d(), test::acPlan(LengthUnit::Inch), p.inch_unit_mm, p.inch_decimals, p.clock);
}

TEST_P(EveryDialect, PrintsThePointsAsTheControllersOutputStatementWould) {
  const ProbePlan plan = test::acPlan();
  MeasurementRun run;
  run.points.push_back({1, Eigen::Vector3d(53.58401, -235.0, 150.0), 750000000.9});
  const auto ls = test::lines(d().writeResults(plan, run));
  const auto& want = GetParam().first_lines;
  ASSERT_GE(ls.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_EQ(ls[i], want[i]) << "line " << i + 1;
  if (!GetParam().last_line.empty()) {
    EXPECT_EQ(ls.back(), GetParam().last_line);
  }
}

TEST_P(EveryDialect, ReadsTheFormsTheControlMayPrint) {
  const Printed& p = GetParam();
  // Haas shares Macro B's reader (its other forms: fanuc_test); LOG prints one form (line ends
  // and spaces a hand edit may leave: linuxcnc_test).
  if (p.accepted.empty()) GTEST_SKIP() << "the written form is the only one";
  const ProbePlan plan = test::acPlan();
  auto ls = test::lines(d().writeResults(plan, test::displacedRun(plan)));
  for (const auto& [i, text] : p.accepted) ls[i] = text;
  const MeasurementRun back = d().parseResults(test::join(ls, "\r\n"), "res.txt", plan);
  EXPECT_EQ(back.points[0].position_m_mm, Eigen::Vector3d(53.584, -235.0, 150.0));
  if (!std::isnan(p.accepted_t_s)) {
    EXPECT_EQ(back.points[0].t_s, p.accepted_t_s);
  }
}

TEST_P(EveryDialect, RecoversInjectedErrors) { test::expectRecovery(d(), test::acPlan()); }

TEST_P(EveryDialect, GeneratedProgramsPassTheChecker) { test::expectCleanPrograms(d()); }

INSTANTIATE_TEST_SUITE_P(Dialects, EveryDialect,
                         ::testing::Values(
                             // DPRNT [44] and [35] (000's units), #3001 in whole ms; CR LF like
                             // a punch.
                             Printed{"fanuc", 4, 25.4, 5, test::Clock::Milliseconds,
                                     {"ROTACAL-RESULTS DIALECT FANUC CYCLE TOUCH154 POINTS 154 UNIT MM",
                                      "DATE 20231007 TIME 132000", "P1 X  53.5840 Y-235.0000 Z 150.0000 T     900"},
                                     "END",
                                     // leading zeros (parameter 6001) and [80]'s trailing point;
                                     // 2026-11-22 01:41:19 + 12.345 s (Python's datetime)
                                     {{1, "DATE 20261122 TIME 014119"}, {2, "P1 X0053.5840 Y-0235.0000 Z  150.0000 T 12345."}},
                                     848626879.0 + 12.345},
                             Printed{"haas", 4, 25.4, 5, test::Clock::Milliseconds,
                                     {"ROTACAL-RESULTS DIALECT HAAS CYCLE TOUCH154 POINTS 154 UNIT MM"}},
                             // Klartext programs are written in MM whatever the machine, and so
                             // are their results; FN 16 prints the decimal comma of a German
                             // language setting.
                             Printed{"heidenhain", 4, 1.0, 4, test::Clock::Seconds,
                                     {"ROTACAL HEIDENHAIN CYCLE TOUCH154 POINTS 154 UNIT MM",
                                      "P    1 X   53,5840 Y -235,0000 Z  150,0000", "T20231007 132000"},
                                     "END",
                                     // a point or a comma, an explicit sign; 2024-02-29 23:59:59
                                     // (Python's datetime)
                                     {{1, "P1 X53.5840 Y-235,0000 Z +150.0000"}, {2, "T20240229 235959"}},
                                     762566399.0},
                             // LOG's %.6f, the angles of point 1's pose with LinuxCNC's sign, the
                             // probe's state; no clock, nothing after the last point.
                             Printed{"linuxcnc", 6, 25.4, 6, test::Clock::None,
                                     {"rotacal-results/1 dialect=linuxcnc cycle=touch154 points=154 unit=mm",
                                      "P1 53.584010 -235.000000 150.000000 0.0000 0.0000 1"},
                                     ""},
                             Printed{"okuma", 4, 25.4, 5, test::Clock::None,
                                     {"ROTACAL-RESULTS DIALECT OKUMA CYCLE TOUCH154 POINTS 154 UNIT MM"},
                                     "END",
                                     // '+', spaces and leading zeros
                                     {{1, "P1 X+53.5840 Y-235.0000 Z 0150.0000"}}},
                             // SPRINT's %10.4F
                             Printed{"siemens", 4, 25.4, 5, test::Clock::None,
                                     {"ROTACAL-RESULTS DIALECT SIEMENS CYCLE TOUCH154 POINTS 154 UNIT MM",
                                      "P1 X   53.5840 Y -235.0000 Z  150.0000"},
                                     "END",
                                     // %F without a width
                                     {{1, "P1 X53.5840 Y-235.0000 Z150.0000"}}}),
                         [](const ::testing::TestParamInfo<Printed>& info) { return info.param.dialect; });

}  // namespace
}  // namespace rotacal
