// The Fanuc Macro B dialect (its round trip, recovery and clean programs: battery_test): the
// date on the 2000 epoch and CR LF, the parser accepts the forms DPRNT may print and names the
// line of every fault, the probing block and the #700 storage, the checker catches planted
// faults, and the G54 correction is written.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <regex>

#include "controllers/macro_b.hpp"
#include "core/errors.hpp"
#include "core/units.hpp"
#include "ctl_test_util.hpp"
#include "dialect_battery.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {
namespace {

using test::lines;
using test::messageOf;

// #3001 is printed in whole ms.
constexpr double kTimerRoundingS = 0.5e-3 + 1e-12;

const Dialect& fc() { return dialectByName("fanuc"); }

TEST(FanucResults, DprntNumberIsRightAlignedWithTheSignBeforeTheDigits) {
  EXPECT_EQ(macro_b::dprntNumber(123.456, 4, 4), " 123.4560");
  EXPECT_EQ(macro_b::dprntNumber(-200.0, 4, 4), "-200.0000");
  EXPECT_EQ(macro_b::dprntNumber(-12.34561, 4, 4), " -12.3456");
  EXPECT_EQ(macro_b::dprntNumber(-0.00001, 4, 4), "   0.0000") << "never -0.0000";
  EXPECT_EQ(macro_b::dprntNumber(12345.0, 9, 0), "    12345");
  EXPECT_EQ(macro_b::dprntNumber(-1234.5, 4, 4), "-1234.5000") << "widened when it does not fit";
}

TEST(FanucResults, DateOfTheFirstTriggerOnThe2000EpochAndCrLf) {
  const ProbePlan plan = test::acPlan();
  const std::string text = fc().writeResults(plan, test::displacedRun(plan));
  // The run starts at 0 s, the first point is probed at the plan's t_s + 0.25 s (< 60 s, so
  // HHMMSS is that many seconds).
  const long first_s = static_cast<long>(std::floor(plan.points[0].t_s + 0.25));
  ASSERT_LT(first_s, 60);
  EXPECT_EQ(lines(text)[1], fmt::format("DATE 20000101 TIME {:>6}", first_s));
  EXPECT_NE(text.find("\r\n"), std::string::npos) << "CR LF like a Fanuc punch";
}

TEST(FanucResults, ParserAcceptsTheFormsDprntMayPrint) {
  const ProbePlan plan = test::acPlan();
  auto ls = lines(fc().writeResults(plan, test::displacedRun(plan)));
  ls[1] = "DATE 20261122 TIME 014119";  // leading zero (parameter 6001) instead of a space
  ls[2] = "P1 X0051.0010 Y-0235.0000 Z  150.0000 T 12345.";
  ls[3] = "P2 X51.0010 Y  -215.0000 Z150.0000 T00012346";  // [80] with leading zeros
  ls[4] = "  P3   X 51.0010   Y-185.0000   Z 150.0000   T    12347  ";
  std::string text = "\x12%\r\n";  // DC2 of POPEN and a tape mark
  for (size_t i = 0; i < ls.size(); ++i) text += ls[i] + (i % 2 ? "\r" : "\r\n");
  text += "%\x14";
  const MeasurementRun back = fc().parseResults(text, "res.txt", plan);
  ASSERT_EQ(back.points.size(), plan.points.size());
  EXPECT_EQ(back.points[0].position_m_mm, Eigen::Vector3d(51.001, -235.0, 150.0));
  // 2026-11-22 01:41:19 is 848626879 s after 2000-01-01 00:00:00 (Python's datetime).
  EXPECT_DOUBLE_EQ(back.points[0].t_s, 848626879.0 + 12.345);
  EXPECT_EQ(back.points[1].position_m_mm.y(), -215.0);
  EXPECT_DOUBLE_EQ(back.points[1].t_s, 848626879.0 + 12.346);
  EXPECT_DOUBLE_EQ(back.points[2].t_s, 848626879.0 + 12.347);
}

class FanucRejects : public test::WrittenResults {
 protected:
  FanucRejects() : WrittenResults("fanuc", "\r\n") {}
};

TEST_F(FanucRejects, MissingPointAtTheLastLine) {
  expectAt([](auto& v) { v.erase(v.begin() + 45); }, kLastLine, "point 44 is missing");  // lines: header, DATE, P1 ...
}

TEST_F(FanucRejects, ProgramThatStoppedEarlyHasNoEnd) {
  // header + DATE + 44 points: the alarm stopped the program
  expectAt([](auto& v) { v.resize(46); }, 46, "point 45 is missing and there is no END line");
  expectAt([](auto& v) { v.pop_back(); }, kLastLine, "no END line");
}

TEST_F(FanucRejects, DuplicatedPointAtItsSecondLine) {
  expectAt([&](auto& v) { v.insert(v.begin() + 10, ls[9]); }, 11, "point 8 appears twice (first at line 10)");
}

TEST_F(FanucRejects, PointIdNotInThePlan) {
  // Before END: the edited file's last line but one.
  expectAt([](auto& v) { v.insert(v.end() - 1, "P200 X 1.0000 Y 2.0000 Z 3.0000 T 5"); }, ls.size(),
           "point 200 is not in the plan");
}

TEST_F(FanucRejects, CoordinateThatIsNotANumber) {
  expectAt([](auto& v) { v[6] = "P6 X 12.3456 Y****.**** Z 1.0000 T 5"; }, 7, "Y '****.****' of point 6 is not a number");
  expectAt([](auto& v) { v[6] = "P6 X 1.2.3 Y 1.0000 Z 1.0000 T 5"; }, 7, "X '1.2.3' of point 6 is not a number");
}

TEST_F(FanucRejects, HeaderWithTheWrongPointCount) {
  expectAt([](auto& v) { v[0] = "ROTACAL-RESULTS DIALECT FANUC CYCLE TOUCH154 POINTS 150 UNIT MM"; }, 1,
           "header says POINTS 150 but the plan has 154 points");
}

TEST_F(FanucRejects, TextAfterEnd) {
  expectAt([](auto& v) { v.push_back("P1 X 1.0000 Y 2.0000 Z 3.0000 T 5"); }, kLastLine, "text after END");
}

TEST(FanucProgram, FrameAndProbeBlock) {
  const test::WrittenProgram p("fanuc", "^G31");
  EXPECT_EQ(p.ls[0], "%");
  EXPECT_EQ(p.ls[1], "O7154(ROTACAL TOUCH154)");
  EXPECT_EQ(p.ls[p.ls.size() - 2], "M30");
  EXPECT_EQ(p.text.find("-0.0000"), std::string::npos);
  for (const auto& l : p.ls) {
    EXPECT_LE(l.size(), 80u) << l;
    EXPECT_EQ(l.find_first_of("abcdefghijklmnopqrstuvwxyz"), std::string::npos) << l;
  }
  EXPECT_EQ(p.ls[p.g], "G31 X51.0000 Y-235.0000 Z150.0000 F100.0");
  EXPECT_EQ(p.ls[p.g + 1], "#1=#5061-51.0000");
  EXPECT_EQ(p.ls[p.g + 2], "#2=#5062+235.0000");
  EXPECT_EQ(p.ls[p.g + 4], "IF[[#1*#1+#2*#2+#3*#3]GT0.0001]GOTO1001");
  EXPECT_EQ(p.ls[p.g + 5], "#3000=1(POINT 1 NOT TRIGGERED)");
  EXPECT_EQ(p.ls[p.g + 6], "N1001");
  EXPECT_EQ(p.ls[p.g + 7], "#700=#5061");
  EXPECT_EQ(p.ls[p.g + 10], "#703=#3001");
  EXPECT_NE(p.text.find("\nDPRNT[P1*X#700[44]*Y#701[44]*Z#702[44]*T#703[80]]\n"), std::string::npos);
  EXPECT_NE(p.text.find("\nDPRNT[END]\nPCLOS\nM30\n%\n"), std::string::npos);
}

TEST(FanucProgram, InchProgramUsesG20AndFiveInchDecimals) {
  const test::WrittenProgram p("fanuc", "^G31", LengthUnit::Inch);
  EXPECT_NE(p.text.find("\nG20\n"), std::string::npos);
  EXPECT_NE(p.text.find("]GT0.000001]GOTO1001\n"), std::string::npos) << "(0.001 in)^2 no-trigger threshold";
  EXPECT_NE(p.text.find("\nDPRNT[P1*X#700[35]*Y#701[35]*Z#702[35]*T#703[80]]\n"), std::string::npos) << "5 inch decimals";
}

TEST(FanucProgram, StoredVariablesRestartAtEachPose) {
  const test::WrittenProgram p("fanuc", "^G31");
  // The first point of every pose is stored at #700 and printed before the next index move.
  int first_of_pose = 0;
  for (size_t i = 0; i < p.plan.points.size(); ++i)
    first_of_pose += i == 0 || p.plan.points[i].pose_name != p.plan.points[i - 1].pose_name;
  const std::regex store(R"(\n#700=#5061\n)");
  EXPECT_EQ(std::distance(std::sregex_iterator(p.text.begin(), p.text.end(), store), std::sregex_iterator()), first_of_pose);
  // The largest pose uses #700 .. #700 + 4 n - 1 and nothing beyond.
  std::map<std::string, int> per_pose;
  for (const auto& pt : p.plan.points) ++per_pose[pt.pose_name];
  int most = 0;
  for (const auto& [name, n] : per_pose) most = std::max(most, n);
  const int top = 700 + 4 * most - 1;
  EXPECT_NE(p.text.find(fmt::format("\n#{}=#3001\n", top)), std::string::npos);
  EXPECT_EQ(p.text.find(fmt::format("\n#{}=", top + 1)), std::string::npos);
  EXPECT_LE(most, 28) << "touch154: at most 28 points per pose, #700-#811";
}

TEST(FanucProgram, PoseWithMoreThanSeventyPointsIsRefused) {
  nc::Program p;
  p.cycle = "touch154";
  p.number = cycleByName("touch154").programNumber();
  for (int id = 1; id <= 71; ++id) {
    nc::Op op;
    op.kind = nc::Op::Kind::Probe;
    op.point_id = id;
    op.feed = 100;
    p.ops.push_back(op);
  }
  EXPECT_THROW(fc().writeProgram(p), std::invalid_argument);
  p.ops.pop_back();
  EXPECT_NO_THROW(fc().writeProgram(p));
}

class FanucCheck : public test::PlantedFaults {
 protected:
  FanucCheck() : PlantedFaults("fanuc", "^G31") {}
};

TEST_F(FanucCheck, CatchesAMissingDecimalPoint) {
  const auto ps = with([&](auto& v) { v[g] = "G31 X51 Y-235.0000 Z150.0000 F100.0"; });
  ASSERT_EQ(ps.size(), 1u);
  EXPECT_EQ(ps[0], fmt::format("{}: X51 has no decimal point (read in least input increments)", g + 1));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "G31 X51.0000 Y-235.0000 Z150.0000 F100"; }), "F100 has no"));
}

