// The Siemens Sinumerik dialect: MEAS=1 with STOPRE, $AA_MW reads and the $AC_MEA[1] +
// distance check; WRITE/SPRINT results round-trip and recover injected errors; a point the
// program marked as not triggered is rejected; the checker catches planted faults; the
// toolcarrier offsets program adds the identified values.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "test_util.hpp"
#include "dialect_battery.hpp"

namespace rotacal {
namespace {

const Dialect& sm() { return dialectByName("siemens"); }


TEST(SiemensProgram, ProbeBlockAndCheck) {
  const test::WrittenProgram p("siemens", "^MEAS=1");
  EXPECT_EQ(p.ls[0], "; %_N_ROTACAL_TOUCH154_MPF");
  EXPECT_EQ(p.ls[p.g], "MEAS=1 G1 X51.0000 Y-235.0000 Z150.0000 F100.0");
  EXPECT_EQ(p.ls[p.g + 1], "STOPRE");
  EXPECT_EQ(p.ls[p.g + 2], "R90=$AA_MW[X]");
  EXPECT_EQ(p.ls[p.g + 5], "R93=R90-51.0000");
  EXPECT_EQ(p.ls[p.g + 6], "R94=R91+235.0000");
  EXPECT_EQ(p.ls[p.g + 8], "IF ($AC_MEA[1]==0) OR (R93*R93+R94*R94+R95*R95<0.0001) GOTOF NOHIT1");
  EXPECT_EQ(p.ls[p.g + 9], "TXT=SPRINT(\"P1 X%10.4F Y%10.4F Z%10.4F\",R90,R91,R92)");
  EXPECT_EQ(p.ls[p.g + 10], "WRITE(ERR,\"ROTACAL_TOUCH154\",TXT)");
  const size_t nohit = test::lineStarting(p.ls, "NOHIT1:");
  EXPECT_EQ(p.ls[nohit + 1], "TXT=\"NOT-TRIGGERED P1\"");
  EXPECT_EQ(p.ls[nohit + 3], "MSG(\"ROTACAL: POINT 1 NOT TRIGGERED\")");
  EXPECT_EQ(p.ls[nohit + 4], "M0");
  EXPECT_EQ(p.ls.back(), "M30");
}


class SiemensCheck : public test::PlantedFaults {
 protected:
  SiemensCheck() : PlantedFaults("siemens", "^MEAS=1") {}
};

TEST_F(SiemensCheck, CatchesPlantedFaults) {
  auto ps = with([&](auto& v) { v.erase(v.begin() + static_cast<long>(g) + 1); });  // STOPRE
  ASSERT_EQ(ps.size(), 1u);
  EXPECT_EQ(ps[0].rfind(fmt::format("{}: MEAS=1 is not followed by STOPRE", g + 1), 0), 0u) << ps[0];
  ps = with([&](auto& v) { v[test::lineStarting(v, "NOHIT1:") + 4] = "M1"; });  // no stop in the branch
  EXPECT_TRUE(test::hasProblem(ps, fmt::format("{}: MEAS=1 is not followed", g + 1)));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "MEAS=1 G1 X51.0000 Y-335.0000 Z150.0000 F100.0"; }),
                               fmt::format("{}: Y = -335.0000 mm is outside the stroke", g + 1)));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "MEAS=1 G1 X51 Y-235.0000 Z150.0000 F100.0"; }),
                               "X51 has no decimal point"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[3] = "; " + std::string(90, 'X'); }), "more than 80"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.insert(v.begin() + static_cast<long>(g), "DEF INT LATE"); }),
                               "DEF after the first statement"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[test::lineStarting(v, "NOHIT1:")] = "NOHITX:"; }),
                               "undefined label 'NOHIT1'"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g + 9] = "TXT=SPRINT(\"P1 X%10.4F\",R90"; }), "unbalanced"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.pop_back(); }), "does not end with M30"));
}

TEST(SiemensOffsets, ToolcarrierFineOffsetsAndAxisVectors) {
  const ProbePlan plan = test::acPlan();
  const std::string text = sm().writeOffsets(test::table4Request(plan));
  EXPECT_NE(text.find("\n$TC_CARR44[1]=$TC_CARR44[1]+0.0146\n$TC_CARR45[1]=$TC_CARR45[1]+0.0232\n"
                      "$TC_CARR46[1]=$TC_CARR46[1]+0.0277\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\n$TC_CARR56[1]=$TC_CARR56[1]+0.0039\n"), std::string::npos) << "dy_CA = 3.9 um";
  // v1 = A axis direction (1, c_AY, -b_AY) normalized; c_AY = -0.5 mdeg = -8.727e-6 rad.
  EXPECT_NE(text.find("\n$TC_CARR8[1]=-0.000009\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\n$TC_CARR24[1]=$TC_CARR24[1]-0.0005\n"), std::string::npos);
  for (const auto& l : test::lines(text)) EXPECT_LE(l.size(), 80u) << l;
  test::expectPlausibilityLimit(sm(), plan, "$TC_CARR44[1]=$TC_CARR44[1]+0.7000");
}

}  // namespace
}  // namespace rotacal
