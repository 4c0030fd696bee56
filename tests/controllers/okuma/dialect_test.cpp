// The Okuma OSP-P300 dialect: G31 with VSKPX-Z, the distance check and a user alarm; results
// written by PUT/WRITE round-trip and recover injected errors; the parser rejects what the
// program did not write; the checker catches planted faults; the work offset shift is written.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "test_util.hpp"
#include "dialect_battery.hpp"

namespace rotacal {
namespace {

const Dialect& ok() { return dialectByName("okuma"); }

TEST(OkumaProgram, ProbeBlockCheckAndOutput) {
  const test::WrittenProgram p("okuma", "^G31");
  EXPECT_EQ(p.ls[0], "O7154 (ROTACAL)");
  EXPECT_NE(p.text.find("\nFWRITC MD1:ROTACAL-TOUCH154.TXT;A\n"
                        "PUT 'ROTACAL-RESULTS DIALECT OKUMA CYCLE TOUCH154 POINTS 154 UNIT MM'\nWRITE C\n"),
            std::string::npos);
  EXPECT_EQ(p.ls[p.g], "G31 X51.0000 Y-235.0000 Z150.0000 F100.0");
  EXPECT_EQ(p.ls[p.g + 1], "VC1=VSKPX");
  EXPECT_EQ(p.ls[p.g + 4], "VC4=VC1-51.0000");
  EXPECT_EQ(p.ls[p.g + 5], "VC5=VC2+235.0000");
  EXPECT_EQ(p.ls[p.g + 7], "IF [VC4*VC4+VC5*VC5+VC6*VC6 GT 0.0001] N1001");
  EXPECT_EQ(p.ls[p.g + 8], "PUT 'NOT-TRIGGERED P1'");
  EXPECT_EQ(p.ls[p.g + 11], "VUACM[1]='PT1 NO TRIGGER'");
  EXPECT_EQ(p.ls[p.g + 12], "VDOUT[992]=1001");
  EXPECT_EQ(p.ls[p.g + 13], "N1001 PUT 'P1 X'");
  EXPECT_EQ(p.ls[p.g + 14], "PUT VC1,4");
  EXPECT_EQ(p.ls[p.g + 19], "WRITE C");
  EXPECT_EQ(p.ls.back(), "M02");
}


class OkumaCheck : public test::PlantedFaults {
 protected:
  OkumaCheck() : PlantedFaults("okuma", "^G31") {}
};

TEST_F(OkumaCheck, CatchesPlantedFaults) {
  auto ps = with([&](auto& v) { v.erase(v.begin() + static_cast<long>(g) + 12); });  // VDOUT alarm
  ASSERT_EQ(ps.size(), 1u);
  EXPECT_EQ(ps[0].rfind(fmt::format("{}: G31 is not followed by the no-trigger check", g + 1), 0), 0u) << ps[0];
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "G31 X51.0000 Y-235.0000 Z150 F100.0"; }), "not of the generated form"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "G31 X51.0000 Y-235.0000 Z450.0000 F100.0"; }),
                               fmt::format("{}: Z = 450.0000 mm is outside the stroke", g + 1)));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g + 13] = "N1002 PUT 'P1 X'"; }), "IF without a defined label"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.erase(v.end() - 2); }), "FWRITC without CLOSE C"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[3] = "(" + std::string(90, 'X') + ")"; }), "more than 80"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[3] = "(OPEN"; }), "comment not closed"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.pop_back(); }), "does not end with M02"));
}

TEST(OkumaOffsets, WorkOffsetShift) {
  const ProbePlan plan = test::acPlan();
  const std::string text = ok().writeOffsets(test::table4Request(plan));
  EXPECT_NE(text.find("\nVZOFX[1]=VZOFX[1]+0.0146\nVZOFY[1]=VZOFY[1]+0.0232\nVZOFZ[1]=VZOFZ[1]+0.0277\n"
                      "VZOFA[1]=VZOFA[1]-0.0005\n"),
            std::string::npos)
      << text;
  for (const auto& l : test::lines(text)) EXPECT_LE(l.size(), 80u) << l;
  test::expectPlausibilityLimit(ok(), plan, "VZOFX[1]=VZOFX[1]+0.7000");
}

}  // namespace
}  // namespace rotacal