TEST_F(FanucCheck, CatchesARemovedNoTriggerAlarm) {
  const auto ps = with([&](auto& v) { v.erase(v.begin() + static_cast<long>(g) + 5); });
  ASSERT_EQ(ps.size(), 1u);
  EXPECT_EQ(ps[0].rfind(fmt::format("{}: G31 is not followed by the no-trigger check", g + 1), 0), 0u) << ps[0];
}

TEST_F(FanucCheck, CatchesAPointOutsideTheStrokes) {
  const auto ps = with([&](auto& v) { v[g] = "G31 X51.0000 Y-335.0000 Z150.0000 F100.0"; });
  ASSERT_EQ(ps.size(), 1u);
  EXPECT_NE(ps[0].find("Y = -335.0000 mm is outside the stroke"), std::string::npos) << ps[0];
}

TEST_F(FanucCheck, CatchesConstructsThatAreNotMacroB) {
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g + 1] = "o1001 if [#5070 NE 1]"; }), "o-word"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g + 1] = "#<dx>=#5061-51.0000"; }), "named parameters"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "g31 X51.0000 Y-235.0000 Z150.0000 F100.0"; }), "lower-case"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[3] = "(probe)"; }), "lower-case letters in a comment"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[3] = "(" + std::string(90, 'X') + ")"; }), "more than 80"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[test::lineStarting(v, "DPRNT[ROTACAL")] = "DPRNT[A=B]"; }),
                  "DPRNT text has '='"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g + 4] = "IF[[#1*#1+#2*#2+#3*#3]GT0.0001]GOTO1001]"; }),
                  "unbalanced brackets"));
}

