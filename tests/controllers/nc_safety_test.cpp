// What reaches a control, across the dialects (issue 14): each cycle's own program number;
// outside text (a report's path, a machine's name) never leaving its comment; the checkers'
// limits kept by every writer (Heidenhain's offsets lines, DPRNT field widths); each control's
// dwell word. Every expectation is computed here from the text, not by the writers' helpers.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "controllers/program_writing.hpp"
#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "ctl_test_util.hpp"
#include "dialect_battery.hpp"
#include "gcode/reader.hpp"
#include "postproc/compensate_program.hpp"
#include "postproc/probe_program.hpp"
#include "cycles/tooltip/program.hpp"
#include "test_util.hpp"
#include "dialect_lists.hpp"

namespace rotacal {
namespace {

using test::lines;

std::string firstLineStartingWithO(const std::string& text) {
  for (const auto& l : lines(text))
    if (!l.empty() && l[0] == 'O') return l;
  return "";
}

// The numbers as docs/dialects.md lists them.
const std::map<std::string, int> kDocumentedNumbers = {
    {"touch154", 7154}, {"spheres3", 7001}, {"rtest", 7002}, {"spaceframe", 7003}, {"tooltip", 7004}};

TEST(ProgramNumbers, EachCycleHasItsOwnNumberInEveryDialectThatNumbersPrograms) {
  const MachineModel ac = test::acTestMachine();
  const MachineModel a120 = loadMachine(test::sourcePath("examples/machines/ac_trunnion_a120.json"));
  const MachineModel head = loadMachine(test::sourcePath("examples/machines/head_ab.json"));
  const std::vector<ProbePlan> plans = {
      makePlan("touch154", ac, {}), makePlan("spheres3", ac, {}),
      makePlan("spaceframe", a120, {{"theta_list", "0,180"}, {"phi_list", "0,90"}}),
      makePlan("tooltip", head, {{"units", "inch"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}})};
  for (const char* d : {"fanuc", "haas", "okuma"}) {
    std::set<int> seen;
    for (const auto& plan : plans) {
      if (plan.cycle == "tooltip" && std::string(d) == "okuma") continue;  // refused: G93 unverified
      const std::string text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
      std::smatch m;
      const std::string o = firstLineStartingWithO(text);
      ASSERT_TRUE(std::regex_search(o, m, std::regex(R"(^O(\d+))"))) << d << " " << plan.cycle << ": " << o;
      EXPECT_EQ(std::stoi(m[1]), kDocumentedNumbers.at(plan.cycle)) << d << " " << plan.cycle;
      if (std::string(d) == "haas") {
        EXPECT_EQ(m[1].length(), 5u) << "Haas: O + 5 digits";
      }
      EXPECT_TRUE(seen.insert(std::stoi(m[1])).second) << d << ": " << plan.cycle << " shares its number";
    }
  }
  // rtest is written for linuxcnc only (no O-number there), but has its number for when it is not.
  EXPECT_EQ(cycleByName("rtest").programNumber(), kDocumentedNumbers.at("rtest"));
  nc::Program none;
  EXPECT_THROW(ctl::programNumber(none), std::invalid_argument);
}

// ---- Outside text in comments ----

// The code of a text with its comments removed, one entry per non-empty statement: what the
// control executes. Independent of the writers: the comment syntax of each file form.
std::vector<std::string> codeOf(const std::string& form, const std::string& text) {
  std::vector<std::string> out;
  if (form == "hal") {
    for (const auto& l : lines(text))
      if (!l.empty() && l[0] != '#') out.push_back(l);
    return out;
  }
  if (form == "siemens" || form == "heidenhain") {
    for (auto l : lines(text)) {
      if (form == "heidenhain") l = std::regex_replace(l, std::regex(R"(^\d+ )"), "");  // the block number
      l = l.substr(0, l.find(';'));
      while (!l.empty() && l.back() == ' ') l.pop_back();
      if (!l.empty()) out.push_back(l);
    }
    return out;
  }
  for (const auto& b : nc::readProgram(text)) {
    if (!b.code.empty()) out.push_back(b.code);
    for (const auto& issue : b.issues) out.push_back("ISSUE " + issue);
  }
  return out;
}

// LinuxCNC writes its offsets as a HAL file unless the name ends in .ngc.
std::string formOf(const std::string& dialect, const std::string& path) {
  if (dialect == "linuxcnc" && !(path.size() > 4 && path.substr(path.size() - 4) == ".ngc")) return "hal";
  return dialect;
}

// Hostile names: nested parentheses (rs274 refuses "(... (1).json)"), line ends that would put
// the rest of the name on an executable line, a semicolon, a quote, UTF-8.
const std::vector<std::string> kHostile = {"REPORT (1).json", "out/x\nG0 X0 Y0 Z-100\n(.json",
                                           "a;M30\r\nG1 Z-100 F9999.json", "r\xc3\xa9p\"ort)(.json"};
const char* kHostileMachine = "mach)\nG0 Z-100 (x";

TEST(OutsideText, NamesInOffsetsFilesNeverBecomeCode) {
  for (const std::string& d : test::programDialects()) {
    for (const std::string& path : {std::string("offsets.x"), std::string("offsets.hal"), std::string("offsets.ngc")}) {
      if (std::string(d) != "linuxcnc" && path != "offsets.x") continue;
      auto offsets = [&](const std::string& report, const std::string& machine) {
        ProbePlan plan = test::acPlan();
        plan.machine.name = machine;
        OffsetRequest r = test::table4Request(plan);
        r.report_file = report;
        r.path = path;
        return dialectByName(d).writeOffsets(r);
      };
      const std::string benign = offsets("REPORT.json", "MACHINE");
      for (const auto& h : kHostile) {
        const std::string text = offsets(h, kHostileMachine);
        EXPECT_EQ(codeOf(formOf(d, path), text), codeOf(formOf(d, path), benign)) << d << " " << path << "\n" << text;
        if (std::string(d) != "linuxcnc") {
          for (const auto& l : lines(text)) EXPECT_LE(l.size(), 80u) << d << ": " << l;
        }
      }
    }
  }
}

TEST(OutsideText, MachineNameInProgramsNeverBecomesCode) {
  for (const std::string& d : test::programDialects()) {
    ProbePlan plan = test::acPlan();
    plan.machine.name = "MACHINE";
    const std::string benign = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
    plan.machine.name = kHostileMachine;
    const std::string text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
    EXPECT_EQ(codeOf(d, text), codeOf(d, benign)) << d;
    EXPECT_EQ(dialectByName(d).check(text, plan, test::shapeOf(plan, d)), std::vector<std::string>{}) << d;
  }
}

TEST(OutsideText, ReportPathInACompensatedProgramNeverBecomesCode) {
  const ProbePlan plan = test::acPlan();
  const LocationErrors e = test::table4();
  for (const std::string& d : test::wordAddressDialects()) {
    const std::string text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
    const NcSyntax syntax{d, 4, 5, 4, std::string(d) == "siemens" ? NcSyntax::Comment::Semicolon
                                                                   : NcSyntax::Comment::Parentheses};
    auto compensated = [&](const std::string& report) {
      ProgramCompensationOptions o;
      o.header = {"location errors of " + report + ":"};
      return compensateProgram(text, "p", plan.machine, e, syntax, o).text;
    };
    const std::string benign = compensated("REPORT.json");
    for (const auto& h : kHostile) {
      const std::string out = compensated(h);
      EXPECT_EQ(codeOf(d, out), codeOf(d, benign)) << d << " " << h;
      EXPECT_EQ(dialectByName(d).check(out, plan, test::shapeOf(plan, d)), std::vector<std::string>{}) << d;
    }
  }
}

TEST(OutsideText, CommentLinesKeepOnlyEachDialectsSafeCharacters) {
  const std::string hostile = "a(b)c;d\"e\nf\rg\x01h\xc3\xa9i";
  for (const std::string& d : test::programDialects()) {
    const auto ls = dialectByName(d).commentLines(hostile + std::string(300, 'x'));
    ASSERT_GE(ls.size(), 2u) << d << ": long text is wrapped";
    for (const auto& l : ls) {
      for (unsigned char c : l) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << d << ": byte " << int(c) << " in " << l;
      const bool semicolon = std::string(d) == "siemens" || std::string(d) == "heidenhain";
      if (semicolon) {
        EXPECT_EQ(l.rfind(";", 0), 0u) << d << ": " << l;
        // Heidenhain's lines get a block number of up to 4 digits and a blank in front.
        EXPECT_LE(l.size(), std::string(d) == "heidenhain" ? 80u - 5u : 80u) << d;
      } else {
        // One comment: '(' first, ')' last, none inside.
        EXPECT_EQ(l.front(), '(') << d << ": " << l;
        EXPECT_EQ(l.back(), ')') << d << ": " << l;
        EXPECT_EQ(l.find_first_of("()", 1), l.size() - 1) << d << ": " << l;
        EXPECT_LE(l.size(), std::string(d) == "linuxcnc" ? 252u : 80u) << d;
      }
      if (std::string(d) != "linuxcnc" && std::string(d) != "heidenhain") {
        EXPECT_EQ(l.find_first_of("abcdefghijklmnopqrstuvwxyz"), std::string::npos) << d << ": " << l;
      }
    }
  }
  EXPECT_THROW(dialectByName("csv").commentLines("x"), std::invalid_argument);
}

// Issue 14: Heidenhain's offsets provenance line was 84-165 characters against its own 80.
TEST(HeidenhainOffsets, EveryLineWithinEightyAndTheProvenanceWhole) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r = test::table4Request(plan);
  // 165 characters, with blanks (a folder named by hand) where the wrap may break it.
  r.report_file = "results/2023-10-07/machine shop hall 2/calibration after the crash of the A axis/";
  while (r.report_file.size() < 154) r.report_file += "repeat run ";
  r.report_file += "report.json";
  const std::string text = dialectByName("heidenhain").writeOffsets(r);
  std::string comments;
  int n = 0;
  for (const auto& l : lines(text)) {
    EXPECT_LE(l.size(), 80u) << l;
    EXPECT_EQ(l.rfind(std::to_string(n++) + " ", 0), 0u) << "block numbers in sequence: " << l;
    const size_t sc = l.find("; ");
    if (sc != std::string::npos) comments += l.substr(sc + 2) + " ";
  }
  // Wrapped at blanks only: the path comes back whole when the pieces are joined.
  EXPECT_NE(comments.find(r.report_file), std::string::npos) << comments;
}

// ---- DPRNT field widths and the dwell word ----

TEST(MacroB, EveryDprntFieldKeepsEightDigitsAndTheParserAgrees) {
  const ProbePlan plan = test::acPlan();
  for (const char* d : {"fanuc", "haas"}) {
    const std::string text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
    const std::regex field(R"(#\d+\[(\d)(\d)\])");
    int fields = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), field); it != std::sregex_iterator(); ++it, ++fields)
      EXPECT_LE(std::stoi((*it)[1]) + std::stoi((*it)[2]), 8) << d << ": " << (*it)[0];
    EXPECT_GT(fields, 4 * 154) << d;
    // The checker flags a [90] time field, the parser a 9-digit time.
    const std::string wide = std::regex_replace(text, std::regex(R"(\[80\]\])"), "[90]]");
    ASSERT_NE(wide, text) << d;
    EXPECT_TRUE(test::hasProblem(dialectByName(d).check(wide, plan, test::shapeOf(plan, d)), "a + b > 8")) << d;
    auto ls = lines(dialectByName(d).writeResults(plan, test::displacedRun(plan)));
    ls[2] = std::regex_replace(ls[2], std::regex(R"(T *\d+$)"), "T123456789");
    const std::string e = test::parseError(dialectByName(d), test::join(ls, "\r\n"), plan);
    EXPECT_NE(e.find("res.txt:3: T '123456789' of point 1 has 9 digits"), std::string::npos) << d << ": " << e;
    ls[2] = std::regex_replace(ls[2], std::regex(R"(T\d+$)"), "T00012345");  // 8 digits with leading zeros: fine
    EXPECT_EQ(test::parseError(dialectByName(d), test::join(ls, "\r\n"), plan), "") << d;
    // A run longer than [80] can count: the simulated results refuse it rather than print 9 digits.
    MeasurementRun run = test::displacedRun(plan);
    run.points.back().t_s = run.points.front().t_s + 1e5 + 1.0;  // 27.8 h
    EXPECT_THROW(dialectByName(d).writeResults(plan, run), std::invalid_argument) << d;
  }
}

