// The battery every dialect with its own results text passes (dialect_battery.hpp): the round
// trip within the printed digits in mm and in inch, the recovery of injected errors, and the
// checker on the generated programs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <sstream>
#include <cctype>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "controllers/dialect.hpp"
#include "core/machine.hpp"
#include "cycles/cycle.hpp"
#include "dialect_battery.hpp"
#include "dialect_lists.hpp"
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

// What each controller prints, one entry a dialect with programs (the neutral csv's one form:
// csv_test).
const std::vector<Printed> kPrinted = {
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
            {{1, "P1 X53.5840 Y-235.0000 Z150.0000"}}}
#ifdef ROTACAL_TEST_DIALECT_PRINTED
// The entry of a dialect that only a test program registers (tests/controllers/throwaway/).
#include ROTACAL_TEST_DIALECT_PRINTED
#endif
};

INSTANTIATE_TEST_SUITE_P(Dialects, EveryDialect, ::testing::ValuesIn(kPrinted),
                         [](const ::testing::TestParamInfo<Printed>& info) { return info.param.dialect; });

// A dialect added to the registry without its entry above would escape the battery silently.
TEST(EveryDialectBattery, TakesEveryDialectWithPrograms) {
  std::vector<std::string> listed;
  for (const auto& p : kPrinted) listed.push_back(p.dialect);
  std::sort(listed.begin(), listed.end());
  std::vector<std::string> want = test::programDialects();
  std::sort(want.begin(), want.end());
  EXPECT_EQ(listed, want);
}

// Every program's header says what its X Y Z are and where the zero goes, for the machine it was
// planned on: the probe-ball centre at the rotary axes' intersection on a table, the head's pivot
// with the ball hanging pivot_to_ball_mm from it on a head (an operator who sets up a head machine
// as a table puts the ball that far from where the plan expects it), and the convention its angles
// follow. Read from each dialect's text as the operator reads it (comment delimiters, block
// numbers, line breaks and case aside); expected values from the machine file, not from the code
// that writes the header.
TEST(ProgramHeader, EveryKinematicsAndDialectStatesItsControlledPointZeroAndAngleConvention) {
  auto readable = [](const std::string& text) {
    std::string out;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      size_t i = 0;
      while (i < line.size() && std::isdigit(static_cast<unsigned char>(line[i]))) ++i;  // Heidenhain's block number
      for (; i < line.size(); ++i) {
        const char ch = line[i];
        if (ch == '(' || ch == ')' || ch == ';' || ch == '[' || ch == ']') continue;
        out += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      }
      out += ' ';
    }
    std::string squeezed;
    for (char ch : out)
      if (!(ch == ' ' && !squeezed.empty() && squeezed.back() == ' ')) squeezed += ch;
    return squeezed;
  };
  int checked = 0;
  for (const char* name : {"ac_trunnion", "bc_trunnion", "bc_head_table", "ab_head", "head_ab", "bc_head"}) {
    const MachineModel m = loadMachine(test::sourcePath(std::string("examples/machines/") + name + ".json"));
    ProbePlan plan;
    try {
      plan = makePlan("one_sphere", m, {});
    } catch (const std::invalid_argument&) {
      continue;  // head_ab.json carries a tester's sphere, no probe: no probing program
    }
    const bool head = hasSpindleHead(m.kinematics);
    for (const std::string& d : dialectNames()) {
      if (d == "csv") continue;
      std::string text;
      try {
        text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
      } catch (const std::invalid_argument&) {
        continue;  // a dialect that cannot express this machine's program refuses it (and says why)
      }
      const std::string h = readable(text);
      const std::string where = std::string(name) + " / " + d;
      if (head) {
        EXPECT_NE(h.find("PIVOT"), std::string::npos) << where;
        EXPECT_NE(h.find("NOT THE BALL"), std::string::npos) << where;
        EXPECT_NE(h.find(fmt::format("{:.3f} MM FROM IT", m.head->pivot_to_ball_mm)), std::string::npos) << where;
        EXPECT_EQ(h.find("INTERSECTION OF THE ROTARY AXES"), std::string::npos) << where;
        EXPECT_NE(h.find("ISO 841"), std::string::npos) << where;
      } else {
        EXPECT_NE(h.find("BALL CENTRE"), std::string::npos) << where;
        EXPECT_NE(h.find("INTERSECTION OF THE ROTARY AXES"), std::string::npos) << where;
        EXPECT_EQ(h.find("PIVOT"), std::string::npos) << where;
        EXPECT_NE(h.find(m.kinematics == Kinematics::TableAC ? "000 EQ. 1" : "002 EQ. 2"), std::string::npos)
            << where << ": " << h.substr(0, 600);
      }
      ++checked;
    }
  }
  // 4 machines with a probe x 6 dialects, less what a dialect refuses (Heidenhain cycle 0 on the A/B head)
  EXPECT_GE(checked, 20);
}

}  // namespace
}  // namespace rotacal
