// The malformed-input battery of every results parser (issue 3): for each dialect, at least ten
// distinct kinds of damaged, truncated, mixed-up or foreign files, each rejected with
// rotacal::InputError naming the exact FILE:LINE and what is wrong. The files are built from
// the dialect's own writer output (a valid file) by one edit each, so the expected line is
// known independently of the parser: it is where the edit was made.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <functional>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "controllers/text.hpp"
#include "controllers/dialect.hpp"
#include "controllers/result_checks.hpp"
#include "core/errors.hpp"
#include "ctl_test_util.hpp"

namespace rotacal {
namespace {

using test::join;
using test::lines;

/// Where point k (1-based) sits in a valid file of touch154 (0-based line index), and whether
/// the file ends with END.
struct Layout {
  size_t first = 1;   // index of point 1's line
  size_t stride = 1;  // lines per point (heidenhain: point line + time line)
  bool end = true;
  size_t at(int k) const { return first + static_cast<size_t>(k - 1) * stride; }
};

Layout layoutOf(const std::string& d) {
  if (d == "csv" || d == "linuxcnc") return {1, 1, false};
  if (d == "fanuc" || d == "haas") return {2, 1, true};  // header, DATE line
  if (d == "heidenhain") return {1, 2, true};
  return {1, 1, true};  // siemens, okuma
}

/// The point line `line` of dialect `d` with its X value text replaced by `x`.
std::string withX(const std::string& d, const std::string& line, const std::string& x) {
  if (d == "csv") {
    const size_t a = line.find(',');
    const size_t b = line.find(',', a + 1);
    return line.substr(0, a + 1) + x + line.substr(b);
  }
  if (d == "linuxcnc") {
    const size_t a = line.find(' ');
    const size_t b = line.find(' ', a + 1);
    return line.substr(0, a + 1) + x + line.substr(b);
  }
  static const std::regex field(R"(X *[^ Y]+)");
  return std::regex_replace(line, field, "X" + x, std::regex_constants::format_first_only);
}

struct Case {
  std::string kind;
  std::string text;
  int line;              // expected line of the error (1-based)
  std::string message;   // expected part of the message after "res.txt:LINE: "
};

class Malformed : public ::testing::TestWithParam<std::string> {
 protected:
  const Dialect& d() const { return dialectByName(GetParam()); }
  ProbePlan plan = test::acPlan();
  MeasurementRun run = [this] {
    MeasurementRun r = test::displacedRun(plan);
    for (auto& p : r.points) p.t_s += 7.5e8;  // a real date on the controllers' clock epoch
    return r;
  }();
  std::vector<std::string> ls = lines(d().writeResults(plan, run));
  Layout lay = layoutOf(GetParam());

  std::string edit(const std::function<void(std::vector<std::string>&)>& f) const {
    auto v = ls;
    f(v);
    return join(v);
  }
  int lineOf(int k) const { return static_cast<int>(lay.at(k)) + 1; }
  int lastLine(const std::vector<std::string>& v) const { return static_cast<int>(v.size()); }