TEST(MacroB, DwellIsSecondsInEachControlsOwnWord) {
  const MachineModel head = loadMachine(test::sourcePath("examples/machines/head_ab.json"));
  const ProbePlan plan = makePlan(
      "tooltip", head,
      {{"units", "inch"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}, {"dwell_s", "2.5"}, {"repeats", "1"}});
  // Haas: G04 P2.5 ([HaasMan]: P with a point = seconds); Fanuc: G04 X2.5 (P would be integer ms).
  for (const auto& [d, word] : {std::pair<const char*, const char*>{"haas", "P"}, {"fanuc", "X"}}) {
    const std::string text = dialectByName(d).writeProgram(test::cycleProgram(plan, d));
    const std::regex dwell(R"(\nG04 ([A-Z])([0-9.]+)\n)");
    int n = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), dwell); it != std::sregex_iterator(); ++it, ++n) {
      EXPECT_EQ((*it)[1], word) << d;
      EXPECT_EQ(std::stod((*it)[2]), 2.5) << d;
    }
    EXPECT_EQ(n, 18) << d << ": one dwell per reading (004 Table 1's 18 steps)";
    EXPECT_EQ(dialectByName(d).check(text, plan, test::shapeOf(plan, d)), std::vector<std::string>{}) << d;
  }
}

}  // namespace
}  // namespace rotacal
