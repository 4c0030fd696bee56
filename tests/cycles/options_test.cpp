// The one rule of a cycle's options (cycles/options.hpp): each key reads into its field, values
// are checked by their reader, and an unknown key is refused with every key of the table.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "cycles/options.hpp"

namespace rotacal {
namespace {

struct Fields {
  double r = 0.0;
  std::vector<double> list;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  int n = 0;
  std::string name;
};

OptionTable tableOf(Fields& f) {
  OptionTable t("demo");
  t.number("radius_mm", &f.r).list("tilt_list", &f.list).vec3("center_w_mm", &f.c).count("repeats", &f.n, 2, 9);
  t.text("label", &f.name);
  return t;
}

std::string refusal(const CycleOptions& o) {
  Fields f;
  try {
    tableOf(f).read(o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(OptionTable, ReadsEachKeyIntoItsField) {
  Fields f;
  tableOf(f).read({{"radius_mm", "12.5"}, {"tilt_list", "-30,0,30"}, {"center_w_mm", "1,-2,3.5"}, {"repeats", "9"},
                   {"label", "left"}});
  EXPECT_EQ(f.r, 12.5);
  EXPECT_EQ(f.list, (std::vector<double>{-30.0, 0.0, 30.0}));
  EXPECT_EQ(f.c, Eigen::Vector3d(1.0, -2.0, 3.5));
  EXPECT_EQ(f.n, 9);
  EXPECT_EQ(f.name, "left");
  Fields g;
  tableOf(g).read({});
  EXPECT_EQ(g.r, 0.0);  // an option not given keeps the cycle's default
}

TEST(OptionTable, RefusesUnknownKeysAndBadValuesNamingThem) {
  EXPECT_EQ(refusal({{"radius_mm", "1"}, {"radiuss_mm", "1"}}),
            "unknown option 'radiuss_mm' for cycle demo (known: radius_mm, tilt_list, center_w_mm, repeats, label)");
  EXPECT_NE(refusal({{"repeats", "10"}}).find("option repeats must be a whole number from 2 to 9, not '10'"), std::string::npos);
  EXPECT_NE(refusal({{"repeats", "2.5"}}).find("repeats"), std::string::npos);
  EXPECT_NE(refusal({{"center_w_mm", "1,2"}}).find("option center_w_mm: expected x,y,z"), std::string::npos);
  EXPECT_NE(refusal({{"radius_mm", "wide"}}).find("radius_mm"), std::string::npos);
  requireKnownOptions("demo", {{"a", "1"}}, {"a", "b"});
  EXPECT_THROW(requireKnownOptions("demo", {{"c", "1"}}, {"a", "b"}), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
