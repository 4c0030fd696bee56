// The Heidenhain TNC 640 Klartext dialect: block numbers on every line, BEGIN/END PGM, cycle 0
// with the no-trigger check, FN 16 results with decimal commas and the control's clock per
// point; the parser reads commas and points and names the line of every fault; the checker
// catches planted faults; the offsets file lists the kinematics / preset values to enter.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <regex>

#include "test_util.hpp"
#include "controllers/heidenhain/format_files.hpp"
#include "dialect_battery.hpp"

namespace rotacal {
namespace {

const Dialect& hh() { return dialectByName("heidenhain"); }

TEST(HeidenhainProgram, KlartextFrameAndCycle0) {
  const test::WrittenProgram p("heidenhain", "TCH PROBE 0\\.0");
  EXPECT_EQ(p.ls[0], "0 BEGIN PGM ROTACAL_TOUCH154 MM");
  EXPECT_EQ(p.ls.back(), fmt::format("{} END PGM ROTACAL_TOUCH154 MM", p.ls.size() - 1));
  for (size_t i = 0; i < p.ls.size(); ++i) {
    EXPECT_EQ(p.ls[i].rfind(std::to_string(i) + " ", 0), 0u) << p.ls[i];
    EXPECT_LE(p.ls[i].size(), 80u) << p.ls[i];
  }
  // Point 1: +X face, probed in -X from the approach start 58 to the end 51 (trigger 53.584).
  auto body = [&](size_t i) { return p.ls[i].substr(p.ls[i].find(' ') + 1); };
  EXPECT_EQ(body(p.g), "TCH PROBE 0.0 REF. PLANE Q10 X-");
  EXPECT_EQ(body(p.g + 1), "TCH PROBE 0.1 X+58.0000 Y-235.0000 Z+150.0000");
  EXPECT_EQ(body(p.g + 2), "FN 12: IF +Q10 LT +51.0100 GOTO LBL 1001");
  EXPECT_EQ(body(p.g + 4), "FN 0: QR2 = +Q10");
  EXPECT_EQ(body(p.g + 5), "FN 0: QR3 = -235.0000");
  EXPECT_EQ(body(p.g + 7), "FN 16: F-PRINT TNC:\\ROTACAL\\RCP.A / TNC:\\ROTACAL\\ROTACAL_TOUCH154.TXT");
  // The format files are in the header comments, verbatim.
  for (const auto& [file, content] : heidenhainFormatFiles("touch154", 154))
    EXPECT_NE(p.text.find(fmt::format(" ; {}={}\n", file, content)), std::string::npos) << file;
}


TEST(HeidenhainProgram, RefusesWhatCycle0CannotDo) {
  const ProbePlan plan = test::acPlan();
  nc::Program p = test::cycleProgram(plan, "heidenhain");
  for (auto& op : p.ops)
    if (op.kind == nc::Op::Kind::Probe) {
      op.xyz.y() += 1.0;  // no longer along one axis
      break;
    }
  EXPECT_THROW(hh().writeProgram(p), std::invalid_argument);
}

class HeidenhainCheck : public test::PlantedFaults {
 protected:
  HeidenhainCheck() : PlantedFaults("heidenhain", "TCH PROBE 0\\.0") {}
  std::string at(size_t i, const std::string& body) const { return fmt::format("{} {}", i, body); }
};

TEST_F(HeidenhainCheck, CatchesPlantedFaults) {
  auto ps = with([&](auto& v) { v[g + 2] = at(g + 2, "FN 0: Q99 = +0"); });  // the check removed
  EXPECT_TRUE(test::hasProblem(ps, fmt::format("{}: TCH PROBE 0 is not followed", g + 1))) << ps.size();
  ps = with([&](auto& v) { v[g + 2] = at(g + 2, "FN 11: IF +Q10 GT +51.0100 GOTO LBL 1001"); });  // wrong direction
  EXPECT_TRUE(test::hasProblem(ps, fmt::format("{}: TCH PROBE 0 is not followed", g + 1)));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g + 1] = at(g + 1, "TCH PROBE 0.1 X+58.0000 Y-335.0000 Z+150.0000"); }),
                               fmt::format("{}: Y = -335.0000 mm is outside the stroke", g + 2)));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g - 1] = at(g - 1, "L X+58.0000 Y-235 Z+150.0000 R0 F2000"); }),
                               "Y-235 needs an explicit sign and a decimal point"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[5] = "; no block number"; }), "6: line does not start with a block number"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[5] = "7 ; wrong number"; }), "block number 7 where 5 was expected"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[5] = at(5, "; " + std::string(80, 'x')); }), "more than 80"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.back() = at(v.size() - 1, "END PGM OTHER MM"); }), "END PGM"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[5] = at(5, "L A+0.0000 M128"); }), "TCP or a tilted plane"));
}

TEST(HeidenhainOffsets, KinematicsAndPresetValuesToEnter) {
  const ProbePlan plan = test::acPlan();
  const std::string text = hh().writeOffsets(test::table4Request(plan));
  EXPECT_NE(text.find("; kinematics, transformation to the A axis: X +0.0146 Y +0.0232 Z +0.0277\n"), std::string::npos)
      << text;
  EXPECT_NE(text.find("; kinematics, transformation A axis to C axis: X +0.0000 Y +0.0039 Z +0.0000\n"),
            std::string::npos);
  EXPECT_NE(text.find("; preset table, A axis of the active preset: -0.0005 deg\n"), std::string::npos);
  const auto ls = test::lines(text);
  EXPECT_EQ(ls[0], "0 BEGIN PGM ROTACAL_KIN MM");
  for (size_t i = 0; i < ls.size(); ++i) {
    EXPECT_EQ(ls[i].rfind(std::to_string(i) + " ", 0), 0u) << ls[i];
    EXPECT_LE(ls[i].size(), 80u) << ls[i];
  }
  test::expectPlausibilityLimit(hh(), plan, "X +0.7000 Y +0.0232");
}

}  // namespace
}  // namespace rotacal
