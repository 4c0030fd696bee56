// The fixed-tool-tip program (004 Table 1) in every dialect: the golden comparison with the 18
// motion lines typed from 004 Table 1, LinuxCNC's rs274 accepting the program and keeping the
// tool tip fixed, the checkers' inverse-time rules, and Heidenhain's refusal.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "cycles/cycle.hpp"
#include "controllers/dialect.hpp"
#include "cycles/tooltip/plan.hpp"
#include "core/units.hpp"
#include "cycles/tooltip/program.hpp"
#include "rs274_run.hpp"
#include "test_util.hpp"
#include "dialect_lists.hpp"

namespace rotacal::test {
namespace {

namespace fs = std::filesystem;


// 004 Table 1, typed from the seed text (R = 15 in, 5 deg steps, 0..90 deg).
const char* kTable1[18] = {
    "Y-1.3073Z-0.0571A5.", "Y-1.2974Z-0.1708A5.", "Y-1.2776Z-0.2832A5.", "Y-1.2480Z-0.3935A5.",
    "Y-1.2090Z-0.5008A5.", "Y-1.1607Z-0.6042A5.", "Y-1.1036Z-0.7031A5.", "Y-1.0382Z-0.7966A5.",
    "Y-0.9648Z-0.8841A5.", "Y-0.8841Z-0.9648A5.", "Y-0.7966Z-1.0382A5.", "Y-0.7031Z-1.1036A5.",
    "Y-0.6042Z-1.1607A5.", "Y-0.5008Z-1.2090A5.", "Y-0.3935Z-1.2480A5.", "Y-0.2832Z-1.2776A5.",
    "Y-0.1708Z-1.2974A5.", "Y-0.0571Z-1.3073A5.",
};

/// 004 Table 1's plan: one run (a new static plan repeats it kTooltipRepeats times).
ProbePlan table1Plan(CycleOptions extra = {}) {
  CycleOptions o{{"units", "inch"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}, {"repeats", "1"}};
  for (const auto& [k, v] : extra) o[k] = v;
  return makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")), o);
}

/// The motion lines of a program: lines with an A word and a Y or X word, F word removed.
std::vector<std::string> motionLines(const std::string& program) {
  std::vector<std::string> out;
  std::istringstream in(program);
  std::string l;
  const std::regex motion(R"(^([XY]-?[0-9.]+)?([YZ]-?[0-9.]+)*Z-?[0-9.]+A-?[0-9.]+F[0-9.]+$)");
  while (std::getline(in, l)) {
    std::string s;
    for (char c : l)
      if (c != ' ') s += c;
    if (std::regex_match(s, motion)) out.push_back(s.substr(0, s.find('F')));
  }
  return out;
}

TEST(TooltipProgram, ReproducesTable1DigitForDigitInEveryIsoDialect) {
  const ProbePlan plan = table1Plan();
  for (const std::string& d : test::inverseTimeDialects()) {
    const Dialect& dialect = dialectByName(d);
    const std::string text = dialect.writeProgram(test::cycleProgram(plan, d));
    const auto lines = motionLines(text);
    ASSERT_EQ(lines.size(), 18u) << d << "\n" << text;
    for (int k = 0; k < 18; ++k) EXPECT_EQ(lines[k], kTable1[k]) << d << " line " << k + 1;
    const auto problems = dialect.check(text, plan, test::shapeOf(plan, d));
    for (const auto& pr : problems) ADD_FAILURE() << d << ": " << pr;
  }
}

TEST(TooltipProgram, CheckerFlagsMissingFeedAndProbingUnderG93) {
  const ProbePlan plan = table1Plan();
  const Dialect& lc = dialectByName("linuxcnc");
  const std::string text = lc.writeProgram(test::cycleProgram(plan, "linuxcnc"));
  const std::string no_f = std::regex_replace(text, std::regex("A5\\.F2\\."), "A5.", std::regex_constants::format_first_only);
  ASSERT_NE(no_f, text);
  const auto p = lc.check(no_f, plan, test::shapeOf(plan, "linuxcnc"));
  ASSERT_FALSE(p.empty());
  EXPECT_NE(p.front().find("without an F word"), std::string::npos) << p.front();
  const std::string probe = std::regex_replace(text, std::regex("G91 G01 G93 F2\\."), "G91 G01 G93 F2.\nG38.2 Z-1 F2.");
  bool flagged = false;
  for (const auto& s : lc.check(probe, plan, test::shapeOf(plan, "linuxcnc"))) flagged |= s.find("probing under inverse-time") != std::string::npos;
  EXPECT_TRUE(flagged);
  // and the writer refuses a probing op under G93
  nc::Program prog = test::cycleProgram(plan, "linuxcnc");
  nc::Op bad;
  bad.kind = nc::Op::Kind::Probe;
  bad.point_id = 1;
  bad.feed = 1;
  for (size_t i = 0; i < prog.ops.size(); ++i)
    if (prog.ops[i].kind == nc::Op::Kind::Pause) {
      prog.ops.insert(prog.ops.begin() + static_cast<long>(i), bad);
      break;
    }
  prog.point_count = 1;
  EXPECT_THROW(lc.writeProgram(prog), std::invalid_argument);
}

TEST(TooltipProgram, DialectsWhereG93IsUnverifiedRefuseInverseTimeWithTheReason) {
  // controllers.md marks G93 itself UNVERIFIED for Okuma (Sec. 6.5) and Heidenhain (Sec. 5.5):
  // both refuse the only cycle that needs it, naming the section, and write no G93.
  const ProbePlan plan = table1Plan();
  for (const auto& [d, section] : {std::pair<const char*, const char*>{"heidenhain", "Sec. 5.5"}, {"okuma", "Sec. 6.5"}}) {
    try {
      const std::string text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
      ADD_FAILURE() << d << " accepted inverse time:\n" << text;
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("inverse-time"), std::string::npos) << m;
      EXPECT_NE(m.find(section), std::string::npos) << m;
      EXPECT_NE(m.find("moves under inverse time"), std::string::npos) << m;
    }
  }
  // Their checkers flag a G93 in a tooltip program with the same reason.
  const std::string fanuc = dialectByName("fanuc").writeProgram(test::cycleProgram(plan, "fanuc"));
  bool flagged = false;
  for (const auto& p : dialectByName("okuma").check(fanuc, plan, test::shapeOf(plan, "fanuc"))) flagged |= p.find("Sec. 6.5") != std::string::npos;
  EXPECT_TRUE(flagged);
}


/// rs274 accepts the program, and the absolute end points of its STRAIGHT_FEED moves keep the
/// tool tip fixed: |pivot + Rx(A) Ry(B) (0,0,-R) - tip0| within the program's rounding.
void expectRs274KeepsTipFixed(const ProbePlan& plan, size_t expected_feeds) {
  const std::string text = dialectByName("linuxcnc").writeProgram(test::cycleProgram(plan, "linuxcnc"));
  const Rs274Run r = runRs274(text);
  ASSERT_EQ(r.exit_code, 0) << r.err << "\n" << text;
  EXPECT_EQ(std::regex_replace(r.err, std::regex(R"(executing|\s)"), ""), "") << r.err;
  const std::regex feed(R"(STRAIGHT_FEED\(([-0-9.]+), ([-0-9.]+), ([-0-9.]+), ([-0-9.]+), ([-0-9.]+), ([-0-9.]+))");
  size_t n = 0;
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const double k = o.inch ? kMmPerInch : 1.0;
  const Eigen::Vector3d tip0 = plan.points.front().contact_w_mm;
  double worst = 0;
  for (auto it = std::sregex_iterator(r.out.begin(), r.out.end(), feed); it != std::sregex_iterator(); ++it, ++n) {
    const Eigen::Vector3d p(std::stod((*it)[1]) * k, std::stod((*it)[2]) * k, std::stod((*it)[3]) * k);
    const double a = std::stod((*it)[4]), b = std::stod((*it)[5]);
    worst = std::max(worst, (p + tipOffset_m(degToRad(a), degToRad(b), o.radius_mm) - tip0).norm());
  }
  EXPECT_EQ(n, expected_feeds);
  // rounding of each coordinate to 0.0001 in: |error| <= sqrt(3) x 0.5e-4 in = 2.2 um, plus
  // rs274's printed 4 decimals of the angle (0.5e-4 deg x 381 mm = 0.33 um).
  EXPECT_LT(worst, std::sqrt(3.0) * 0.5e-4 * kMmPerInch + 0.5e-4 * kRadPerDeg * o.radius_mm + 1e-6);
  EXPECT_NE(r.out.find("DWELL"), std::string::npos);
}

TEST(TooltipRs274, Table1ProgramRunsAndKeepsTheTipFixed) {
  if (!fs::exists(kRs274)) GTEST_SKIP() << kRs274 << " not found";
  // 18 steps + the zero-length feed of "G91 G01 G93 F2." (004's mode line)
  expectRs274KeepsTipFixed(table1Plan(), 18 + 1);
}

// A new static plan runs three times in its program, each run from the zero pose with the stop
// that zeroes the laser: three times Table 1's feeds and stops, the tip fixed throughout.
TEST(TooltipRs274, ANewPlansThreeRunsRunAndKeepTheTipFixed) {
  if (!fs::exists(kRs274)) GTEST_SKIP() << kRs274 << " not found";
  CycleOptions o{{"units", "inch"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}};
  const ProbePlan plan = makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")), o);
  ASSERT_EQ(tooltipOptionsFrom(plan.options, plan.machine).repeats, kTooltipRepeats);
  expectRs274KeepsTipFixed(plan, 3 * (18 + 1));
  const Rs274Run r = runRs274(dialectByName("linuxcnc").writeProgram(test::cycleProgram(plan, "linuxcnc")));
  size_t stops = 0;
  for (size_t p = r.out.find("PROGRAM_STOP"); p != std::string::npos; p = r.out.find("PROGRAM_STOP", p + 1)) ++stops;
  EXPECT_EQ(stops, 3u) << r.out;
}

TEST(TooltipRs274, DynamicTestRunsAtEveryAngleOfTheOtherAxis) {
  if (!fs::exists(kRs274)) GTEST_SKIP() << kRs274 << " not found";
  // B axis sweeping at A = 0, 30 and 60 deg (004 Sec. VI), 2 sweeps of 15 deg steps; mm program.
  const ProbePlan plan = table1Plan({{"axis", "B"}, {"sweeps", "2"}, {"other_deg", "0,30,60"}, {"step_deg", "15"},
                                     {"units", "inch"}});
  const std::string text = dialectByName("linuxcnc").writeProgram(test::cycleProgram(plan, "linuxcnc"));
  const Rs274Run r = runRs274(text);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  size_t feeds = 0;
  for (size_t p = r.out.find("STRAIGHT_FEED"); p != std::string::npos; p = r.out.find("STRAIGHT_FEED", p + 1)) ++feeds;
  // every point but the three zero poses is a step of tooltipPiecesPerStep moves (the dynamic
  // test keeps the tip on its point), plus one zero-length feed per sweep (mode line)
  const int pieces = tooltipPiecesPerStep(tooltipOptionsFrom(plan.options, plan.machine));
  EXPECT_GT(pieces, 1);
  EXPECT_EQ(feeds, (plan.points.size() - 3) * static_cast<size_t>(pieces) + 3);
}

}  // namespace
}  // namespace rotacal::test

