// Feed moves split by `compensate` (issue 18, item 2), checked by an independent path: a small
// interpreter in this test reads the rewritten LinuxCNC program, runs every written line as the
// machine would (a straight joint-space move) on the machine with the errors, and measures the
// distance of the controlled point, seen from the workpiece, to the nominal path (the nominal
// move's workpiece curve as a fine polyline: the geometric definition, not the same-fraction
// figure the subdivision itself evaluates). Also: G93 feeds keep each block's time, zero errors
// reproduce every dialect's program line for line, and rs274 reads the split program.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <unistd.h>

#include "controllers/dialect.hpp"
#include "core/compensation.hpp"
#include "core/units.hpp"
#include "postproc/compensate_program.hpp"
#include "rs274_run.hpp"
#include "test_util.hpp"
#include "dialect_lists.hpp"

namespace rotacal {
namespace {

// 3 x 000 Table 4 and an error motion of C (3 um cos 2C radial, 1.5 um sin 3C axial, 5 urad
// sin C angular), sampled at 12 angles as a cycle reports it.
GeometricErrors threeTimesTable4WithMotion() {
  LocationErrors e = test::table4Mean();
  e.values *= 3.0;
  GeometricErrors g(e);
  ComponentErrors c;
  for (int i = 0; i < 12; ++i) {
    const double a = 30.0 * i, r = degToRad(a);
    c.angle_deg.push_back(a);
    ComponentVector v = ComponentVector::Zero();
    v[0] = 3e-3 * std::cos(2 * r);
    v[2] = 1.5e-3 * std::sin(3 * r);
    v[5] = 5e-6 * std::sin(r);
    c.values.push_back(v);
  }
  g.components.push_back(c);
  return g;
}

// The path: the tool 200 mm from the C axis, 150 mm above the table; each move turns C by 15 deg
// and A by 15 deg (down to -90 and back), as a five-axis finishing path would.
MachineCommand pathPoint(int k) {
  const double tilt = -15.0 * std::abs(((k + 6) % 12) - 6);
  const Pose q{tilt, 0.0, -180.0 + 15.0 * k};
  const double c = degToRad(q.C);
  return {T_m_w_nominal(Kinematics::TableAC, q) * Eigen::Vector3d(200.0 * std::cos(c), 200.0 * std::sin(c), 150.0), q};
}
constexpr int kMoves = 24;

// The program in LinuxCNC's signs (A counts the other way there: controllerSign).
std::string pathProgram(const MachineModel& m, bool inverse_time) {
  const int sa = m.controllerSign('A', "linuxcnc"), sc = m.controllerSign('C', "linuxcnc");
  std::string t = "%\n(five-axis path)\nG21 G90 G17 G40 G49\nG54\n";
  auto words = [&](const MachineCommand& c) {
    return fmt::format("X{:.4f} Y{:.4f} Z{:.4f} A{:.4f} C{:.4f}", c.x_m_mm.x(), c.x_m_mm.y(), c.x_m_mm.z(),
                       sa * c.pose.A, sc * c.pose.C);
  };
  t += "G0 " + words(pathPoint(0)) + "\n";
  t += inverse_time ? "G93\n" : "G94\n";
  for (int k = 1; k <= kMoves; ++k)
    t += (k == 1 ? "G1 " : "") + words(pathPoint(k)) + (inverse_time ? " F12.5" : k == 1 ? " F800.0" : "") + "\n";
  t += "G94\nM2\n%\n";
  return t;
}

struct Written {
  MachineCommand end;
  double f = 0.0;
};

// What the written program commands, line by line (motion lines only, after the first rapid).
std::vector<Written> interpret(const std::string& text, const MachineModel& m) {
  const int sa = m.controllerSign('A', "linuxcnc"), sc = m.controllerSign('C', "linuxcnc");
  std::vector<Written> out;
  std::istringstream in(text);
  std::string line;
  Written cur;
  static const std::regex word(R"(([XYZACF])(-?[0-9.]+))");
  while (std::getline(in, line)) {
    line = std::regex_replace(line, std::regex(R"(\([^)]*\))"), "");
    bool motion = false;
    cur.f = 0.0;
    for (std::sregex_iterator it(line.begin(), line.end(), word), end; it != end; ++it) {
      const char l = (*it)[1].str()[0];
      const double v = std::stod((*it)[2].str());
      if (l == 'X') cur.end.x_m_mm.x() = v;
      if (l == 'Y') cur.end.x_m_mm.y() = v;
      if (l == 'Z') cur.end.x_m_mm.z() = v;
      if (l == 'A') cur.end.pose.A = sa * v;
      if (l == 'C') cur.end.pose.C = sc * v;
      if (l == 'F') cur.f = v;
      motion = motion || l != 'F';
    }
    if (motion) out.push_back(cur);
  }
  return out;
}

MachineCommand lerp(const MachineCommand& a, const MachineCommand& b, double s) {
  return {a.x_m_mm + s * (b.x_m_mm - a.x_m_mm), Pose{a.pose.A + s * (b.pose.A - a.pose.A), 0.0, a.pose.C + s * (b.pose.C - a.pose.C)}};
}

Eigen::Vector3d nominalWorkpiece(const MachineCommand& c) {
  return T_m_w_nominal(Kinematics::TableAC, c.pose).inverse() * c.x_m_mm;
}

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * d)).norm();
}

struct PathCheck {
  double worst_mm = 0.0;
  int lines = 0;
  std::vector<double> block_minutes;  // G93: sum of 1 / F over each nominal block's lines
};