TEST_F(FanucCheck, CatchesAMissingEnd) {
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.erase(v.end() - 2); }), "does not end with M30"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.pop_back(); }), "does not end with '%'"));
}

TEST(FanucOffsets, IncrementalG54ShiftWithTheFanucSign) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r;
  r.plan = &plan;
  r.identified.kinematics = Kinematics::TableAC;
  const double v[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};  // 000 Table 4 mean, um / mdeg
  for (int i = 0; i < 8; ++i) r.identified.setReportValue(i, v[i]);
  r.report_file = "out/report_1.json";
  const std::string text = fc().writeOffsets(r);
  const auto ls = lines(text);
  EXPECT_NE(text.find("\nG91 G10 L2 P1 X0.0146 Y0.0232 Z0.0277 A-0.0005\nG90\n"), std::string::npos) << text;
  EXPECT_NE(text.find("OUT/REPORT-1.JSON"), std::string::npos) << text;
  EXPECT_NE(text.find("UNVERIFIED"), std::string::npos);
  EXPECT_NE(text.find("19700"), std::string::npos);
  for (const auto& l : ls) {
    EXPECT_LE(l.size(), 80u) << l;
    EXPECT_EQ(l.find_first_of("abcdefghijklmnopqrstuvwxyz"), std::string::npos) << l;
  }
  r.identified.set("dx_AY", -0.7);
  EXPECT_THROW(fc().writeOffsets(r), std::invalid_argument);
  r.force = true;
  EXPECT_NE(fc().writeOffsets(r).find("X-0.7000"), std::string::npos);
}

