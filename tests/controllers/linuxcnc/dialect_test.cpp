// The LinuxCNC dialect (its round trip, recovery and clean programs: battery_test): the logged
// angles carry LinuxCNC's sign, the parser reads hand-edited line ends and names the line of
// every fault, the probing block, the checker catches planted faults, the double touch, the
// HAL offsets follow the documented pin mapping, and a B head over a C table (maxkins) gets its
// pivot length and the work offset that the exact model says cancel what they hold.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <regex>

#include "cycles/cycle.hpp"
#include "controllers/linuxcnc/hal.hpp"
#include "core/errors.hpp"
#include "core/kinematic_model.hpp"
#include "core/units.hpp"
#include "ctl_test_util.hpp"
#include "dialect_battery.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {
namespace {

using test::lines;
using test::messageOf;

const Dialect& lc() { return dialectByName("linuxcnc"); }

TEST(LinuxCncResults, AnglesAreTheControllersWithTheLinuxCncSign) {
  const ProbePlan plan = test::acPlan();
  const auto ls = lines(lc().writeResults(plan, test::displacedRun(plan)));
  for (const auto& p : plan.points) {
    if (!(p.pose.A == -90.0 && p.pose.C == 90.0)) continue;  // pose V of 000
    const auto& l = ls[static_cast<size_t>(p.id)];
    EXPECT_NE(l.find(" 90.0000 -90.0000 1"), std::string::npos) << "A = -A*, C = -C* on xyzac-trt-kins: " << l;
    return;
  }
  FAIL() << "no point at A* = -90, C* = 90";
}

TEST(LinuxCncResults, ParserAcceptsCrLfCrAndRepeatedSpaces) {
  const ProbePlan plan = test::acPlan();
  auto ls = lines(lc().writeResults(plan, test::displacedRun(plan)));
  std::string text;
  for (size_t i = 0; i < ls.size(); ++i) {
    std::string l = ls[i];
    if (i % 3 == 1) l = "  " + std::regex_replace(l, std::regex(" "), "   ");
    text += l + (i % 3 == 0 ? "\r\n" : i % 3 == 1 ? "\r" : "\n");
  }
  text += "\n\n";
  EXPECT_EQ(lc().parseResults(text, "res.txt", plan).points.size(), plan.points.size());
}

class LinuxCncRejects : public test::WrittenResults {
 protected:
  LinuxCncRejects() : WrittenResults("linuxcnc") {}
};

TEST_F(LinuxCncRejects, MissingPointAtTheLastLine) {
  expectAt([](auto& v) { v.erase(v.begin() + 17); }, kLastLine, "point 17 is missing");  // P17
}

TEST_F(LinuxCncRejects, DuplicatedPointAtItsSecondLine) {
  // P5 again as line 32
  expectAt([&](auto& v) { v.insert(v.begin() + 31, ls[5]); }, 32, "point 5 appears twice (first at line 6)");
}

TEST_F(LinuxCncRejects, PointIdNotInThePlan) {
  expectAt([](auto& v) { v[40] = "P155 1.0 2.0 3.0 0.0 0.0 1"; }, 41, "point 155 is not in the plan");
}

TEST_F(LinuxCncRejects, NonNumberNamingTheToken) {
  expectAt([](auto& v) { v[12] = "P12 1.000000 2.0x0000 3.000000 0.0000 0.0000 1"; }, 13,
           "'2.0x0000' (field 3 of point 12) is not a number");
}

TEST_F(LinuxCncRejects, UntriggeredPoint) {
  expectAt([](auto& v) { v[9].back() = '0'; }, 10, "point 9 was not triggered");
}

TEST_F(LinuxCncRejects, HeaderWithTheWrongPointCount) {
  expectAt([](auto& v) { v[0] = "rotacal-results/1 dialect=linuxcnc cycle=touch154 points=153 unit=mm"; }, 1,
           "header says points=153 but the plan has 154 points");
}

TEST_F(LinuxCncRejects, HeaderOfAnotherCycleOrMissing) {
  expectAt([](auto& v) { v[0] = "rotacal-results/1 dialect=linuxcnc cycle=rtest points=154 unit=mm"; }, 1,
           "results of cycle 'rtest'");
  expectAt([](auto& v) { v.erase(v.begin()); }, 1, "expected the header");
}

TEST_F(LinuxCncRejects, WrongFieldCount) {
  expectAt([](auto& v) { v[3] = "P3 1.0 2.0 3.0 0.0 1"; }, 4, "expected 7 fields");
}

TEST(LinuxCncProgram, FrameLogAndProbeBlock) {
  const test::WrittenProgram p("linuxcnc", "^G38\\.2");
  EXPECT_EQ(p.text.find("-0.0000"), std::string::npos);
  EXPECT_EQ(p.ls.front(), "%");
  EXPECT_EQ(p.ls[p.ls.size() - 2], "M2");
  const size_t open = test::lineStarting(p.ls, "(LOGOPEN");
  EXPECT_EQ(p.ls[open], "(LOGOPEN,rotacal_touch154.txt)");
  EXPECT_EQ(p.ls[open + 1], "(LOG,rotacal-results/1 dialect=linuxcnc cycle=touch154 points=154 unit=mm)");
  EXPECT_EQ(p.ls[p.g + 1], "o1001 if [#5070 NE 1]");
  EXPECT_EQ(p.ls[p.g + 2], "(ABORT, rotacal: point 1 did not trigger)");
  EXPECT_EQ(p.ls[p.g + 3], "o1001 endif");
  EXPECT_EQ(p.ls[p.g + 4], "(LOG,P1 %.6f#5061 %.6f#5062 %.6f#5063 %.4f#5064 %.4f#5066 %d#5070)");
  for (const auto& l : p.ls) EXPECT_LE(l.size(), 252u) << l;
}

TEST(LinuxCncProgram, InchProgramUsesG20AndFiveDecimals) {
  const test::WrittenProgram p("linuxcnc", "^G38\\.2", LengthUnit::Inch);
  EXPECT_NE(p.text.find("\nG20\n"), std::string::npos);
  EXPECT_TRUE(std::regex_search(p.text, std::regex(R"(\nG38\.2 X-?\d+\.\d{5} Y-?\d+\.\d{5} Z-?\d+\.\d{5} F)")));
}

TEST(LinuxCncProgram, BcMachineLogsTheBAxisParameter) {
  nc::Program p;
  p.cycle = "rtest";
  p.rotary_axes = {'B', 'C'};
  nc::Op probe;
  probe.kind = nc::Op::Kind::Probe;
  probe.point_id = 1;
  probe.feed = 100;
  p.ops.push_back(probe);
  const std::string text = lc().writeProgram(p);
  EXPECT_NE(text.find("%.4f#5065 %.4f#5066 %d#5070)"), std::string::npos) << text;
}

class LinuxCncCheck : public test::PlantedFaults {
 protected:
  LinuxCncCheck() : PlantedFaults("linuxcnc", "^G38\\.2") {}
};

TEST_F(LinuxCncCheck, CatchesARemovedAbort) {
  const auto problems = with([&](auto& v) { v.erase(v.begin() + static_cast<long>(g) + 2); });  // point 1's (ABORT, ...)
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].rfind(fmt::format("{}: G38.2 is not followed", g + 1), 0), 0u) << problems[0];
}

