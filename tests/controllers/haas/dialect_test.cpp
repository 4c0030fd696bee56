// The Haas NGC dialect: the Macro B program with O + 5 digits, retained #10700.., G103 P1 and
// [80] time fields; its results round-trip and recover injected errors; the checker passes the
// generated program and catches Haas-specific faults; the offsets give MRZP values to enter.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "test_util.hpp"
#include "dialect_battery.hpp"

namespace rotacal {
namespace {

const Dialect& hs() { return dialectByName("haas"); }

TEST(HaasResults, HeaderClockAndPointLines) {
  const ProbePlan plan = test::acPlan();
  MeasurementRun run = test::displacedRun(plan);
  for (auto& p : run.points) p.t_s += 750000000.0;  // 2023-10-07 13:20:00 + plan time + 0.25 s
  const auto ls = test::lines(hs().writeResults(plan, run));
  // The header holds the first trigger's second (13:20:00 + plan t_s + 0.25 s, < 60 s); T = ms
  // since that second, right-aligned in 8 characters ([80]).
  const double first = plan.points[0].t_s + 0.25;
  ASSERT_LT(first, 60.0);
  EXPECT_EQ(ls[1], fmt::format("DATE 20231007 TIME {}", 132000 + static_cast<long>(std::floor(first))));
  EXPECT_EQ(ls[2].substr(ls[2].find('T')),
            fmt::format("T{:>8}", static_cast<long>(std::round((first - std::floor(first)) * 1000))));
  EXPECT_EQ(ls.back(), "END");
}


TEST(HaasProgram, HaasFrameAndStorage) {
  const test::WrittenProgram p("haas", "^G31");
  EXPECT_EQ(p.ls[1], "O07154(ROTACAL TOUCH154)");
  EXPECT_NE(p.text.find("\nG54\nG103 P1\nPOPEN\n"), std::string::npos);
  EXPECT_NE(p.text.find("\nPCLOS\nG103\nM30\n%\n"), std::string::npos);
  EXPECT_EQ(p.ls[p.g + 7], "#10700=#5061");
  EXPECT_EQ(p.ls[p.g + 10], "#10703=#3001");
  EXPECT_NE(p.text.find("\nDPRNT[P1*X#10700[44]*Y#10701[44]*Z#10702[44]*T#10703[80]]\n"), std::string::npos);
  EXPECT_EQ(p.text.find("#10980"), std::string::npos) << "retained globals end at #10999";
}


class HaasCheck : public test::PlantedFaults {
 protected:
  HaasCheck() : PlantedFaults("haas", "^G31") {}
};

TEST_F(HaasCheck, CatchesHaasFaults) {
  EXPECT_TRUE(test::hasProblem(with([](auto& v) { v[1] = "O7154(ROTACAL TOUCH154)"; }), "O and 5 digits"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v.erase(v.begin() + static_cast<long>(test::lineStarting(v, "G103 P1"))); }),
                               "DPRNT before G103 P1"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[test::lineStarting(v, "DPRNT[P1")] = "DPRNT[P1*X#10700[54]]"; }),
                               "a + b > 8"));
  const auto ps = with([&](auto& v) { v.erase(v.begin() + static_cast<long>(g) + 5); });
  ASSERT_EQ(ps.size(), 1u);
  EXPECT_EQ(ps[0].rfind(fmt::format("{}: G31 is not followed by the no-trigger check", g + 1), 0), 0u) << ps[0];
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "G31 X51.0000 Y-235.0000 Z150 F100.0"; }), "Z150 has no decimal point"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g] = "G31 X51.0000 Y-235.0000 Z-150.0000 F100.0"; }),
                               "Z = -150.0000 mm is outside the stroke"));
  EXPECT_TRUE(test::hasProblem(with([&](auto& v) { v[g - 1] = "G93 G01 X51.0000 F10.0"; }), "G93"));
}

TEST(HaasOffsets, MrzpValuesToEnterAndTheZeroShift) {
  const ProbePlan plan = test::acPlan();
  const std::string text = hs().writeOffsets(test::table4Request(plan));
  // Table 4: dx_AY 14.6 um, dy_AY 23.2 um, dz_AY 27.7 um -> settings 255-257 + 0.0146/0.0232/0.0277 mm.
  EXPECT_NE(text.find("\n#10121=#20255+0.0146\n#10122=#20256+0.0232\n#10123=#20257+0.0277\n"), std::string::npos) << text;
  EXPECT_NE(text.find("#3006=1(ENTER 10121-10123 IN SETTINGS 255-257)"), std::string::npos);
  EXPECT_NE(text.find("\nG91 G10 L2 P1 A-0.0005\n"), std::string::npos) << "a_AY = -0.5 mdeg";
  EXPECT_NE(text.find("CANNOT BE SET FROM A MACRO"), std::string::npos);
  for (const auto& l : test::lines(text)) EXPECT_LE(l.size(), 80u) << l;
  test::expectPlausibilityLimit(hs(), plan, "#10121=#20255+0.7000");
}

}  // namespace
}  // namespace rotacal
