// The contributors file (core/contributors.hpp): 000 Table 5's values in their units, and precise
// errors for bad input.
#include <gtest/gtest.h>

#include "core/contributors.hpp"
#include "core/errors.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

TEST(Contributors, Table5FileHoldsThePapersValuesInInternalUnits) {
  const ContributorSet cs = loadContributors(test::sourcePath("examples/contributors/table5.json"));
  // Every id of 000 Table 5 plus form_error (the catalog's rtest_* ids are the R-test's, its
  // laser_* ids the laser's of 004).
  size_t touch_ids = 0;
  for (const auto& c : contributorCatalog())
    touch_ids += c.id.substr(0, 6) == "rtest_" || c.id.substr(0, 6) == "laser_" ? 0 : 1;
  EXPECT_EQ(cs.items.size(), touch_ids);
  EXPECT_EQ(touch_ids, 21u);
  EXPECT_DOUBLE_EQ(cs.find("probe_repeatability")->u[0], 0.7e-3);            // 0.7 um -> mm
  EXPECT_DOUBLE_EQ(cs.find("E_yy_lin")->u[0], 1e-5);                          // 1 um/100mm (000: "1 um/mm")
  EXPECT_DOUBLE_EQ(cs.find("E_zx_rand")->u[0], 2e-3);                         // 2 um
  EXPECT_DOUBLE_EQ(cs.find("S_yz")->u[0], 3e-5);                              // 3 um/100mm
  EXPECT_EQ(cs.find("setup_position")->u, Eigen::Vector3d(0.01, 0.01, 0.12));  // 10, 10, 120 um
  EXPECT_DOUBLE_EQ(cs.find("setup_orientation")->u[2], 1e-4);                 // 10 um/100mm
  EXPECT_DOUBLE_EQ(cs.find("form_error")->u[1], 2e-3);                        // 2 mrad
  EXPECT_DOUBLE_EQ(cs.node_spacing_min_mm, 20.0);
  EXPECT_DOUBLE_EQ(cs.node_spacing_max_mm, 50.0);
  const LinearAxisModel m = cs.linearAxisModel();
  EXPECT_DOUBLE_EQ(m.u_rand(1, 0), 2e-3);  // E_yx_rand: direction Y of the X axis
  EXPECT_DOUBLE_EQ(m.u_S_xy, 3e-5);
  ASSERT_TRUE(cs.reference.has_value());
  EXPECT_DOUBLE_EQ(cs.reference->combined.at("b_AY"), 2.0);
  EXPECT_DOUBLE_EQ(cs.reference->contributors.at("S_yz").at("dy_AY"), 5.5);
}

TEST(Contributors, UnitsConvert) {
  double f = 0;
  ASSERT_TRUE(unitFactor(Quantity::Ratio, "um/m", &f));
  EXPECT_DOUBLE_EQ(f, 1e-6);
  ASSERT_TRUE(unitFactor(Quantity::Ratio, "um/100mm", &f));
  EXPECT_DOUBLE_EQ(f, 1e-5);
  ASSERT_TRUE(unitFactor(Quantity::Ratio, "mdeg", &f));
  EXPECT_NEAR(f, 1.745329252e-5, 1e-14);
  EXPECT_FALSE(unitFactor(Quantity::Length, "um/m", &f));
  EXPECT_FALSE(unitFactor(Quantity::Ratio, "um", &f));
}

void expectInputError(const std::string& text, int line, const std::string& fragment) {
  try {
    contributorsFromJson(parseJsonText(text, "c.json"));
    FAIL() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "c.json");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Contributors, BadInputNamesTheFileLineAndProblem) {
  expectInputError(R"({"format": "x"})", 1, "not a contributors file");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"probe_noise\": {\"u\": 1, \"unit\": \"um\"}}}",
                   3, "unknown contributor 'probe_noise'");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"S_xy\": {\"u\": 3, \"unit\": \"um\"}}}", 3,
                   "unit 'um' is not one of");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"E_xx_rand\": {\"u\": -2, \"unit\": \"um\"}}}",
                   3, ">= 0");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"node_spacing_mm\": [50, 20],\n \"contributors\": {\"S_xy\": {\"u\": 3, \"unit\": \"urad\"}}}",
                   2, "min <= max");
  expectInputError("{\"format\": \"rotacal-contributors/1\",\n \"contributors\": {\n  \"form_error\": {\"offset\": {\"u\": 1, \"unit\": \"um\"}}}}",
                   3, "'form_error' needs");
}

}  // namespace
}  // namespace rotacal