TEST_F(LinuxCncCheck, CatchesAPointOutsideTheStrokes) {
  const auto problems = with([&](auto& v) { v[g] = "G38.2 X700.0000 Y-235.0000 Z150.0000 F100.0"; });
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find(fmt::format("{}: X = 700.0000 mm is outside the stroke", g + 1)), std::string::npos)
      << problems[0];
}

TEST_F(LinuxCncCheck, CatchesARotaryAngleOutsideItsStrokeInThePapersConvention) {
  const size_t a = test::lineStarting(ls, "G0 A");
  const auto problems = with([&](auto& v) { v[a] = "G0 A-30.0000 C0.0000"; });  // LinuxCNC A-30 = paper A* +30 > +20
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("papers' convention 30.0000"), std::string::npos) << problems[0];
}

TEST_F(LinuxCncCheck, CatchesLineSyntaxAndStructureFaults) {
  EXPECT_TRUE(test::hasProblem(with([](auto& v) { v[1] = "(" + std::string(260, 'x') + ")"; }), "Command too long"));
  EXPECT_TRUE(test::hasProblem(with([](auto& v) { v[1] = "(open"; }), "comment not closed"));
  EXPECT_TRUE(test::hasProblem(with([](auto& v) { v[test::lineStarting(v, "(LOGOPEN")] = "(LOGOPEN x.txt)"; }),
                  "LOGOPEN needs a comma"));
  EXPECT_TRUE(test::hasProblem(with([](auto& v) {
                    const size_t i = test::lineStarting(v, "(LOG,P1 ");
                    v[i] = "(note)" + v[i];
                  }),
                  "shares its line"));
  EXPECT_TRUE(test::hasProblem(with([](auto& v) { v.erase(v.end() - 2); }), "does not end with M2 or M30"));
  EXPECT_TRUE(test::hasProblem(with([](auto& v) {
                    const size_t g = test::lineStarting(v, "G38.2");
                    v.erase(v.begin() + static_cast<long>(g), v.begin() + static_cast<long>(g) + 5);
                  }),
                  "153 recorded touches [G38.2/G38.3 moves whose position is LOGged], the plan has 154 points"));
}

