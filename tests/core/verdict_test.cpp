// The verdict (core/verdict.hpp) against ISO 14253-1's zones written out by hand: a value within
// its own U is not significant; with a tolerance T, conformance is proven where |v| + U <= T,
// non-conformance where |v| - U > T, and the measurement cannot decide between.
#include <gtest/gtest.h>

#include "core/verdict.hpp"

namespace rotacal {
namespace {

TEST(Verdict, DecidesByTheZonesOfIso14253) {
  // U = 2: |v| <= 2 not significant whatever T
  EXPECT_EQ(decide(1.9, 2.0, 10.0), ParameterVerdict::NotSignificant);
  EXPECT_EQ(decide(-2.0, 2.0, std::nullopt), ParameterVerdict::NotSignificant);
  EXPECT_EQ(decide(2.1, 2.0, std::nullopt), ParameterVerdict::Significant);
  // T = 10: conforms up to 8, does not conform beyond 12, undecided between
  EXPECT_EQ(decide(8.0, 2.0, 10.0), ParameterVerdict::WithinTolerance);
  EXPECT_EQ(decide(-8.01, 2.0, 10.0), ParameterVerdict::Undecided);
  EXPECT_EQ(decide(12.0, 2.0, 10.0), ParameterVerdict::Undecided);
  EXPECT_EQ(decide(-12.01, 2.0, 10.0), ParameterVerdict::Adjust);
}

TEST(Verdict, ReportBlockJudgesEachParameterInItsOwnUnit) {
  const Json errs = {{"dx_AY", {{"value", 14.6}, {"U", 4.5}, {"unit", "um"}}},
                     {"a_AY", {{"value", -0.5}, {"U", 0.65}, {"unit", "mdeg"}}},
                     {"b_AY", {{"value", 3.0}, {"U", 0.5}, {"unit", "mdeg"}}},
                     {"no_u", {{"value", 1.0}, {"unit", "um"}}}};
  LocationTolerance t;
  t.length_um = 5.0;  // no angle tolerance
  const Json v = verdictJson(errs, t);
  ASSERT_TRUE(v.is_object());
  EXPECT_EQ(v["parameters"]["dx_AY"]["verdict"], "adjust");  // 14.6 - 4.5 > 5
  EXPECT_EQ(v["parameters"]["a_AY"]["verdict"], "not significant: leave as is");
  EXPECT_EQ(v["parameters"]["b_AY"]["verdict"], "significant (no tolerance given)");
  EXPECT_FALSE(v["parameters"].contains("no_u"));  // without U nothing is judged
  EXPECT_NE(v["summary"].get<std::string>().find("adjust dx_AY"), std::string::npos);
  EXPECT_TRUE(verdictJson(Json::object(), t).is_null());
}

}  // namespace
}  // namespace rotacal
