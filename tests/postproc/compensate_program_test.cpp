// The rewritten program against an independent path: a small G90 interpreter in this test reads
// each probing move (pose, start, end) of the original and of the compensated LinuxCNC program;
// the exact simulator then runs the original on the nominal machine and the compensated one on
// the machine with 000 Table 4's errors, both against the same true test piece. The ball centre
// at every trigger, seen from the workpiece, must be the same; the uncompensated program on the
// machine with errors must miss by the errors' size (so the check can fail).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <unistd.h>

#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/simulation.hpp"
#include "postproc/compensate_program.hpp"
#include "postproc/probe_program.hpp"
#include "rs274_run.hpp"
#include "test_util.hpp"
#include "dialect_lists.hpp"

namespace rotacal {
namespace {

std::string fixedOf(double v) { return fmt::format("{:.4f}", v); }

struct ProbeMove {
  Pose pose;  // papers' convention
  Eigen::Vector3d start, end;
};

// G90 only, X Y Z A C literal words, G38.2 is the recorded probe (the double touch is off).
std::vector<ProbeMove> probeMoves(const std::string& text, int sign) {
  std::vector<ProbeMove> moves;
  Eigen::Vector3d x = Eigen::Vector3d::Constant(NAN);
  Pose q;
  std::istringstream in(text);
  std::string line;
  const std::regex word(R"(([XYZAC])(-?[0-9]+\.[0-9]+))");
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '(' || line[0] == 'o' || line[0] == '%') continue;
    Eigen::Vector3d nx = x;
    for (auto it = std::sregex_iterator(line.begin(), line.end(), word); it != std::sregex_iterator(); ++it) {
      const char c = (*it)[1].str()[0];
      const double v = std::stod((*it)[2].str());
      if (c == 'X') nx.x() = v;
      if (c == 'Y') nx.y() = v;
      if (c == 'Z') nx.z() = v;
      if (c == 'A') q.A = sign * v;
      if (c == 'C') q.C = sign * v;
    }
    if (line.rfind("G38.2", 0) == 0) moves.push_back({q, x, nx});
    x = nx;
  }
  return moves;
}

// The plan of the probing moves as the machine executes them.
ProbePlan planOfMoves(const ProbePlan& base, const std::vector<ProbeMove>& moves) {
  ProbePlan p = base;
  for (size_t i = 0; i < moves.size(); ++i) {
    ProbePoint& pt = p.points[i];
    pt.pose = moves[i].pose;
    pt.approach_m = (moves[i].end - moves[i].start).normalized();
    pt.trigger_m_mm = moves[i].end - base.machine.overtravel_mm * pt.approach_m;
  }
  return p;
}

struct Fixture {
  ProbePlan plan = test::touch154Plan();
  LocationErrors errors = test::table4Mean();
  Truth piece;  // the true test piece of the bundled truth: set up 0.5 mm / 2 mrad off, top tilted
  std::string program;
  Fixture() {
    piece = loadTruth(test::sourcePath("examples/truth/table4_mean.json"), Kinematics::TableAC);
    piece.errors = LocationErrors{};
    program = dialectByName("linuxcnc").writeProgram(test::cycleProgram(plan, "linuxcnc"));
  }
  ProgramCompensation compensate(const LocationErrors& e) const {
    return compensateProgram(program, "touch154.ngc", plan.machine, e, NcSyntax{"linuxcnc"}, {});
  }
  // Ball centres at trigger in the workpiece frame when `text` runs on a machine with `e`.
  std::vector<Eigen::Vector3d> triggersInWorkpiece(const std::string& text, const LocationErrors& e) const {
    const auto moves = probeMoves(text, plan.machine.controllerSign('A', "linuxcnc"));
    EXPECT_EQ(moves.size(), plan.points.size());
    const ProbePlan p = planOfMoves(plan, moves);
    Truth t = piece;
    t.errors = e;
    const MeasurementRun run = simulate(p, t, SimulationOptions{});
    std::vector<Eigen::Vector3d> w;
    for (size_t i = 0; i < run.points.size(); ++i)
      w.push_back(T_m_w(e, p.points[i].pose).inverse() * run.points[i].position_m_mm);
    return w;
  }
};