// ---- double touch ----

/// The A/C test machine with a double touch: first touch at 600 mm/min, back off 0.05 mm,
/// recorded touch at 10 mm/min (the e2e machine's values).
ProbePlan doubleTouchPlan() {
  MachineModel m = test::acTestMachine();
  m.feeds.probing_mm_min = 600.0;
  m.feeds.probing_slow_mm_min = 10.0;
  m.retract_mm = 0.05;
  return makePlan("touch154", m, {});
}

TEST(LinuxCncDoubleTouch, ZeroFieldsInTheMachineFileGiveTheSingleTouchProgram) {
  const ProbePlan plan = test::acPlan();
  std::string json = test::kAcMachineJson;
  json.insert(json.rfind('}'), R"(, "retract_mm": 0, "feeds": {"probing_slow_mm_min": 0})");
  const JsonDoc doc = parseJsonText(json, "zero_fields.json");
  const ProbePlan zero = makePlan("touch154", machineFromJson(doc, doc.value), {});
  const std::string single = lc().writeProgram(test::cycleProgram(plan, "linuxcnc"));
  EXPECT_EQ(lc().writeProgram(test::cycleProgram(zero, "linuxcnc")), single);
  EXPECT_EQ(single.find("G38.3"), std::string::npos);
  EXPECT_EQ(single.find("G91"), std::string::npos);
}

TEST(LinuxCncDoubleTouch, FastTouchBackOffAlongTheApproachThenSlowRecordedTouch) {
  const ProbePlan plan = doubleTouchPlan();
  const std::string text = lc().writeProgram(test::cycleProgram(plan, "linuxcnc"));
  EXPECT_EQ(lc().check(text, plan, test::shapeOf(plan, "linuxcnc")), std::vector<std::string>{});
  const auto ls = lines(text);
  const ProbePoint& p1 = *plan.findPoint(1);
  // the end of the probing line: overtravel past the nominal trigger along the approach
  const Eigen::Vector3d end = p1.trigger_m_mm + plan.machine.overtravel_mm * p1.approach_m;
  const Eigen::Vector3d back = -0.05 * p1.approach_m;
  auto num = [](double v) { return fmt::format("{:.4f}", v == 0.0 ? 0.0 : v); };
  const std::string xyz = fmt::format("X{} Y{} Z{}", num(end.x()), num(end.y()), num(end.z()));
  const size_t g = test::lineStarting(ls, "G38.3");
  EXPECT_EQ(ls[g], "G38.3 " + xyz + " F600.0");
  EXPECT_EQ(ls[g + 1], "o1001 if [#5070 NE 1]");
  EXPECT_EQ(ls[g + 2], "(ABORT, rotacal: point 1 did not trigger)");
  EXPECT_EQ(ls[g + 3], "o1001 endif");
  EXPECT_EQ(ls[g + 4], fmt::format("G91 G0 X{} Y{} Z{}", num(back.x()), num(back.y()), num(back.z())));
  EXPECT_EQ(ls[g + 5], "G90");
  EXPECT_EQ(ls[g + 6], "G38.2 " + xyz + " F10.0");
  EXPECT_EQ(ls[g + 7], "o500001 if [#5070 NE 1]");
  EXPECT_EQ(ls[g + 10], "(LOG,P1 %.6f#5061 %.6f#5062 %.6f#5063 %.4f#5064 %.4f#5066 %d#5070)");
  size_t first = 0, second = 0;
  for (const auto& l : ls) {
    first += l.rfind("G38.3 ", 0) == 0;
    second += l.rfind("G38.2 ", 0) == 0;
  }
  EXPECT_EQ(first, plan.points.size());
  EXPECT_EQ(second, plan.points.size());
}