namespace rotacal::test {
namespace {

// The dynamic test's program (issue 17): each joint-space move keeps the tool tip on its point.
// The test walks the neutral program's incremental moves itself and evaluates the tip, pivot +
// Rx(A) Ry(B) (0, 0, -R), at 50 points along each move against the fixed tip.
struct Walk {
  double worst_um = 0.0;
  int moves = 0;
};

Walk walkDynamic(const ProbePlan& plan) {
  const nc::Program prog = tooltipProgram(plan, "linuxcnc");
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const double unit = o.inch ? kMmPerInch : 1.0;
  const Eigen::Vector3d tip = plan.points.front().contact_w_mm;
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
  Pose q;
  bool incremental = false;
  Walk w;
  const int sign = plan.machine.controllerSign(o.axis, "linuxcnc");
  for (const auto& op : prog.ops) {
    if (op.kind == nc::Op::Kind::Mode) incremental = op.incremental;
    if (op.kind == nc::Op::Kind::Rapid) pivot = op.xyz * unit;
    if (op.kind == nc::Op::Kind::Index)
      for (const auto& [ax, deg] : op.rotary) (ax == 'A' ? q.A : q.B) = sign * deg;
    if (op.kind != nc::Op::Kind::RotaryLinear) continue;
    EXPECT_TRUE(incremental);
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    for (char ax : op.axes) d[ax - 'X'] = op.xyz[ax - 'X'] * unit;
    const double dq = sign * op.rotary.front().second;
    for (int i = 0; i <= 50; ++i) {
      const double s = i / 50.0;
      Pose at = q;
      (o.axis == 'A' ? at.A : at.B) += s * dq;
      const Eigen::Vector3d t = pivot + s * d + tipOffset_m(degToRad(at.A), degToRad(at.B), o.radius_mm);
      w.worst_um = std::max(w.worst_um, mmToUm((t - tip).norm()));
    }
    pivot += d;
    (o.axis == 'A' ? q.A : q.B) += dq;
    ++w.moves;
  }
  return w;
}

TEST(TooltipProgram, TheDynamicTestKeepsTheTipWithinItsStatedSag) {
  // 004 Sec. VI at R = 381 mm, 5 deg steps: one move per step sags 363 um mid-move.
  const CycleOptions base{{"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "30"}, {"sweeps", "1"}};
  CycleOptions whole = base;
  whole["max_sag_um"] = "999";
  const Walk coarse = walkDynamic(makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")), whole));
  EXPECT_NEAR(coarse.worst_um, mmToUm(381.0 * (1 - std::cos(degToRad(2.5)))), 1.0);  // 362.7 um
  const ProbePlan plan = makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")), base);
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const Walk fine = walkDynamic(plan);
  std::printf("dynamic test, R 381 mm, 5 deg steps: one move per step %.1f um; %d moves per step %.3f um (bound %.3f "
              "um + the printed decimals)\n",
              coarse.worst_um, tooltipPiecesPerStep(o), fine.worst_um, tooltipSagUm(o));
  EXPECT_EQ(fine.moves, coarse.moves * tooltipPiecesPerStep(o));
  EXPECT_LE(tooltipSagUm(o), 1.0);
  // The sag bound plus the rounding of the printed coordinates (half a unit of the last decimal
  // per coordinate, two in the plane: head_ab is an inch machine, 4 decimals: 1.80 um).
  const double half_unit_um = o.inch ? 0.5e-4 * kMmPerInch * 1000.0 : 0.5;
  EXPECT_LT(fine.worst_um, tooltipSagUm(o) + std::sqrt(2.0) * half_unit_um);
  // The program states it.
  const std::string text = dialectByName("linuxcnc").writeProgram(tooltipProgram(plan, "linuxcnc"));
  EXPECT_NE(text.find(fmt::format("in {} moves", tooltipPiecesPerStep(o))), std::string::npos);
}

}  // namespace
}  // namespace rotacal::test