TEST(CompensateProgram, CompensatedProgramOnTheMachineWithErrorsTouchesWhereTheNominalDoes) {
  const Fixture f;
  const ProgramCompensation c = f.compensate(f.errors);
  const auto nominal = f.triggersInWorkpiece(f.program, LocationErrors{});
  const auto compensated = f.triggersInWorkpiece(c.text, f.errors);
  const auto uncompensated = f.triggersInWorkpiece(f.program, f.errors);
  double worst = 0, worst_uncomp = 0;
  for (size_t i = 0; i < nominal.size(); ++i) {
    worst = std::max(worst, (compensated[i] - nominal[i]).norm());
    worst_uncomp = std::max(worst_uncomp, (uncompensated[i] - nominal[i]).norm());
  }
  // 4 printed decimals: +-0.05 um per coordinate (0.087 um in space), plus the tool direction the
  // rotary axes cannot restore at A = 0 (< 2 urad) over the few mm of the probing line.
  std::printf("compensated vs nominal: worst %.4f um; uncompensated: worst %.2f um; direction residual %.3f urad\n",
              mmToUm(worst), mmToUm(worst_uncomp), c.max_direction_residual_rad * 1e6);
  EXPECT_LT(mmToUm(worst), 0.1);
  EXPECT_GT(mmToUm(worst_uncomp), 20.0);  // Table 4's errors: tens of um at the piece
  EXPECT_EQ(c.compensated_blocks + c.uncompensated_blocks, c.motion_blocks);
  EXPECT_LE(c.uncompensated_blocks, 2);  // the first climb and index, before X and Y are known
  EXPECT_LT(c.max_direction_residual_rad, mdegToRad(0.2) + 1e-9);  // at most b_CA, the tilt about Y at A = 0
}

TEST(CompensateProgram, ZeroErrorsReproduceEveryCoordinate) {
  const Fixture f;
  const ProgramCompensation c = f.compensate(LocationErrors{});
  const int sign = f.plan.machine.controllerSign('A', "linuxcnc");
  const auto a = probeMoves(f.program, sign), b = probeMoves(c.text, sign);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_LT((a[i].end - b[i].end).norm(), 1e-12);
    EXPECT_LT((a[i].start - b[i].start).norm(), 1e-12);
    EXPECT_DOUBLE_EQ(a[i].pose.A, b[i].pose.A);
    EXPECT_DOUBLE_EQ(a[i].pose.C, b[i].pose.C);
  }
  EXPECT_LT(c.max_shift_mm, 1e-12);  // rounding of the HTM round trip only
}

TEST(CompensateProgram, LinuxcncInterpreterAcceptsTheRewrittenProgram) {
  if (!test::haveRs274()) GTEST_SKIP() << "rs274 (linuxcnc-uspace) not installed";
  const Fixture f;
  // A report path with parentheses: as written before, "(... REPORT (1).json)" nested them and
  // rs274 refused the program.
  ProgramCompensationOptions opt;
  opt.header = {"location errors of out/REPORT (1).json:"};
  std::string text = compensateProgram(f.program, "touch154.ngc", f.plan.machine, f.errors, NcSyntax{"linuxcnc"}, opt).text;
  ASSERT_NE(text.find("REPORT [1].json"), std::string::npos);
  text = std::regex_replace(text, std::regex("#5070"), "1");  // a probe that trips (rs274's canon never does)
  const test::Rs274Run r = test::runRs274(text);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(test::countOf(r.out, "STRAIGHT_PROBE"), 154u);
}