TEST(LinuxCncDoubleTouch, CheckerCountsRecordedTouchesAndWantsTheFirstTouchChecked) {
  const ProbePlan plan = doubleTouchPlan();
  const auto ls = lines(lc().writeProgram(test::cycleProgram(plan, "linuxcnc")));
  auto v = ls;
  v.erase(v.begin() + static_cast<long>(test::lineStarting(v, "(LOG,P1 ")));
  auto problems = lc().check(test::join(v), plan, test::shapeOf(plan, "linuxcnc"));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("153 recorded touches"), std::string::npos) << problems[0];
  v = ls;
  const size_t g = test::lineStarting(v, "G38.3");
  v.erase(v.begin() + static_cast<long>(g) + 2);  // the first touch's (ABORT, ...)
  problems = lc().check(test::join(v), plan, test::shapeOf(plan, "linuxcnc"));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].rfind(fmt::format("{}: G38.3 is not followed", g + 1), 0), 0u) << problems[0];
}

TEST(LinuxCncDoubleTouch, MachineFileNeedsASlowFeedAndABackOffInsideTheApproach) {
  auto msg = [](const std::string& extra) {
    std::string json = test::kAcMachineJson;
    json.insert(json.rfind('}'), extra);
    return messageOf<InputError>([&] {
      const JsonDoc doc = parseJsonText(json, "m.json");
      machineFromJson(doc, doc.value);
    });
  };
  EXPECT_NE(msg(R"(, "retract_mm": 0.05)").find("probing_slow_mm_min > 0"), std::string::npos);
  EXPECT_NE(msg(R"(, "retract_mm": 6, "feeds": {"probing_slow_mm_min": 10})").find("smaller than approach_mm"),
            std::string::npos);
  EXPECT_NE(msg(R"(, "retract_mm": -1)").find("must be >= 0"), std::string::npos);
  const MachineModel m = doubleTouchPlan().machine;
  const Json j = machineToJson(m);
  EXPECT_EQ(j["retract_mm"].get<double>(), 0.05);
  EXPECT_EQ(j["feeds"]["probing_slow_mm_min"].get<double>(), 10.0);
  EXPECT_FALSE(machineToJson(test::acTestMachine()).contains("retract_mm")) << "single touch: the file as before";
}

// ---- offsets ----

OffsetRequest request(const ProbePlan& plan) {
  OffsetRequest r;
  r.plan = &plan;
  r.identified.kinematics = plan.machine.kinematics;
  r.report_file = "report.json";
  return r;
}

LocationErrors table4() {
  LocationErrors e;
  e.kinematics = Kinematics::TableAC;
  const double v[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};  // 000 Table 4 mean, um / mdeg
  for (int i = 0; i < 8; ++i) e.setReportValue(i, v[i]);
  return e;
}

// Values are printed with 6 decimals (mm): half a unit of the last digit.
constexpr double kPinRoundingMm = 0.5e-6 + 1e-12;

TEST(LinuxCncOffsets, PinsFollowTheDocumentedMapping) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r = request(plan);
  r.identified = table4();
  const std::string hal = lc().writeOffsets(r);
  const auto pins = parseHalSetp(hal, "xyzac-trt-kins");
  ASSERT_EQ(pins.size(), 5u) << hal;
  EXPECT_NEAR(pins.at("x-rot-point"), 0.0146, kPinRoundingMm);
  EXPECT_NEAR(pins.at("y-rot-point"), 0.0232 + 0.0039, kPinRoundingMm);
  EXPECT_NEAR(pins.at("z-rot-point"), 0.0277, kPinRoundingMm);
  EXPECT_NEAR(pins.at("y-offset"), -0.0039, kPinRoundingMm);
  EXPECT_NEAR(pins.at("z-offset"), 0.0, kPinRoundingMm);
  // a_AY = -0.5 mdeg; LinuxCNC counts A the other way: G54 A offset = -1 * -0.0005 deg.
  EXPECT_NE(hal.find("#   G10 L2 P1 A0.000500\n"), std::string::npos) << hal;
  EXPECT_NE(hal.find("report.json"), std::string::npos);
  EXPECT_NE(hal.find("b_AY"), std::string::npos);
}