TEST(FanucResults, RepeatsShareTheControlClock) {
  const ProbePlan plan = test::acPlan();
  // Two repeats on the common clock (s since 2000-01-01), the second 2 h later.
  for (double start : {750000000.0, 750007200.0}) {
    MeasurementRun run = test::displacedRun(plan);
    for (auto& p : run.points) p.t_s += start;
    const std::string text = fc().writeResults(plan, run);
    // 750000000 s = 2023-10-07 13:20:00 (Python's datetime); +2 h = 15:20:00; the header holds
    // the first trigger's second (plan t_s + 0.25 s, < 60 s).
    const long first_s = static_cast<long>(std::floor(plan.points[0].t_s + 0.25));
    ASSERT_LT(first_s, 60);
    EXPECT_EQ(lines(text)[1], fmt::format("DATE 20231007 TIME {}", (start == 750000000.0 ? 132000 : 152000) + first_s));
    const MeasurementRun back = fc().parseResults(text, "res.txt", plan);
    for (size_t i = 0; i < back.points.size(); ++i)
      EXPECT_NEAR(back.points[i].t_s, run.points[i].t_s, kTimerRoundingS + 1e-6);
  }
}

TEST_F(FanucRejects, ClockLineMissingOrInvalid) {
  expectAt([](auto& v) { v.erase(v.begin() + 1); }, 2, "expected 'DATE YYYYMMDD TIME HHMMSS' after the header");
  expectAt([](auto& v) { v[1] = "DATE 20230230 TIME 120000"; }, 2,
           "DATE 20230230 TIME 120000 is not a date YYYYMMDD and a time HHMMSS");
  expectAt([](auto& v) { v[1] = "DATE 20230228 TIME 126000"; }, 2, "DATE 20230228 TIME 126000 is not a date");
}

TEST(FanucProgram, ReadsTheClockBeforeZeroingTheTimer) {
  const test::WrittenProgram p("fanuc", "^G31");
  EXPECT_NE(p.text.find("\nPOPEN\n#1=#3011\n#2=#3012\n#3001=0\n"
                        "DPRNT[ROTACAL-RESULTS*DIALECT*FANUC*CYCLE*TOUCH154*POINTS*154*UNIT*MM]\n"
                        "DPRNT[DATE*#1[80]*TIME*#2[60]]\n"),
            std::string::npos);
}

TEST(FanucProgram, DoubleTouchIsRefusedNotIgnored) {
  const ProbePlan plan = test::acPlan();
  nc::Program p = test::cycleProgram(plan, "fanuc");
  for (auto& op : p.ops)
    if (op.kind == nc::Op::Kind::Probe) op.retract_mm = 1.0;
  EXPECT_THROW(fc().writeProgram(p), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