  std::vector<Case> cases() const;
};

std::vector<Case> Malformed::cases() const {
  const std::string n = GetParam();
  const bool macro_b = n == "fanuc" || n == "haas";
  std::vector<Case> c;

  c.push_back({"empty file", "", 1, "empty results file"});
  c.push_back({"only blank lines", "\n  \n\n", 1, "empty results file"});
  c.push_back({"binary file (PNG signature)", std::string("\x89PNG\r\n\x1a\n", 8) + join(ls), 1,
               "byte 0x89 at column 1: a results file is plain ASCII text"});
  {
    // NUL is a legitimate punch feed code in DPRNT output (dropped); 0x01 is not.
    const char bad = macro_b ? '\x01' : '\0';
    auto v = ls;
    v[lay.at(5)].insert(3, 1, bad);
    c.push_back({macro_b ? "control byte inside a line" : "NUL byte inside a line", join(v), lineOf(5),
                 fmt::format("byte 0x{:02X} at column 4", macro_b ? 1 : 0)});
  }
  {
    // The results of another dialect (the operator picked the wrong --dialect).
    const std::string other = n == "csv" ? "okuma" : "csv";
    c.push_back({"another dialect's file", dialectByName(other).writeResults(plan, run), 1,
                 n == "csv" ? "expected the header 'point,x_mm,y_mm,z_mm,t_s'" : "expected the header"});
  }
  {
    auto v = ls;
    v.erase(v.begin() + static_cast<long>(lay.at(40)), v.begin() + static_cast<long>(lay.at(40) + lay.stride));
    c.push_back({"missing point", join(v), lastLine(v), "point 40 is missing"});
  }
  {
    auto v = ls;
    for (size_t s = 0; s < lay.stride; ++s) v[lay.at(41) + s] = v[lay.at(40) + s];
    c.push_back({"duplicate point", join(v), lineOf(41),
                 fmt::format("point 40 appears twice (first at line {})", lineOf(40))});
  }
  {
    auto v = ls;
    std::string& l = v[lay.at(41)];
    l.replace(l.find("41"), 2, "155");
    c.push_back({"point id out of range", join(v), lineOf(41), "point 155 is not in the plan (touch154 cycle, 154 points)"});
  }
  {
    auto v = ls;
    const std::vector<std::string> last(ls.begin() + static_cast<long>(lay.at(154)),
                                        ls.begin() + static_cast<long>(lay.at(154) + lay.stride));
    v.insert(v.begin() + static_cast<long>(lay.at(154) + lay.stride), last.begin(), last.end());
    c.push_back({"extra point (the last one twice)", join(v), lineOf(154) + static_cast<int>(lay.stride),
                 fmt::format("point 154 appears twice (first at line {})", lineOf(154))});
  }
  {
    auto v = ls;
    v[lay.at(7)] = withX(n, v[lay.at(7)], "53.5x84");
    c.push_back({"value that is not a number", join(v), lineOf(7), "'53.5x84'"});
  }
  for (const char* nonfinite : {"nan", "inf", "1e999"}) {
    auto v = ls;
    v[lay.at(8)] = withX(n, v[lay.at(8)], nonfinite);
    c.push_back({fmt::format("non-finite value ({})", nonfinite), join(v), lineOf(8),
                 fmt::format("'{}'", nonfinite)});
  }
  {
    // A decimal comma where the control prints a point (Heidenhain prints either: there, a
    // thousands separator is the wrong one).
    auto v = ls;
    if (n == "heidenhain") {
      v[lay.at(9)] = withX(n, v[lay.at(9)], "1.053,5840");
      c.push_back({"thousands separator", join(v), lineOf(9), "X '1.053,5840' of point 9 is not a number"});
    } else {
      v[lay.at(9)] = withX(n, v[lay.at(9)], "53,5840");
      const std::string what = n == "csv"        ? "expected 5 fields (point,x_mm,y_mm,z_mm,t_s), got 6"
                               : n == "linuxcnc" ? "'53,5840' (field 2 of point 9) is not a number"
                                                 : "X '53,5840' of point 9 is not a number";
      c.push_back({"decimal comma", join(v), lineOf(9), what});
    }
  }
  {
    // The file ends in the middle of point 100's line (transfer cut off).
    auto v = ls;
    v.resize(lay.at(100) + 1);
    std::string& l = v.back();
    l.resize(l.find_first_of(".,", l.find_first_of("0123456789", 2)) + 2);
    const std::string what = n == "csv"        ? "expected 5 fields"
                             : n == "linuxcnc" ? "expected 7 fields"
                                               : "point 100: expected 'Y'";
    c.push_back({"last line cut", join(v).substr(0, join(v).size() - 1), lineOf(100), what});
  }
  {
    // The file ends after point 99 (program or transfer stopped).
    auto v = ls;
    v.resize(lay.at(100));
    const std::string what = lay.end ? "point 100 is missing and there is no END line"
                                     : "point 100 is missing (the file has 99 of the plan's 154 points)";
    c.push_back({"truncated after a whole line", join(v), lastLine(v), what});
  }
  {
    // Two points' values exchanged (ids kept): each is a real trigger, of the other point.
    MeasurementRun r = run;
    std::swap(r.points[9].position_m_mm, r.points[10].position_m_mm);
    c.push_back({"values of another point (swapped)", d().writeResults(plan, r), lineOf(10), "point 10 at ("});
  }
  {
    // 8 mm past the nominal trigger: beyond the move's end (overtravel 2 mm).
    MeasurementRun r = run;
    const ProbePoint& p = *plan.findPoint(12);
    r.points[11].position_m_mm = p.trigger_m_mm + 8.0 * p.approach_m;
    c.push_back({"trigger beyond the end of its move", d().writeResults(plan, r), lineOf(12),
                 "is 8.000 mm along its probing move from the nominal trigger, outside the move [-5.000, +2.000] mm"});
  }

  // Header kinds (csv has a fixed header and no count).
  const std::string h = ls[0];
  auto header = [&](const std::string& from, const std::string& to, const std::string& kind, const std::string& what,
                    int line = 1) {
    std::string hh = h;
    const size_t at = hh.find(from);
    ASSERT_NE(at, std::string::npos) << n << ": " << from;
    hh.replace(at, from.size(), to);
    auto v = ls;
    v[0] = hh;
    c.push_back({kind, join(v), line, what});
  };
  if (n == "csv") {
    header("x_mm", "x_in", "wrong header", "expected the header 'point,x_mm,y_mm,z_mm,t_s', got 'point,x_in,y_mm,z_mm,t_s'");
    auto v = ls;
    v[lay.at(3)] = withX(n, v[lay.at(3)], "");
    c.push_back({"empty coordinate", join(v), lineOf(3), "x_mm '' of point 3 is not a number"});
    v = ls;
    v[lay.at(4)] = "-4" + v[lay.at(4)].substr(1);
    c.push_back({"point id not a positive integer", join(v), lineOf(4), "point id '-4' is not a positive integer"});
    v = ls;
    v[lay.at(6)] += ",0.5";
    c.push_back({"extra field", join(v), lineOf(6), "expected 5 fields (point,x_mm,y_mm,z_mm,t_s), got 6"});
  } else if (n == "linuxcnc") {
    header("points=154", "points=153", "wrong point count", "header says points=153 but the plan has 154 points");
    header("cycle=touch154", "cycle=rtest", "wrong cycle", "results of cycle 'rtest', the plan is 'touch154'");
    header("unit=mm", "unit=inch", "wrong unit (inch header on mm values)", "point 1 at (", lineOf(1));
    header("unit=mm", "unit=cm", "unknown unit", "unit 'cm' must be mm or inch");
    auto v = ls;
    v[lay.at(30)].back() = '0';
    c.push_back({"point marked as not triggered", join(v), lineOf(30), "point 30 was not triggered (#5070 = 0)"});
    v = ls;
    v[lay.at(31)].back() = '2';
    c.push_back({"trigger flag not 0 or 1", join(v), lineOf(31), "trigger flag '2' of point 31 must be 1"});
    // The logged A of point 32 from another pose: the coordinates alone would not show it.
    v = ls;
    auto t = ctl::tokens(v[lay.at(32)]);  // P32 x y z a c 1
    t[4] = "-37.0000";
    v[lay.at(32)] = fmt::format("{}", fmt::join(t, " "));
    c.push_back({"rotary position of another pose", join(v), lineOf(32), "point 32 was logged at A = -37.0000 deg"});
    v = ls;
    v.insert(v.begin() + 5, h);
    c.push_back({"second header (appended run)", join(v), 6, "a second header line"});
  } else {
    header("POINTS 154", "POINTS 153", "wrong point count", "header says POINTS 153 but the plan has 154 points");
    header("TOUCH154", "RTEST", "wrong cycle", "results of cycle 'RTEST', the plan is 'TOUCH154'");
    if (n == "heidenhain") {
      header("UNIT MM", "UNIT INCH", "unit other than MM", "expected the header");
    } else {
      header("UNIT MM", "UNIT INCH", "wrong unit (inch header on mm values)", "point 1 at (", lineOf(1));
      header("UNIT MM", "UNIT CM", "unknown unit", "UNIT 'CM' must be MM or INCH");
    }
    auto v = ls;
    v.push_back(v[lay.at(3)]);
    c.push_back({"text after END", join(v), lastLine(v),
                 fmt::format("text after END (line {})", lastLine(v) - 1)});
    v = ls;
    v.insert(v.begin() + static_cast<long>(lay.at(20)), h);
    c.push_back({"second header (appended run)", join(v), lineOf(20), "a second header line"});
    // Every point there, the END line not: the file was cut just before its end.
    v = ls;
    v.pop_back();
    c.push_back({"END line missing", join(v), lastLine(v), "no END line after the last point: the file is incomplete"});
    if (n != "heidenhain") {
      // Another control's tagged results under this dialect's reader.
      const std::string tag = ctl::upper(n), other = n == "fanuc" ? "HAAS" : "FANUC";
      header("DIALECT " + tag, "DIALECT " + other, "another dialect's tag",
             fmt::format("results of dialect '{}', expected {}", other, tag));
    }
    if (n == "siemens" || n == "okuma") {
      // Their point lines end after Z: anything further is not what the program wrote.
      v = ls;
      v[lay.at(2)] += " T5";
      c.push_back({"text after the last field", join(v), lineOf(2), "point 2: unexpected text"});
    }
    // A point that does not trigger: what the program writes before it stops.
    v = ls;
    v.resize(lay.at(30));
    if (macro_b) {
      // The Macro B program raises #3000 and writes nothing more: the file just ends.
      c.push_back({"point not triggered (file ends)", join(v), lastLine(v),
                   "point 30 is missing and there is no END line: the program stopped early (a point that does not "
                   "trigger raises alarm 3000)"});
    } else {
      // Heidenhain's F-PRINT pads the id as it pads the point lines' ("P%5d").
      v.push_back(n == "heidenhain" ? "NOT-TRIGGERED P   30" : "NOT-TRIGGERED P30");
      c.push_back({"point marked as not triggered", join(v), lastLine(v),
                   "point 30 was not triggered: the program stopped there"});
    }
    if (macro_b) {
      v = ls;
      v[1] = "DATE 20231332 TIME 132004";
      c.push_back({"invalid date", join(v), 2, "DATE 20231332 TIME 132004 is not a date YYYYMMDD and a time HHMMSS"});
      v = ls;
      v.erase(v.begin() + 1);
      c.push_back({"missing DATE line", join(v), 2, "expected 'DATE YYYYMMDD TIME HHMMSS' after the header"});
      v = ls;
      v[lay.at(33)] = v[lay.at(33)].substr(0, v[lay.at(33)].find('T')) + "T-5";
      c.push_back({"negative time", join(v), lineOf(33), "T -5 of point 33 is negative"});
    }
    if (n == "heidenhain") {
      v = ls;
      v.erase(v.begin() + static_cast<long>(lay.at(33)) + 1);
      c.push_back({"point without its time line", join(v), lineOf(34) - 1, "point 33 (line 66) has no time line"});
      v = ls;
      v[lay.at(34) + 1] = "T20231332 132004";
      c.push_back({"invalid date", join(v), lineOf(34) + 1, "time of point 34 'T20231332 132004' is not"});
    }
  }
  return c;
}

TEST_P(Malformed, EveryKindIsRejectedAtItsLineWithAPreciseMessage) {
  // The unedited file is accepted: every rejection below is due to its one edit.
  ASSERT_EQ(d().parseResults(join(ls), "res.txt", plan).points.size(), 154u);
  const auto cs = cases();
  std::set<std::string> kinds;
  for (const auto& c : cs) {
    SCOPED_TRACE(GetParam() + ": " + c.kind);
    kinds.insert(c.kind);
    std::string msg;
    try {
      d().parseResults(c.text, "res.txt", plan);
    } catch (const InputError& e) {
      msg = e.what();
      EXPECT_EQ(e.file(), "res.txt");
      EXPECT_EQ(e.line(), c.line) << msg;
    }
    ASSERT_FALSE(msg.empty()) << "accepted";
    const std::string prefix = fmt::format("res.txt:{}: ", c.line);
    EXPECT_EQ(msg.rfind(prefix, 0), 0u) << msg;
    EXPECT_NE(msg.find(c.message), std::string::npos) << msg;
  }
  EXPECT_GE(kinds.size(), 10u);
  EXPECT_EQ(kinds.size(), cs.size()) << "each kind once";
  RecordProperty("kinds", static_cast<int>(kinds.size()));
}

TEST_P(Malformed, SwappedValuesAreOffTheirProbingMove) {
  // The plausibility check's distance is the exact point-to-line distance: the two swapped
  // triggers are as far off each other's line as the nominal triggers are apart laterally.
  MeasurementRun r = run;
  std::swap(r.points[9].position_m_mm, r.points[10].position_m_mm);
  const std::string e = test::messageOf<InputError>([&] { d().parseResults(d().writeResults(plan, r), "res.txt", plan); });
  const ProbePoint& p10 = *plan.findPoint(10);
  const Eigen::Vector3d dd = r.points[9].position_m_mm - p10.trigger_m_mm;
  const double lateral = (dd - dd.dot(p10.approach_m) * p10.approach_m).norm();
  ASSERT_GT(lateral, 1.0);
  EXPECT_NE(e.find(fmt::format("mm is {:.3f} mm off the line of its probing move", lateral)), std::string::npos) << e;
}

INSTANTIATE_TEST_SUITE_P(AllDialects, Malformed,
                         ::testing::ValuesIn(dialectNames()),
                         [](const auto& info) { return info.param; });

TEST(MalformedMacroB, PunchCodesAroundTheOutputAreNotAnError) {
  // POPEN sends DC2 and a NUL feed, PCLOS DC4: the parser drops them and reads the file.
  const ProbePlan plan = test::acPlan();
  MeasurementRun run = test::displacedRun(plan);
  for (auto& p : run.points) p.t_s += 7.5e8;
  for (const char* name : {"fanuc", "haas"}) {
    const Dialect& d = dialectByName(name);
    const std::string text = std::string("\x12\0\0%\r\n", 6) + d.writeResults(plan, run) + "%\r\n\x14";
    EXPECT_EQ(d.parseResults(text, "res.txt", plan).points.size(), 154u) << name;
  }
}

TEST(ResultChecks, TextCheckCountsLinesAsTheParsersDo) {
  // LF, CR LF and a lone CR each end one line.
  const std::string e = test::messageOf<InputError>([] { ctl::requireText("a\nb\r\nc\rd\x7f", "f.txt"); });
  EXPECT_EQ(e.rfind("f.txt:4: byte 0x7F at column 2", 0), 0u) << e;
  EXPECT_NO_THROW(ctl::requireText("tab\tand ~ printable\r\n", "f.txt"));
}

TEST(ResultChecks, ProbingMoveBoundsAreInclusiveWithTheirTolerance) {
  const ProbePlan plan = test::acPlan();
  const ProbePoint& p = plan.points.front();
  const Eigen::Vector3d u = p.approach_m;
  const Eigen::Vector3d side = u.unitOrthogonal();
  const double tol = ctl::kTriggerOffMoveTolMm;
  auto ok = [&](const Eigen::Vector3d& x) {
    return test::messageOf<InputError>([&] { ctl::requireOnProbingMove(plan, p, x, "f", 1); }).empty();
  };
  EXPECT_TRUE(ok(p.trigger_m_mm));
  EXPECT_TRUE(ok(p.start_m(plan.machine.approach_mm + 0.99 * tol)));
  EXPECT_FALSE(ok(p.start_m(plan.machine.approach_mm + 1.01 * tol)));
  EXPECT_TRUE(ok(p.end_m(plan.machine.overtravel_mm + 0.99 * tol)));
  EXPECT_FALSE(ok(p.end_m(plan.machine.overtravel_mm + 1.01 * tol)));
  EXPECT_TRUE(ok(p.trigger_m_mm + 0.99 * tol * side));
  EXPECT_FALSE(ok(p.trigger_m_mm + 1.01 * tol * side));
  EXPECT_FALSE(ok(p.trigger_m_mm + Eigen::Vector3d::Constant(std::nan(""))));
  EXPECT_TRUE(ok(p.trigger_m_mm + 0.5 * u + 0.05 * side));
}

}  // namespace
}  // namespace rotacal