TEST(LinuxCncOffsets, PreviousValuesAreAddedAndOtherLinesKept) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r = request(plan);
  r.identified = table4();
  r.previous_text =
      "# old file\r\nsetp xyzac-trt-kins.x-rot-point 1.5\r\nsetp   xyzac-trt-kins.y-offset   -20.0  # A pivot\r\n"
      "setp xyzac-trt-kins.tool-offset 0\r\n";
  const std::string hal = lc().writeOffsets(r);
  const auto pins = parseHalSetp(hal, "xyzac-trt-kins");
  EXPECT_NEAR(pins.at("x-rot-point"), 1.5 + 0.0146, kPinRoundingMm);
  EXPECT_NEAR(pins.at("y-offset"), -20.0 - 0.0039, kPinRoundingMm);
  EXPECT_NEAR(pins.at("z-rot-point"), 0.0277, kPinRoundingMm) << "missing previous value counts as 0";
  EXPECT_EQ(pins.at("tool-offset"), 0.0) << "unrelated pins are carried over";
  EXPECT_NE(hal.find("1.500000"), std::string::npos) << "old value listed";
}

TEST(LinuxCncOffsets, ImplausibleCorrectionThrowsUnlessForced) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r = request(plan);
  r.identified = table4();
  r.identified.set("dz_AY", 0.62);
  const std::string msg = messageOf<std::invalid_argument>([&] { lc().writeOffsets(r); });
  EXPECT_NE(msg.find("dz_AY = 0.6200 mm exceeds the plausibility limit of 0.5 mm"), std::string::npos) << msg;
  r.identified = table4();
  r.identified.set("b_CA", mdegToRad(-150.0));
  EXPECT_NE(messageOf<std::invalid_argument>([&] { lc().writeOffsets(r); }).find("b_CA = -150.0 mdeg"),
            std::string::npos);
  r.force = true;
  EXPECT_NO_THROW(lc().writeOffsets(r));
}

TEST(LinuxCncOffsets, BcMachineWritesTheXyzbcPins) {
  ProbePlan plan;
  plan.cycle = "rtest";
  plan.machine = test::machineFrom(test::kBcMachineJson);
  OffsetRequest r = request(plan);
  r.identified.set("dx_BY", 0.010);
  r.identified.set("dy_CB", 0.002);
  r.identified.set("dz_BY", -0.020);
  r.identified.set("dx_CB", 0.005);
  r.identified.set("b_BY", mdegToRad(1.0));
  const std::string hal = lc().writeOffsets(r);
  const auto pins = parseHalSetp(hal, "xyzbc-trt-kins");
  EXPECT_NEAR(pins.at("x-rot-point"), 0.015, kPinRoundingMm);
  EXPECT_NEAR(pins.at("y-rot-point"), 0.002, kPinRoundingMm);
  EXPECT_NEAR(pins.at("z-rot-point"), -0.020, kPinRoundingMm);
  EXPECT_NEAR(pins.at("x-offset"), -0.005, kPinRoundingMm);
  EXPECT_NEAR(pins.at("z-offset"), 0.0, kPinRoundingMm);
  EXPECT_NE(hal.find("G10 L2 P1 B-0.001000"), std::string::npos) << hal;
}

TEST(LinuxCncOffsets, PreviousFileWithANonNumberIsRefused) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r = request(plan);
  r.previous_text = "setp xyzac-trt-kins.x-rot-point [KINS]X\n";
  EXPECT_THROW(lc().writeOffsets(r), std::invalid_argument);
}


// ---- offsets as a G10 work-offset program (*.ngc) ----

/// The number after `letter` on the "G10 L2 P1" line.
double g10Word(const std::string& text, char letter) {
  for (const auto& l : lines(text)) {
    if (l.rfind("G10 L2 P1", 0) != 0) continue;
    const size_t at = l.find(std::string(" ") + letter);
    if (at == std::string::npos) break;
    return std::stod(l.substr(at + 2));
  }
  throw std::runtime_error(std::string("no G10 L2 P1 word ") + letter + " in\n" + text);
}

