// The Siemens Sinumerik dialect: MEAS=1 with STOPRE, $AA_MW reads and the $AC_MEA[1] +
// distance check; WRITE/SPRINT results round-trip and recover injected errors; a point the
// program marked as not triggered is rejected; the checker catches planted faults; the
// toolcarrier offsets program adds the identified values.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "test_util.hpp"
#include "dialect_battery.hpp"
#include "controllers/motion_reader.hpp"

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

// A program a user brings, in the language's own words: the verifier reads its settings as
// absent and X=-10 as X-10, so it follows the same motions as the program written plainly; a
// frame change, a cycle's call and a name it does not know are refused at their line, by name.
TEST(SinumerikNames, AUsersProgramReadsAsItsPlainTwin) {
  const std::string own =
      "N10 G17 G90 G54 G71\nN15 TRAFOOF\nN16 SOFT FFWON\nN20 G0 X0 Y0 Z100 A0 C0\nN40 G1 Z50 F2000\n"
      "N50 X=25.5 Y=-10 A=-15 C=.5 SOFT ; cut\nN55 CYCLE832(0.01,1,1)\nMSG(\"ROT TRAORI\")\nN60 G0 Z100\nN80 M30\n";
  const std::string plain = "N10 G17 G90 G54 G71\n\n\nN20 G0 X0 Y0 Z100 A0 C0\nN40 G1 Z50 F2000\n"
                            "N50 X25.5 Y-10 A-15 C.5\n\n\nN60 G0 Z100\nN80 M30\n";
  const auto a = ctl::readMotions("siemens", own), b = ctl::readMotions("siemens", plain);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].kind, b[i].kind) << i;
    EXPECT_EQ(a[i].line, b[i].line) << i;
    EXPECT_EQ(a[i].words, b[i].words) << i;
    EXPECT_NE(a[i].kind, nc::Motion::Kind::Unreadable) << a[i].problem;
  }
  const auto problem = [](const std::string& block) {
    for (const auto& m : ctl::readMotions("siemens", "N10 G90 G0 X0 Y0 Z100\n" + block + "\nM30\n"))
      if (m.kind == nc::Motion::Kind::Unreadable) return fmt::format("{}: {}", m.line, m.problem);
    return std::string("followed");
  };
  EXPECT_EQ(problem("N20 TRAORI"), "2: TRAORI (five-axis transformation: tool-centre-point control) is not followed by the verifier");
  EXPECT_EQ(problem("TRAORI(1)").rfind("2: TRAORI (", 0), 0u);
  EXPECT_EQ(problem("TCARR=1").rfind("2: TCARR (orientable tool carrier)", 0), 0u);  // an assignment, not a statement
  EXPECT_EQ(problem("CYCLE800(1,\"TC1\",200000,57,0,0,0,30,0,0,0,0,0,-1,100,1)").rfind("2: CYCLE800 (swivel", 0), 0u);
  EXPECT_EQ(problem("N30 ROT Z45").rfind("2: ROT (programmable frame rotation)", 0), 0u);
  EXPECT_EQ(problem("SUPA G0 Z0").rfind("2: SUPA (", 0), 0u);
  EXPECT_EQ(problem("CYCLE81(100,0,2,-10)").rfind("2: CYCLE81: a name rotacal does not know", 0), 0u);
  EXPECT_EQ(problem("N30 PART_SUB").rfind("2: PART_SUB: a name rotacal does not know", 0), 0u);
  EXPECT_EQ(problem("G0 A=DC(90)").rfind("2: A=DC is an expression or a parameter", 0), 0u);
  EXPECT_EQ(problem("G1 X=R1+5 F100").rfind("2: X=R1+5 is an expression or a parameter", 0), 0u);
  // Names that only contain a keyword, and keywords inside strings, are not frame changes.
  EXPECT_EQ(problem("DEF REAL ROT_ANGLE"), "followed");
  EXPECT_EQ(problem("TXT=\"NO TRAORI, NO CYCLE800\""), "followed");
  EXPECT_EQ(problem("R1=5"), "followed");
  // A block of any length is read without recursion (std::regex overflowed the stack on 100 kB):
  // the verifier names the block's length itself.
  EXPECT_EQ(problem("G1 X=" + std::string(100000, 'A')).rfind("2: X=AAAA", 0), 0u);
  EXPECT_EQ(problem("G1 X1.0 F100.0 " + std::string(100000, 'Q')).rfind("2: QQQQ", 0), 0u);
}

}  // namespace
}  // namespace rotacal