TEST(CompensateProgram, IncrementalLinearMovesGetTheRotatedIncrement) {
  const Fixture f;
  // A30.0 in LinuxCNC's count is A = -30 deg in the papers' convention: inside the stroke [-110, 20].
  const std::string prog = "%\nG20 G90\nG0 X1.0 Y-8.0 Z6.0 A30.0 C45.0\nG91 G1 X0.5 Y0.25 Z-0.125 F10.0\nG90\n%\n";
  const LocationErrors e = f.errors;
  const ProgramCompensation c = compensateProgram(prog, "inc.ngc", f.plan.machine, e, NcSyntax{"linuxcnc"}, {});
  // Independent: the two absolute points compensated by the core, differenced.
  const int sa = f.plan.machine.controllerSign('A', "linuxcnc"), sc = f.plan.machine.controllerSign('C', "linuxcnc");
  Pose q;
  q.A = sa * 30.0;  // the program counts in the controller's sense (MACHINE.json)
  q.C = sc * 45.0;
  const CompensatedCommand cc = compensatePose(e, q);
  Pose q_printed = cc.pose;
  q_printed.A = sa * std::stod(fixedOf(sa * cc.pose.A));
  q_printed.C = sc * std::stod(fixedOf(sc * cc.pose.C));
  const Eigen::Vector3d p0 = Eigen::Vector3d(1.0, -8.0, 6.0) * 25.4, d = Eigen::Vector3d(0.5, 0.25, -0.125) * 25.4;
  const Eigen::Vector3d inc = (compensatedPosition(e, q, p0 + d, q_printed) - compensatedPosition(e, q, p0, q_printed)) / 25.4;
  const std::regex w(R"(G91 G1 X(-?[0-9.]+) Y(-?[0-9.]+) Z(-?[0-9.]+) F10\.0)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(c.text, m, w)) << c.text;
  EXPECT_NEAR(std::stod(m[1].str()), inc.x(), 0.5e-5 + 1e-12);  // 5 decimals in inch
  EXPECT_NEAR(std::stod(m[2].str()), inc.y(), 0.5e-5 + 1e-12);
  EXPECT_NEAR(std::stod(m[3].str()), inc.z(), 0.5e-5 + 1e-12);
  // A rotation of 0.5 mdeg tilts the increment: it is not the written one.
  EXPECT_GT((inc - Eigen::Vector3d(0.5, 0.25, -0.125)).norm(), 1e-6);
}

TEST(CompensateProgram, RefusesWhatItCannotKeepExactNamingTheLine) {
  const Fixture f;
  auto lineOf = [&](const std::string& prog) -> std::string {
    try {
      compensateProgram(prog, "p.ngc", f.plan.machine, f.errors, NcSyntax{"linuxcnc"}, {});
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string head = "G21 G90\nG0 X10.0 Y-200.0 Z200.0 A0.0 C0.0\n";
  EXPECT_NE(lineOf(head + "G2 X20.0 Y-200.0 I5.0 J0.0\n").find("p.ngc:3: an arc"), std::string::npos);
  EXPECT_NE(lineOf(head + "G43.4 H1\n").find("p.ngc:3: G43.4"), std::string::npos);
  EXPECT_NE(lineOf(head + "G91 G0 A10.0\n").find("p.ngc:3: an incremental (G91) move of A"), std::string::npos);
  EXPECT_NE(lineOf(head + "G1 X[#1+2] F100.0\n").find("p.ngc:3: X[#1+2] is an expression"), std::string::npos);
  EXPECT_NE(lineOf(head + "G10 L2 P1 X1.0\n").find("p.ngc:3: G10 changes an offset"), std::string::npos);
  EXPECT_NE(lineOf(head + "G0 X900.0\n").find("p.ngc:3: the compensated X"), std::string::npos);
}

TEST(CompensateProgram, RotaryWordPushedPastItsStrokeIsRefused) {
  // A-110 sits on the bundled machine's A stroke end [-110, 20]; a_AY = -0.5 mdeg moves it.
  const Fixture f;
  Pose q;
  q.A = -110.0;
  const CompensatedCommand cc = compensatePose(f.errors, q);
  const std::string printed = fixedOf(cc.pose.A);  // fanuc counts A as the papers do
  ASSERT_LT(std::stod(printed), -110.0) << "the case needs the compensation to push A beyond -110";
  auto run = [&](const std::string& a_word, const MachineModel& m) -> std::string {
    const std::string prog = "%\nO7154\nG21 G90\nG0 X0.0 Y0.0 Z200.0 C0.0 " + a_word + "\nM30\n%\n";
    try {
      compensateProgram(prog, "p.nc", m, f.errors, NcSyntax{"fanuc"}, {});
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string m = run("A-110.0", f.plan.machine);
  EXPECT_EQ(m.rfind(fmt::format("p.nc:4: the compensated A{} ", printed), 0), 0u) << m;
  EXPECT_NE(m.find("outside the stroke [-110, 20]"), std::string::npos) << m;
  // Not refused for the angle itself: inside the stroke, or with a stroke that has room.
  EXPECT_EQ(run("A-100.0", f.plan.machine), "accepted");
  MachineModel wider = f.plan.machine;
  for (auto& r : wider.rotary)
    if (r.name == 'A') r.stroke_deg.min = -111.0;
  EXPECT_EQ(run("A-110.0", wider), "accepted");
}

TEST(CompensateProgram, MalformedInputIsRefusedNamingTheLineNeverACrash) {
  const Fixture f;
  auto messageOf = [&](const std::string& prog, const std::string& dialect) -> std::string {
    const NcSyntax syntax{dialect, 4, 5, 4,
                          dialect == "siemens" ? NcSyntax::Comment::Semicolon : NcSyntax::Comment::Parentheses};
    try {
      compensateProgram(prog, "p.nc", f.plan.machine, f.errors, syntax, {});
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string head = "G21 G90\nG0 X10.0 Y-200.0 Z200.0 A0.0 C0.0\n";
  // A measuring prefix with nothing behind it (was front() of an empty vector).
  EXPECT_EQ(messageOf(head + "MEAS=1 \nM30\n", "siemens").rfind("p.nc:3: 'MEAS=1' without a move", 0), 0u)
      << messageOf(head + "MEAS=1 \nM30\n", "siemens");
  EXPECT_EQ(messageOf(head + "MEAS=1 ;probe\nM30\n", "siemens").rfind("p.nc:3: 'MEAS=1' without a move", 0), 0u);
  // 100 kB lines (std::regex recursed once per character and overflowed the stack): refused by
  // their length before any regex sees them, whatever they hold.
  for (const std::string& big : {std::string(100000, ' '), "G1 X1.0" + std::string(100000, '0'),
                                 "R1=" + std::string(100000, '1')}) {
    const std::string m = messageOf(head + big + "\nM30\n", "siemens");
    EXPECT_EQ(m.rfind(fmt::format("p.nc:3: line of {} characters", big.size()), 0), 0u) << m.substr(0, 200);
  }
  // A long line within the limit still goes through the regexes (1000 leading blanks: the
  // measuring-prefix test runs on the raw line).
  EXPECT_EQ(messageOf(head + std::string(1000, ' ') + "G0 Z200.0\nM30\n", "siemens"), "accepted");
  // Exponent notation: X1e2 was read as X1 and a word E2.
  EXPECT_EQ(messageOf(head + "G1 X1e2 F100.0\n", "linuxcnc").rfind("p.nc:3: word X1e2 uses exponent notation", 0), 0u)
      << messageOf(head + "G1 X1e2 F100.0\n", "linuxcnc");
}

// A Sinumerik part program in the language's own words is compensated as its plain twin is: the
// same rewritten coordinates, its settings kept where they stood; a frame change is refused by
// name, the tool carrier's assignment included.
TEST(CompensateProgram, ASinumerikProgramInItsOwnWordsIsCompensatedAsItsPlainTwin) {
  const Fixture f;
  const NcSyntax syntax{"siemens", 4, 5, 4, NcSyntax::Comment::Semicolon};
  const std::string own = "G71 G90\nTRAFOOF\nSOFT FFWON\nG0 X10.0 Y-200.0 Z200.0 A0.0 C0.0\n"
                          "G1 X=20.0 Y=-190.0 A=-15.0 C=30.0 F800.0 SOFT ; cut\nCYCLE832(0.01,1,1)\nG0 Z210.0\nM30\n";
  const std::string plain = "G71 G90\nG0 X10.0 Y-200.0 Z200.0 A0.0 C0.0\nG1 X20.0 Y-190.0 A-15.0 C30.0 F800.0\n"
                            "G0 Z210.0\nM30\n";
  const auto motion = [](const std::string& text) {  // the moves, without the setting and the comment
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) {
      if (l.rfind("SOFT ", 0) == 0) l = l.substr(5);
      l = l.substr(0, l.find(" ;"));
      if (l.rfind("G0 ", 0) == 0 || l.rfind("G1 ", 0) == 0) out.push_back(l);
    }
    return out;
  };
  const std::string a = compensateProgram(own, "own.mpf", f.plan.machine, f.errors, syntax, {}).text;
  const std::string b = compensateProgram(plain, "plain.mpf", f.plan.machine, f.errors, syntax, {}).text;
  EXPECT_EQ(motion(a), motion(b));
  ASSERT_EQ(motion(a).size(), 3u);
  EXPECT_NE(motion(a)[1], "G1 X20.0 Y-190.0 A-15.0 C30.0 F800.0");  // rewritten, not passed through
  EXPECT_NE(a.find("\nTRAFOOF\nSOFT FFWON\n"), std::string::npos) << a;
  EXPECT_NE(a.find("\nSOFT G1 X"), std::string::npos) << a;  // the setting kept, before the words
  EXPECT_NE(a.find(" F800.0 ; cut\n"), std::string::npos) << a;
  EXPECT_NE(a.find("\nCYCLE832(0.01,1,1)\n"), std::string::npos) << a;
  for (const std::string frame : {"TRAORI", "TCARR=1", "CYCLE800(1,\"TC1\",200000,57,0,0,0,30,0,0,0,0,0,-1,100,1)"}) {
    try {
      compensateProgram("G71 G90\n" + frame + "\nG0 X10.0 Y-200.0 Z200.0 A0.0 C0.0\nM30\n", "p.mpf", f.plan.machine,
                        f.errors, syntax, {});
      ADD_FAILURE() << frame << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("p.mpf:2: " + frame.substr(0, frame.find_first_of("=(")) + " (", 0), 0u)
          << e.what();
    }
  }
}

TEST(CompensateProgram, FanucHeaderGoesAfterTheProgramNumber) {
  const Fixture f;
  const std::string prog = "%\nO7154 (TEST)\nG21 G90\nG0 X10.0 Y-200.0 Z200.0 A0.0 C0.0\nM30\n%\n";
  const ProgramCompensation c =
      compensateProgram(prog, "p.nc", f.plan.machine, f.errors, NcSyntax{"fanuc"}, {{0, 0, 0}, {}, {"HELLO"}, {}, true});
  // The mark first, then the caller's lines, in Fanuc's comment form, before the first block.
  EXPECT_EQ(c.text.rfind("%\nO7154 (TEST)\n(ROTACAL-COMPENSATED: REWRITTEN BY ROTACAL COMPENSATE", 0), 0u) << c.text;
  EXPECT_NE(c.text.find(")\n(HELLO)\nG21 G90\n"), std::string::npos) << c.text;
}


// Every word-address dialect's own touch154 program, rewritten, probes the same compensated end
// points as the LinuxCNC one (whose end points the exact simulator checks above): the statements
// of the richer dialects (Siemens DEF/IF/WRITE/R90=, MEAS=1 prefixes, Okuma VC/PUT/FWRITC) pass
// through and only the motion is rewritten.
TEST(CompensateProgram, EveryWordAddressDialectGetsTheSameGuardedEndPoints) {
  const ProbePlan plan = test::touch154Plan();
  const LocationErrors e = test::table4Mean();
  auto endpoints = [&](const std::string& dialect) {
    const std::string text = dialectByName(dialect).writeProgram(test::cycleProgram(plan, dialect));
    const NcSyntax syntax{dialect, 4, 5, 4,
                          dialect == "siemens" ? NcSyntax::Comment::Semicolon : NcSyntax::Comment::Parentheses};
    const std::string out = compensateProgram(text, dialect, plan.machine, e, syntax, {}).text;
    const std::regex guarded(R"((?:G38\.2|G31|MEAS=1 G1) X(-?[0-9.]+) Y(-?[0-9.]+) Z(-?[0-9.]+))");
    std::vector<Eigen::Vector3d> v;
    for (auto it = std::sregex_iterator(out.begin(), out.end(), guarded); it != std::sregex_iterator(); ++it)
      v.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3]));
    return v;
  };
  const auto ref = endpoints("linuxcnc");
  ASSERT_EQ(ref.size(), plan.points.size());
  for (const std::string& d : test::endPointCheckDialects()) {
    const auto v = endpoints(d);
    ASSERT_EQ(v.size(), ref.size()) << d;
    for (size_t i = 0; i < v.size(); ++i) EXPECT_LT((v[i] - ref[i]).norm(), 1e-9) << d << " point " << i + 1;
  }
}


NcSyntax syntaxFor(const std::string& dialect) {
  return NcSyntax{dialect, 4, 5, 4, dialect == "siemens" ? NcSyntax::Comment::Semicolon : NcSyntax::Comment::Parentheses};
}

// One guarded probing move of a program and its no-trigger check, read back from the text with
// this test's own patterns (not the library's parser).
struct GuardedMove {
  int line = 0;
  Eigen::Vector3d start = Eigen::Vector3d::Constant(NAN), end = Eigen::Vector3d::Constant(NAN);
  Eigen::Vector3d expected = Eigen::Vector3d::Constant(NAN);  // the end point the check compares with
  double threshold_sq = NAN;                                    // of the distance test
  bool below_means_untriggered = false;  // Siemens: IF distance < t GOTOF NOHIT; Macro B / Okuma: IF > t skip the alarm
  // What the check decides for a probe that stopped at `stop`: true = "not triggered" (alarm).
  bool untriggered(const Eigen::Vector3d& stop) const {
    const double d2 = (stop - expected).squaredNorm();
    return below_means_untriggered ? d2 < threshold_sq : !(d2 > threshold_sq);
  }
};

std::vector<GuardedMove> guardedMoves(const std::string& text) {
  const std::regex move(R"(^(?:G31|MEAS=1 G1) X(-?[0-9.]+) Y(-?[0-9.]+) Z(-?[0-9.]+))");
  const std::regex motion(R"(^(?:G0?[01]|G31|MEAS=1 G1)\b)");
  const std::regex xyz(R"(([XYZ])(-?[0-9]+\.[0-9]+))");
  const std::regex check(R"(^(#[123]|VC[456]|R9[345])=(#506([123])|VC([123])|R9([012]))([+-])([0-9]+\.[0-9]+)$)");
  const std::regex gt(R"((?:GT|GT )([0-9.]+)\](?:GOTO| N))"), lt(R"(<([0-9.]+)\) GOTOF NOHIT)");
  std::vector<GuardedMove> out;
  Eigen::Vector3d at = Eigen::Vector3d::Constant(NAN);
  std::istringstream in(text);
  std::string l;
  int n = 0;
  while (std::getline(in, l)) {
    ++n;
    std::smatch m;
    if (std::regex_search(l, m, move)) {
      GuardedMove g;
      g.line = n;
      g.start = at;
      g.end = Eigen::Vector3d(std::stod(m[1]), std::stod(m[2]), std::stod(m[3]));
      out.push_back(g);
    }
    if (std::regex_search(l, motion))
      for (auto it = std::sregex_iterator(l.begin(), l.end(), xyz); it != std::sregex_iterator(); ++it)
        at[(*it)[1].str()[0] - 'X'] = std::stod((*it)[2]);
    if (out.empty()) continue;
    GuardedMove& g = out.back();
    if (std::regex_match(l, m, check)) {
      const std::string digit = m[3].matched ? m[3].str() : m[4].matched ? m[4].str() : m[5].str();
      const int axis = m[5].matched ? std::stoi(digit) : std::stoi(digit) - 1;
      const double v = std::stod(m[7]);
      g.expected[axis] = m[6] == "-" ? v : -v;  // stop - v: compares with +v
    } else if (std::regex_search(l, m, gt)) {
      g.threshold_sq = std::stod(m[1]);
    } else if (std::regex_search(l, m, lt)) {
      g.threshold_sq = std::stod(m[1]);
      g.below_means_untriggered = true;
    }
  }
  return out;
}

// Issue 14's most dangerous defect: compensate moved every probing move's end point but left
// the no-trigger check comparing with the old one, so an untriggered probe (a G31 that never
// fires ends silently at its end point) passed. For every dialect with such a check, every
// guarded move of the compensated touch154 program must be followed by a check whose end point
// is the move's own, which catches a probe stopping exactly there and passes one stopping at the
// nominal trigger (overtravel short of the end); the uncompensated check must miss the untriggered
// probe (so this test can fail).
TEST(CompensateProgram, EveryNoTriggerCheckGuardsItsCompensatedEndPoint) {
  const ProbePlan plan = test::touch154Plan();
  const LocationErrors e = test::table4Mean();
  for (const char* d : {"fanuc", "haas", "okuma", "siemens"}) {
    const std::string text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
    const ProgramCompensation c = compensateProgram(text, d, plan.machine, e, syntaxFor(d), {});
    const auto before = guardedMoves(text), after = guardedMoves(c.text);
    ASSERT_EQ(after.size(), plan.points.size()) << d;
    ASSERT_EQ(before.size(), after.size()) << d;
    EXPECT_EQ(c.rewritten_checks, static_cast<int>(3 * plan.points.size())) << d;
    double shift_min = 1e9, shift_max = 0;
    int stale_missed = 0;
    for (size_t i = 0; i < after.size(); ++i) {
      const GuardedMove& g = after[i];
      ASSERT_TRUE(std::isfinite(g.threshold_sq)) << d << " line " << g.line;
      EXPECT_EQ(g.expected, g.end) << d << " line " << g.line;  // digit for digit
      EXPECT_TRUE(g.untriggered(g.end)) << d << " line " << g.line << ": a probe that never fired passes";
      const Eigen::Vector3d trigger = g.end - plan.machine.overtravel_mm * (g.end - g.start).normalized();
      EXPECT_FALSE(g.untriggered(trigger)) << d << " line " << g.line << ": a real trigger raises the alarm";
      // The old check (before the rewrite) against the new end point.
      GuardedMove stale = g;
      stale.expected = before[i].expected;
      stale_missed += !stale.untriggered(g.end);
      const double shift = (g.end - before[i].end).norm();
      shift_min = std::min(shift_min, shift);
      shift_max = std::max(shift_max, shift);
    }
    std::printf("%s: guard end points moved %.1f .. %.1f um; the unrewritten check would pass %d of %zu untriggered probes\n",
                d, mmToUm(shift_min), mmToUm(shift_max), stale_missed, after.size());
    EXPECT_EQ(stale_missed, static_cast<int>(after.size())) << d << ": the case must be one the old check misses";
    EXPECT_NEAR(mmToUm(c.max_check_shift_mm), mmToUm(shift_max), 0.1) << d;
  }
}

TEST(CompensateProgram, ProbingMoveWithoutItsCheckOrWithAnotherEndPointIsRefused) {
  const Fixture f;
  auto run = [&](const std::string& body) -> std::string {
    const std::string prog = "%\nO7154\nG21 G90\nG0 X51.0 Y-235.0 Z200.0 A0.0 C0.0\n" + body + "M30\n%\n";
    try {
      compensateProgram(prog, "p.nc", f.plan.machine, f.errors, syntaxFor("fanuc"), {});
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string move = "G0 Z155.0\nG31 X51.0 Y-235.0 Z150.0 F100.0\n";
  const std::string checks = "#1=#5061-51.0000\n#2=#5062+235.0000\n#3=#5063-150.0000\n";
  EXPECT_EQ(run(move + checks + "G0 Z200.0\n"), "accepted");
  // No check before the next move: the G31 at line 6 is named.
  const std::string none = run(move + "G0 Z200.0\n");
  EXPECT_EQ(none.rfind("p.nc:6: the probing move's end point moves, but its no-trigger check", 0), 0u) << none;
  // Only X and Y: Z is missing.
  EXPECT_NE(run(move + "#1=#5061-51.0000\n#2=#5062+235.0000\nG0 Z200.0\n").find("'#3=#5063-150.0000' for Z"),
            std::string::npos);
  // A check comparing with another point than its move's end: the rewrite cannot tell its meaning.
  const std::string other = run(move + "#1=#5061-52.0000\n#2=#5062+235.0000\n#3=#5063-150.0000\nG0 Z200.0\n");
  EXPECT_EQ(other.rfind("p.nc:7: this no-trigger check compares X with 52", 0), 0u) << other;
}


// Issue 14: compensated Fanuc/Haas/Okuma programs carried lower-case comments of up to 130
// characters that rotacal's own checkers reject. Every dialect's compensated touch154 program,
// mm and inch, with a long lower-case header line, passes that dialect's checker.
TEST(CompensateProgram, EveryDialectsCompensatedProgramPassesItsOwnChecker) {
  const LocationErrors e = test::table4Mean();
  ProgramCompensationOptions opt;
  opt.header = {"location errors of out/report.json:",
                "dx_AY 14.60 um, dy_AY 23.20 um, dz_AY 27.70 um, dy_CA 3.90 um, a_AY -0.50 mdeg, b_AY -0.10 mdeg, "
                "c_AY -0.50 mdeg, b_CA 0.20 mdeg"};
  for (LengthUnit u : {LengthUnit::Millimetre, LengthUnit::Inch}) {
    MachineModel m = test::acMachine();
    m.units = u;
    const ProbePlan plan = makePlan("touch154", m, {});
    for (const std::string& d : test::wordAddressDialects()) {
      const Dialect& dialect = dialectByName(d);
      const std::string text = dialect.writeProgram(test::cycleProgram(plan, d));
      ASSERT_EQ(dialect.check(text, plan, test::shapeOf(plan, d)), std::vector<std::string>{}) << d;
      const std::string out = compensateProgram(text, d, plan.machine, e, syntaxFor(d), opt).text;
      EXPECT_EQ(dialect.check(out, plan, test::shapeOf(plan, d)), std::vector<std::string>{}) << d;
      // The header is there, in the dialect's form.
      EXPECT_NE(out.find("ROTACAL-COMPENSATED"), std::string::npos) << d;
      // LinuxCNC keeps the text; Siemens upper-cases it; Fanuc, Haas, Okuma also turn '_' into '-'.
      const std::string values = std::string(d) == "linuxcnc"  ? "dx_AY 14.60 um"
                                 : std::string(d) == "siemens" ? "DX_AY 14.60 UM"
                                                               : "DX-AY 14.60 UM";
      EXPECT_NE(out.find(values), std::string::npos) << d;
      if (std::string(d) == "siemens") {
        EXPECT_EQ(out.rfind("; %_N_ROTACAL_TOUCH154_MPF\n", 0), 0u) << "transfer line first";
      }
    }
  }
}

TEST(CompensateProgram, ARewriteTheDialectsCheckerWouldRejectIsRefused) {
  // A Fanuc line of 80 characters (the checker's limit) grows when its words get 4 decimals.
  const Fixture f;
  const std::string move = "G01 X10.0 Y-200.0 Z200.0 A0.0 C0.0 F100.0 ";
  const std::string line = move + "(" + std::string(80 - move.size() - 2, 'P') + ")";
  ASSERT_EQ(line.size(), 80u);
  const std::string prog = "%\nO7154\nG21 G90\n" + line + "\nM30\n%\n";
  std::string m;
  try {
    compensateProgram(prog, "p.nc", f.plan.machine, f.errors, syntaxFor("fanuc"), {});
  } catch (const InputError& e) {
    m = e.what();
  }
  EXPECT_EQ(m.rfind("p.nc:4: the rewritten line fails the fanuc checker: line has ", 0), 0u) << m;
  // The same line without the padding is accepted: the length, not the move, is refused.
  EXPECT_NO_THROW(compensateProgram("%\nO7154\nG21 G90\n" + move + "\nM30\n%\n", "p.nc", f.plan.machine, f.errors,
                                    syntaxFor("fanuc"), {}));
}

TEST(CompensateProgram, ACompensatedProgramIsMarkedAndNotCompensatedAgain) {
  const Fixture f;
  const std::string once = f.compensate(f.errors).text;
  std::string m;
  try {
    compensateProgram(once, "once.ngc", f.plan.machine, f.errors, NcSyntax{"linuxcnc"}, {});
  } catch (const InputError& e) {
    m = e.what();
  }
  // The marker is the first comment of the output, so the refusal names that line.
  size_t marker_line = 1;
  for (size_t p = 0; p < once.find("ROTACAL-COMPENSATED"); ++p) marker_line += once[p] == '\n';
  EXPECT_EQ(m.rfind(fmt::format("once.ngc:{}: the program is already compensated", marker_line), 0), 0u) << m;
  // Stripped of its comments (a DNC filter, a hand edit), LinuxCNC's program still carries its
  // statement, and is refused at it.
  std::string stripped;
  for (std::istringstream in(once); std::getline(in, m);)
    if (m.empty() || m[0] != '(') stripped += m + "\n";
  ASSERT_EQ(stripped.find("ROTACAL-COMPENSATED"), std::string::npos);
  m.clear();
  try {
    compensateProgram(stripped, "stripped.ngc", f.plan.machine, f.errors, NcSyntax{"linuxcnc"}, {});
  } catch (const InputError& e) {
    m = e.what();
  }
  EXPECT_NE(m.find("the program is already compensated (statement #<rotacal_compensated> = 1)"), std::string::npos) << m;
  // Fanuc's upper-case form and Siemens's ';' comments carry it too.
  for (const char* d : {"fanuc", "siemens"}) {
    const std::string text = dialectByName(d).writeProgram(test::cycleProgram(f.plan, d));
    const std::string c = compensateProgram(text, d, f.plan.machine, f.errors, syntaxFor(d), {}).text;
    EXPECT_THROW(compensateProgram(c, d, f.plan.machine, f.errors, syntaxFor(d), {}), InputError) << d;
  }
}


// The loop closed through the program (issue 18, item 5): the compensated program's probing moves
// run on the true machine (the simulator, with the true test piece), the controller's records
// read back as the original program's (undoCompensation, `analyze --compensated-with`) and
// identified with the original plan. Compensated for the exact errors, nothing is left; for
// errors 10 % short, the 10 % is what the analysis finds (first order: true - compensated).
TEST(CompensateProgram, TheCompensatedProgramsResultsIdentifyWhatTheCompensationLeft) {
  const Fixture f;
  const int sign = f.plan.machine.controllerSign('A', "linuxcnc");
  auto leftOver = [&](const GeometricErrors& compensated_for) {
    const std::string text =
        compensateProgram(f.program, "touch154.ngc", f.plan.machine, compensated_for, NcSyntax{"linuxcnc"}, {}).text;
    const ProbePlan executed = planOfMoves(f.plan, probeMoves(text, sign));
    Truth t = f.piece;
    t.errors = f.errors;
    const MeasurementRun run = simulate(executed, t, SimulationOptions{});
    const MeasurementRun back = undoCompensation(f.plan, run, compensated_for, NcSyntax{"linuxcnc"});
    IdentificationOptions o;
    return identify(f.plan, {back}, o).estimate;
  };
  const LocationErrors exact = leftOver(GeometricErrors(f.errors));
  LocationErrors short10 = f.errors;
  short10.values *= 0.9;
  const LocationErrors left = leftOver(GeometricErrors(short10));
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const bool length = locationParameters(Kinematics::TableAC)[i].kind == ParamKind::Length;
    // The printed decimals (0.05 um, 0.05 mdeg of angle words... as rounded) leave a few nm.
    EXPECT_LT(std::abs(exact.reportValue(i)), length ? 0.02 : 0.002) << locationParameters(Kinematics::TableAC)[i].name;
    EXPECT_NEAR(left.reportValue(i), 0.1 * f.errors.reportValue(i), length ? 0.03 : 0.003)
        << locationParameters(Kinematics::TableAC)[i].name;
  }
  // Without reading back, the same records would identify the errors compensated for as if
  // nothing had been done (the check can fail).
  const std::string text =
      compensateProgram(f.program, "touch154.ngc", f.plan.machine, GeometricErrors(f.errors), NcSyntax{"linuxcnc"}, {}).text;
  Truth t = f.piece;
  t.errors = f.errors;
  const MeasurementRun raw = simulate(planOfMoves(f.plan, probeMoves(text, sign)), t, SimulationOptions{});
  const LocationErrors naive = identify(f.plan, {raw}, IdentificationOptions{}).estimate;
  EXPECT_GT(std::abs(naive.reportValue(2) - 0.0), 1.0);  // dz_AY: not near zero
}

// The other mistake: the uncompensated program's results given as the compensated program's.
// Read back, they would identify the errors minus the compensation, near zero: a false
// "verified". The controller's records lie on the probing lines it ran, and those are the
// plan's: refused, naming how many touches tell.
TEST(CompensateProgram, TheUncompensatedProgramsResultsAreNotTakenForTheCompensatedOnes) {
  const Fixture f;
  Truth t = f.piece;
  t.errors = f.errors;
  const MeasurementRun original = simulate(f.plan, t, SimulationOptions{});
  std::string m;
  try {
    undoCompensation(f.plan, original, GeometricErrors(f.errors), NcSyntax{"linuxcnc"});
  } catch (const std::invalid_argument& e) {
    m = e.what();
  }
  EXPECT_NE(m.find("lie on the uncompensated program's lines"), std::string::npos) << m;
}

}  // namespace
}  // namespace rotacal