TEST(LinuxCncOffsets, NgcFileShiftsG54ByTheAPivotAndTheAZero) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r = request(plan);
  r.identified = table4();
  r.path = "out/offsets.ngc";
  const std::string ngc = lc().writeOffsets(r);
  // machine = program + offset: a table displaced by (dx, dy, dz)_AY is seen at 0 (mm)
  EXPECT_NEAR(g10Word(ngc, 'X'), 0.0146, 0.5e-6 + 1e-12);
  EXPECT_NEAR(g10Word(ngc, 'Y'), 0.0232, 0.5e-6 + 1e-12);
  EXPECT_NEAR(g10Word(ngc, 'Z'), 0.0277, 0.5e-6 + 1e-12);
  // a_AY = -0.5 mdeg, LinuxCNC's A counts the other way (sign -1): +0.0005 deg
  EXPECT_NEAR(g10Word(ngc, 'A'), 0.0005, 0.5e-6 + 1e-12);
  const auto ls = lines(ngc);
  EXPECT_EQ(ls.front(), "%");
  EXPECT_EQ(ls[ls.size() - 2], "M2");
  EXPECT_NE(ngc.find("dy_CA, b_AY, c_AY, b_CA"), std::string::npos) << "what it cannot apply is named";
  for (const auto& l : ls) EXPECT_LE(l.size(), 252u) << l;
  // the loop: a second correction adds to the first
  r.previous_text = ngc;
  const std::string again = lc().writeOffsets(r);
  EXPECT_NEAR(g10Word(again, 'X'), 2 * 0.0146, 1e-6 + 1e-12);
  EXPECT_NEAR(g10Word(again, 'A'), 2 * 0.0005, 1e-6 + 1e-12);
}

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

TEST(LinuxCncOffsets, NgcFileOfABcTableShiftsG54ByBsPlaceCsYAndTheBZero) {
  ProbePlan bc;
  bc.cycle = "one_sphere";
  bc.machine = test::machineFrom(test::kBcMachineJson);
  OffsetRequest r = request(bc);
  r.identified.kinematics = Kinematics::TableBC;
  // truth_bc.json's values (tests/e2e), um / mdeg
  r.identified.set("dx_BY", 12.4e-3);
  r.identified.set("dy_CB", -8.6e-3);
  r.identified.set("dz_BY", -15.3e-3);
  r.identified.set("dx_CB", 9.7e-3);
  r.identified.set("a_BY", 24.0e-3 * kDegToRad);
  r.identified.set("b_BY", -31.0e-3 * kDegToRad);
  r.identified.set("c_BY", 18.0e-3 * kDegToRad);
  r.identified.set("a_CB", -27.0e-3 * kDegToRad);
  r.path = "offsets.ngc";
  const std::string ngc = lc().writeOffsets(r);
  // machine = program + offset: B's line displaced by (dx, dz)_BY and C's by dy_CB along B's line
  EXPECT_NEAR(g10Word(ngc, 'X'), 0.0124, 0.5e-6 + 1e-12);
  EXPECT_NEAR(g10Word(ngc, 'Y'), -0.0086, 0.5e-6 + 1e-12);
  EXPECT_NEAR(g10Word(ngc, 'Z'), -0.0153, 0.5e-6 + 1e-12);
  // b_BY = -31 mdeg, LinuxCNC's B counts the other way (sign -1): +0.031 deg
  EXPECT_NEAR(g10Word(ngc, 'B'), 0.031, 0.5e-6 + 1e-12);
  EXPECT_NE(ngc.find("dx_CB, a_BY, c_BY, a_CB"), std::string::npos) << "what it cannot apply is named";
  for (const auto& l : lines(ngc)) EXPECT_LE(l.size(), 252u) << l;
}

TEST(LinuxCncOffsets, NgcFormRefusesAForeignPreviousFile) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r = request(plan);
  r.path = "offsets.NGC";
  r.previous_text = "G0 X1\nM2\n";
  EXPECT_NE(messageOf<std::invalid_argument>([&] { lc().writeOffsets(r); }).find("no 'G10 L2 P1' line"),
            std::string::npos);
  r.previous_text = "G10 L2 P1 X1 Q2\n";
  EXPECT_NE(messageOf<std::invalid_argument>([&] { lc().writeOffsets(r); }).find("'Q2'"), std::string::npos);
}

// ---- a B head over a C table (maxkins) ----

