// The HTML report's drawing, checked by computing where things must land: tick choice, the
// mapping of data to pixels (closed form from the plot's margins), refusal of malformed figures,
// and that each report kind holds its sections and nothing that reaches the network.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <regex>
#include <string>

#include "core/json_io.hpp"
#include "core/uncertainty_budget.hpp"
#include "report/figure.hpp"
#include "report/html_report.hpp"
#include "report/svg.hpp"
#include "test_util.hpp"

namespace rotacal::report {
namespace {

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

TEST(NiceTicks, CoverTheRangeWithRoundSteps) {
  const auto t = niceTicks(-3.7, 12.2, 5);
  ASSERT_GE(t.size(), 3u);
  const double step = t[1] - t[0];
  EXPECT_DOUBLE_EQ(step, 5.0);  // range 15.9 / 5 = 3.18 -> next of 1, 2, 2.5, 5: 5
  EXPECT_LE(t.front(), 0.0);
  EXPECT_GE(t.back(), 10.0);
  for (size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], step, 1e-12);
}

TEST(SvgPlot, MapsDataToPixelsLinearly) {
  // Ticks of [0, 10] are 0..10 exactly, so x = 0 lands on the left edge of the plot area
  // (64 px) and x = 10 on the right (width - 16); y = 0 on the bottom, y = 10 on the top (28 px).
  Figure f{"t", "t", "", {"x", "mm", {}}, {"y", "um", {}}, {{"s", "points", {0, 10}, {0, 10}, {}}}, {}};
  const std::string svg = svgPlot(f, 400, 300);
  const int legend_h = 18, bottom = 44 + legend_h;
  const double ph = 300 - 28 - bottom;
  EXPECT_NE(svg.find("<circle cx=\"64.0\" cy=\"" + fmt::format("{:.1f}", 28 + ph) + "\""), std::string::npos) << svg;
  EXPECT_NE(svg.find("<circle cx=\"384.0\" cy=\"28.0\""), std::string::npos) << svg;
  EXPECT_NE(svg.find(">x (mm)<"), std::string::npos);
  EXPECT_NE(svg.find(">y (um)<"), std::string::npos);
}

TEST(Figures, MalformedFiguresAreRefusedWithTheirName) {
  Json j = Json::parse(R"({"id": "bad_one", "x": {"label": "C", "unit": "deg"}, "y": {"label": "e", "unit": "um"},
                          "series": [{"name": "s", "x": [1, 2, 3], "y": [1, 2]}]})");
  try {
    figureFromJson(j);
    FAIL() << "accepted x and y of different lengths";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bad_one"), std::string::npos) << e.what();
  }
  j["series"][0]["y"] = {1, 2, 3};
  EXPECT_NO_THROW(figureFromJson(j));
  j["y"].erase("unit");
  EXPECT_THROW(figureFromJson(j), std::invalid_argument);  // every axis carries its unit
  j["y"]["unit"] = "um";
  j["series"][0]["style"] = "bars";
  EXPECT_THROW(figureFromJson(j), std::invalid_argument);
}

TEST(Figures, RoundTripThroughJson) {
  const JsonDoc doc = readJsonFile(test::sourcePath("tests/report/fixtures/figures_fixture.json"));
  for (const auto& fj : doc.value["figures"]) {
    const Figure f = figureFromJson(fj);
    EXPECT_EQ(figureToJson(f), fj) << f.id;
  }
}

TEST(HtmlReport, FixtureDrawsEveryFigureSeriesAndBand) {
  const JsonDoc doc = readJsonFile(test::sourcePath("tests/report/fixtures/figures_fixture.json"));
  const std::string html = reportHtml(doc.value);
  EXPECT_EQ(count(html, "<svg"), 3);
  EXPECT_EQ(count(html, "class=\"band\""), 1);
  EXPECT_EQ(count(html, "<polyline class=\"series\""), 2);  // the two line series
  EXPECT_EQ(count(html, "class=\"errorbar\""), 12 + 9);    // one per point with u
  // Self-contained: nothing fetched.
  EXPECT_EQ(html.find("src="), std::string::npos);
  EXPECT_EQ(html.find("href="), std::string::npos);
  EXPECT_EQ(html.find("@import"), std::string::npos);
}