// Runs the written lines on the machine with `g` and measures the distance to the nominal path.
PathCheck check(const std::string& text, const MachineModel& m, const GeometricErrors& g) {
  const std::vector<Written> w = interpret(text, m);
  PathCheck r;
  r.block_minutes.assign(kMoves, 0.0);
  int k = 0;  // nominal move being run
  std::vector<Eigen::Vector3d> curve;
  auto curveOf = [&](int move) {
    curve.clear();
    for (int i = 0; i <= 2000; ++i) curve.push_back(nominalWorkpiece(lerp(pathPoint(move), pathPoint(move + 1), i / 2000.0)));
  };
  curveOf(0);
  for (size_t i = 1; i < w.size() && k < kMoves; ++i) {
    ++r.lines;
    for (int j = 0; j <= 40; ++j) {
      const MachineCommand c = lerp(w[i - 1].end, w[i].end, j / 40.0);
      const Eigen::Vector3d p = T_m_w(g, c.pose).inverse() * c.x_m_mm;
      double d = 1e9;
      for (size_t s = 1; s < curve.size(); ++s) d = std::min(d, distanceToSegment(p, curve[s - 1], curve[s]));
      r.worst_mm = std::max(r.worst_mm, d);
    }
    if (w[i].f > 0) r.block_minutes[static_cast<size_t>(k)] += 1.0 / w[i].f;
    const Eigen::Vector3d reached = T_m_w(g, w[i].end.pose).inverse() * w[i].end.x_m_mm;
    if ((reached - nominalWorkpiece(pathPoint(k + 1))).norm() < 2e-4 && ++k < kMoves) curveOf(k);
  }
  EXPECT_EQ(k, kMoves) << "the written lines did not reach every nominal end";
  return r;
}

TEST(SplitMoves, FiveAxisPathStaysWithinHalfAMicrometreOfTheNominalPath) {
  const MachineModel m = test::acMachine();
  const GeometricErrors g = threeTimesTable4WithMotion();
  for (bool inverse_time : {false, true}) {
    const std::string program = pathProgram(m, inverse_time);
    ProgramCompensationOptions split;
    const ProgramCompensation c = compensateProgram(program, "path.ngc", m, g, NcSyntax{"linuxcnc"}, split);
    ProgramCompensationOptions whole;
    whole.subdivide = false;
    const ProgramCompensation u = compensateProgram(program, "path.ngc", m, g, NcSyntax{"linuxcnc"}, whole);
    const PathCheck cs = check(c.text, m, g), us = check(u.text, m, g);
    std::printf("%s: %d moves -> %d lines; off the nominal path: unsplit %.3f um, split %.3f um\n",
                inverse_time ? "G93" : "G94", kMoves, cs.lines, mmToUm(us.worst_mm), mmToUm(cs.worst_mm));
    EXPECT_GT(c.split_blocks, 0);
    EXPECT_EQ(cs.lines, kMoves + c.added_blocks);
    // The tolerance (0.2 um) plus the printing (4 decimals: 0.087 um in space).
    EXPECT_LT(mmToUm(cs.worst_mm), 0.3);
    EXPECT_GT(us.worst_mm, cs.worst_mm);
    if (inverse_time) {
      // Each nominal block keeps its time: 1 / 12.5 min, split or not.
      for (int k = 0; k < kMoves; ++k) EXPECT_NEAR(cs.block_minutes[static_cast<size_t>(k)], 1.0 / 12.5, 1e-6) << "block " << k;
    }
  }
}

TEST(SplitMoves, LinuxcncInterpreterReadsTheSplitProgram) {
  if (!test::haveRs274()) GTEST_SKIP() << "rs274 (linuxcnc-uspace) not installed";
  const MachineModel m = test::acMachine();
  const ProgramCompensation c =
      compensateProgram(pathProgram(m, true), "path.ngc", m, threeTimesTable4WithMotion(), NcSyntax{"linuxcnc"}, {});
  ASSERT_GT(c.added_blocks, 0);
  const test::Rs274Run r = test::runRs274(c.text);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(static_cast<int>(test::countOf(r.out, "STRAIGHT_FEED")), kMoves + c.added_blocks);
}

TEST(SplitMoves, ZeroErrorsReproduceEveryDialectsProgramByteForByte) {
  // Zero errors change no word: every dialect's program comes back as it was, without the mark.
  // Errors of 1 nm change the header only (the mark and the errors) and no line of the program.
  const ProbePlan plan = test::touch154Plan();
  for (const std::string& d : test::wordAddressDialects()) {
    const std::string program = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
    NcSyntax syntax{d};
    if (d == "siemens") syntax.comment = NcSyntax::Comment::Semicolon;
    EXPECT_EQ(compensateProgram(program, "p", plan.machine, GeometricErrors(LocationErrors{}), syntax, {}).text, program)
        << d;
    LocationErrors tiny;
    tiny.set("dz_AY", 1e-6);
    const std::string out = compensateProgram(program, "p", plan.machine, GeometricErrors(tiny), syntax, {}).text;
    std::vector<std::string> a, b;
    std::string l;
    for (std::istringstream s(program); std::getline(s, l);) a.push_back(l);
    for (std::istringstream s(out); std::getline(s, l);) b.push_back(l);
    ASSERT_GT(b.size(), a.size()) << d;
    size_t first = 0;
    while (first < a.size() && a[first] == b[first]) ++first;
    const size_t header = b.size() - a.size();
    for (size_t i = first; i < a.size(); ++i) ASSERT_EQ(a[i], b[i + header]) << d << " line " << i + 1;
    // The header: comments, and the dialect's statement of a compensated program where it has one.
    for (size_t i = first; i < first + header; ++i)
      EXPECT_TRUE(b[i].find_first_of("(;") != std::string::npos || b[i] == dialectByName(d).compensationMark())
          << d << ": " << b[i];
  }
}

}  // namespace
}  // namespace rotacal