// bc_head_table.json's head with maxkins' linuxcnc signs (read back by tests/e2e: B -1, C +1).
constexpr const char* kHeadMachineJson = R"({
  "format": "rotacal-machine/1", "name": "bc_head_maxkins", "kinematics": "head_table",
  "head": {"axis": "B", "pivot_to_ball_mm": 250.0}, "units": "mm",
  "strokes": {"X": [-400.0, 400.0], "Y": [-300.0, 300.0], "Z": [-50.0, 600.0]},
  "rotary_axes": {"B": {"stroke_deg": [-110.0, 110.0], "controller_sign": 1, "dialect_sign": {"linuxcnc": -1}},
                  "C": {"continuous": true, "controller_sign": 1}},
  "table_diameter_mm": 500.0,
  "probe": {"ball_diameter_mm": 6.0, "stylus_length_mm": 50.0, "body_clearance_mm": 5.0, "tool_number": 0},
  "feeds": {"rapid_mm_min": 20000.0, "positioning_mm_min": 2000.0, "probing_mm_min": 100.0, "rotary_deg_min": 3600.0},
  "clearance_mm": 10.0, "approach_mm": 5.0, "overtravel_mm": 2.0})";

// The identified parameters as one_sphere hands them over (mm, rad; u k = 1), those it holds marked.
const std::map<std::string, double> kHeadInjected = {
    {"X0C", 0.0124}, {"Y0C", -0.0086}, {"A0C", mdegToRad(24.0)}, {"B0C", mdegToRad(-31.0)}, {"A0B", mdegToRad(18.0)},
    {"C0B", mdegToRad(-27.0)}, {"B0B", mdegToRad(21.0)}, {"dL", 0.0153}, {"dX_S", 0.0097}};

OffsetRequest headRequest(const ProbePlan& plan) {
  OffsetRequest r = request(plan);
  const KinematicModel m =
      kinematicModel("head_table", Eigen::Vector3d::Zero(), plan.machine.head->pivot_to_ball_mm, 'B');
  for (const auto& q : m.parameters) {
    ParameterEstimate v{q.name, q.kind, 0.0, q.kind == ParamKind::Length ? 0.0005 : mdegToRad(0.1), false};
    const auto it = kHeadInjected.find(q.name);
    if (it != kHeadInjected.end()) v.value = it->second;
    v.held = q.name == "C0C" || q.name == "X0B" || q.name == "Z0B" || q.name == "dX_T" || q.name == "dY_T";
    r.parameters.push_back(v);
  }
  return r;
}

ProbePlan headPlan() {
  ProbePlan plan;
  plan.cycle = "one_sphere";
  plan.machine = test::machineFrom(kHeadMachineJson);
  return plan;
}

TEST(LinuxCncHeadOffsets, HalSetsThePivotLengthToTheModelsPivotToBallDistance) {
  const ProbePlan plan = headPlan();
  OffsetRequest r = headRequest(plan);
  r.path = "offsets.hal";
  const std::string hal = lc().writeOffsets(r);
  const auto pins = parseHalSetp(hal, "maxkins");
  ASSERT_EQ(pins.size(), 1u) << hal;
  // The exact head chain: the ball's distance from the pivot (the chain's origin here: X0B = Z0B = 0)
  // at any head angle, with the identified parameters, is the length maxkins must turn about it.
  const KinematicModel m = kinematicModel("head_table", Eigen::Vector3d::Zero(), 250.0, 'B');
  Eigen::VectorXd p = Eigen::VectorXd::Zero(m.size());
  for (const auto& v : r.parameters) p[m.parameterIndex(v.name)] = v.held ? 0.0 : v.value;
  for (double b : {-60.0, 0.0, 35.0}) {
    Pose pose;
    pose.B = b;
    const double from_pivot = (T_c_t(m, p, pose) * Eigen::Vector3d(0.0, 0.0, -250.0)).norm();
    EXPECT_NEAR(pins.at("pivot-length"), from_pivot, kPinRoundingMm) << "B " << b;
  }
  EXPECT_NE(hal.find("no previous value: MACHINE.json's pivot_to_ball_mm assumed"), std::string::npos) << hal;
  // what the pin cannot hold: the work offset's three, the tilts with their route, the held ones
  EXPECT_NE(hal.find("#   G10 L2 P1 X0.012400 Y-0.008600 B0.021000"), std::string::npos) << hal;
  EXPECT_NE(hal.find("A0C, B0C (orientation of the C axis) and A0B, C0B"), std::string::npos) << hal;
  EXPECT_NE(hal.find("C0C, X0B, Z0B, dX_T, dY_T"), std::string::npos) << hal;
  // the loop: a previous file's pin is the start
  r.previous_text = "setp maxkins.pivot-length 250.5\nsetp other.pin 3\n";
  const std::string again = lc().writeOffsets(r);
  EXPECT_NEAR(parseHalSetp(again, "maxkins").at("pivot-length"), 250.5 + 0.0153, kPinRoundingMm) << again;
  EXPECT_NE(again.find("setp other.pin 3"), std::string::npos) << "unrelated lines kept";
}