TEST(HtmlReport, TextIsEscaped) {
  Json doc = {{"format", "x"},
              {"figures", Json::array({{{"id", "a"}, {"title", "<script>alert(1)</script>"}, {"x", {{"label", "x"}, {"unit", "mm"}}},
                                        {"y", {{"label", "y"}, {"unit", "um"}}},
                                        {"series", Json::array({{{"name", "s"}, {"x", {1}}, {"y", {1}}}})}}})}};
  const std::string html = reportHtml(doc);
  EXPECT_EQ(html.find("<script>alert"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)"), std::string::npos);
}

// What the data were screened against reaches the page: the screen's line, its reach (where it
// sees no gross error) and the data against the declaration, escaped, in the machine table.
TEST(HtmlReport, ShowsWhatTheScreenLeftOutAndWhereItSeesNothing) {
  Json doc = {{"format", "rotacal-report/1"},
              {"cycle", "tooltip"},
              {"outliers", {{"summary", "reading screen: no value beyond 3.64 sigma"},
                            {"reach", {{"summary", "the screen catches ... from 35.2 um (median; 150.2 mm at run 1 A = 90 deg (B0) dz) <x>"},
                                       {"unseen", 0}}}}},
              {"declared_noise", {{"summary", "chi2 20.1 on 17 dof, p 0.27"}}}};
  const std::string html = reportHtml(doc);
  const size_t screen = html.find("reading screen: no value beyond 3.64 sigma"),
               reach = html.find("150.2 mm at run 1 A = 90 deg (B0) dz) &lt;x&gt;"), declared = html.find("chi2 20.1 on 17 dof");
  ASSERT_NE(screen, std::string::npos);
  ASSERT_NE(reach, std::string::npos);
  ASSERT_NE(declared, std::string::npos);
  EXPECT_LT(screen, reach);
  EXPECT_EQ(count(html, "what the screen can see"), 1);
  // Without a reach (a screen that reads no declared covariance) no empty row.
  doc["outliers"].erase("reach");
  EXPECT_EQ(count(reportHtml(doc), "what the screen can see"), 0);
}

TEST(HtmlReport, ShowsTheUncertaintyBudgetAndTheCorrelations) {
  // A REPORT.json with the block core/uncertainty_budget writes: the table repeats its figures,
  // and the correlation matrix has one row per parameter.
  UncertaintyBudget b;
  b.names = {"dx_AY", "b_AY"};
  b.units = {"um", "mdeg"};
  b.cov_a = Eigen::Vector2d(0.25, 0.01).asDiagonal();
  b.cov_b = Eigen::Matrix2d::Zero();
  b.cov_b << 16.0, -1.6, -1.6, 0.25;  // r_B = -0.8
  b.type_a_source = "the <data>";
  b.type_b_source = "S_xz & friends";
  b.terms = {{"data", Eigen::Vector2d(0.5, 0.1)}, {"S_xz", Eigen::Vector2d(4.0, 0.5)}};
  Json doc = {{"format", "rotacal-report/1"},
              {"cycle", "touch154"},
              {"location_errors", {{"dx_AY", {{"value", 14.6}, {"unit", "um"}, {"u", 0.5}, {"iso", "X0A"}}},
                                   {"b_AY", {{"value", -0.1}, {"unit", "mdeg"}, {"u", 0.1}, {"iso", "B0A"}}}}},
              {"uncertainty", budgetJson(b)}};
  const std::string html = reportHtml(doc);
  const Eigen::VectorXd U = b.expanded();
  EXPECT_NE(html.find("data-table=\"uncertainty\""), std::string::npos);
  EXPECT_NE(html.find(fmt::format("{:.3f}", U[0])), std::string::npos);  // 8.062
  EXPECT_NE(html.find(fmt::format("{:.3f}", U[1])), std::string::npos);
  EXPECT_NE(html.find("S_xz <span class=\"n\">4.00</span>"), std::string::npos);
  const size_t cor = html.find("data-table=\"correlation\"");
  ASSERT_NE(cor, std::string::npos);
  const std::string matrix = html.substr(cor, html.find("</table>", cor) - cor);
  EXPECT_EQ(count(matrix, "<tr><th>"), 1 + 2);  // the header, then one row per parameter
  EXPECT_NE(matrix.find(fmt::format("{:.2f}", b.correlation()(0, 1))), std::string::npos);
  EXPECT_EQ(html.find("<data>"), std::string::npos);  // the sources are text, escaped
  EXPECT_NE(html.find("S_xz &amp; friends"), std::string::npos);
}

TEST(HtmlReport, UncertaintyRowsCarryTheirCoverageFactorAndValuesBeyondTheLocationErrors) {
  // A parameter that is not a location error (a scale) shows the value budgetJson was given, and
  // every row its own k (a Monte Carlo's k is not 2).
  UncertaintyBudget b;
  b.names = {"scale_X"};
  b.units = {"um/m"};
  b.cov_a = Eigen::MatrixXd::Constant(1, 1, 4.0);
  b.cov_b = Eigen::MatrixXd::Constant(1, 1, 5.0);
  b.coverage_factor = Eigen::VectorXd::Constant(1, 1.71);
  b.runs = 2000;
  Json doc = {{"format", "rotacal-report/1"}, {"cycle", "spaceframe"}, {"uncertainty", budgetJson(b, Eigen::VectorXd::Constant(1, -12.345))}};
  const std::string html = reportHtml(doc);
  const size_t table = html.find("data-table=\"uncertainty\"");
  ASSERT_NE(table, std::string::npos);
  const std::string rows = html.substr(table, html.find("</table>", table) - table);
  EXPECT_NE(rows.find("<span class=\"n\">-12.345</span>"), std::string::npos) << rows;
  EXPECT_NE(rows.find("<span class=\"n\">1.71</span>"), std::string::npos);
  EXPECT_NE(rows.find("<span class=\"n\">5.130</span>"), std::string::npos);  // U = 1.71 x 3
  EXPECT_NE(html.find("95.45 % coverage"), std::string::npos);
}

}  // namespace
}  // namespace rotacal::report