TEST(LinuxCncHeadOffsets, NgcWorkOffsetCancelsTheTablesPlaceAndTheHeadsZeroOnTheExactModel) {
  const ProbePlan plan = headPlan();
  OffsetRequest r = headRequest(plan);
  r.path = "offsets.ngc";
  const std::string ngc = lc().writeOffsets(r);
  const double ox = g10Word(ngc, 'X'), oy = g10Word(ngc, 'Y'), ob = g10Word(ngc, 'B');
  // machine = program + offset. The program commands the nominal carriage at B = sign x B*; the
  // machine with X0C, Y0C and B0B needs, at every pose, the carriage the exact model gives for the
  // head turned to the angle the offset B makes of it. The two agree to the file's 6 decimals.
  const KinematicModel m = kinematicModel("head_table", Eigen::Vector3d(120.0, 0.0, 80.0), 250.0, 'B');
  Eigen::VectorXd p = Eigen::VectorXd::Zero(m.size());
  for (const char* n : {"X0C", "Y0C", "B0B"}) p[m.parameterIndex(n)] = kHeadInjected.at(n);
  const int sign = plan.machine.controllerSign('B', "linuxcnc");
  ASSERT_EQ(sign, -1);
  double worst = 0.0;
  for (double b : {-60.0, 0.0, 60.0})
    for (double c : {0.0, 120.0, 240.0}) {
      Pose nominal;
      nominal.B = b;
      nominal.C = c;
      Pose turned = nominal;
      turned.B = sign * (sign * b + ob);  // the papers' angle of the machine's B joint
      const Eigen::Vector3d needed = sphereCentreInAxes(m, p, turned);
      const Eigen::Vector3d given =
          sphereCentreInAxes(m, Eigen::VectorXd::Zero(m.size()), nominal) + Eigen::Vector3d(ox, oy, 0.0);
      worst = std::max(worst, (needed - given).norm());
    }
  // 6 decimals: 0.5e-6 mm in X, Y and 0.5e-6 deg of B over the 250 mm stylus
  EXPECT_LT(worst, 0.5e-6 * std::sqrt(2.0) + degToRad(0.5e-6) * 250.0 + 1e-9) << ngc;
  EXPECT_NE(ngc.find("dL [maxkins' pivot-length, a .hal file], A0C, B0C, A0B, C0B"), std::string::npos) << ngc;
  // the loop adds to the previous G54
  r.previous_text = ngc;
  EXPECT_NEAR(g10Word(lc().writeOffsets(r), 'B'), 2 * ob, 1e-9);
}

TEST(LinuxCncHeadOffsets, ImplausibleParametersAndAnotherHeadAreRefused) {
  ProbePlan plan = headPlan();
  OffsetRequest r = headRequest(plan);
  for (auto& v : r.parameters)
    if (v.name == "dL") v.value = 0.7;
  EXPECT_NE(messageOf<std::invalid_argument>([&] { lc().writeOffsets(r); }).find("dL = 0.7000 mm exceeds"),
            std::string::npos);
  r.force = true;
  EXPECT_NO_THROW(lc().writeOffsets(r));
  plan.machine.head->axis = 'A';
  const OffsetRequest a = headRequest(plan);
  EXPECT_NE(messageOf<std::invalid_argument>([&] { lc().writeOffsets(a); }).find("B head over a C table"),
            std::string::npos);
}

TEST(LinuxCncHeadOffsets, EveryOtherDialectRefusesAHeadTableWithItsName) {
  const ProbePlan plan = headPlan();
  const OffsetRequest r = headRequest(plan);
  int refused = 0;
  for (const auto& name : dialectNames()) {
    if (name == "linuxcnc") continue;
    const std::string msg = messageOf<std::invalid_argument>([&] { dialectByName(name).writeOffsets(r); });
    EXPECT_NE(msg.find("head_table"), std::string::npos) << name << ": " << msg;
    EXPECT_NE(msg.find("confirmed for " + name), std::string::npos) << name << ": " << msg;
    ++refused;
  }
  EXPECT_GE(refused, 5);
}

}  // namespace
}  // namespace rotacal
