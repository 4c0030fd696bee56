// `rotacal check` from the command line, and the check `generate` and `compensate` run before
// they write (docs/safety.md): exit codes, the FILE:LINE lines, nothing written on a violation.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>

#include "cli_run.hpp"
#include "dialect_lists.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;
using test::sh;
using test::slurp;


void spit(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

struct Dir {
  fs::path root = fs::temp_directory_path() / ("rotacal_check_cli_" + std::to_string(::getpid()));
  Dir() { fs::create_directories(root); }
  ~Dir() { fs::remove_all(root); }
  std::string p(const std::string& name) const { return (root / name).string(); }
};

const std::string kMachine = std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/ac_trunnion.json";

// A rapid across the column, right after the first touch's retract of the fanuc touch154 program.
std::string withRapidThroughTheColumn(const std::string& text, int* line) {
  const std::string retract = "G01 X58.0000 Y-235.0000 Z150.0000 F2000.0\n";
  const size_t g31 = text.find("G31 ");
  const size_t at = text.find(retract, g31) + retract.size();
  *line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
  return text.substr(0, at) + "G00 X-58.0000 Y-235.0000 Z150.0000\n" + text.substr(at);
}

TEST(CheckCli, PassesGeneratedProgramsAndNamesEachViolation) {
  Dir d;
  ASSERT_EQ(sh("plan --cycle touch154 --machine " + kMachine + " -o " + d.p("plan.json")).code, 0);
  for (const char* dialect : {"linuxcnc", "fanuc", "heidenhain"}) {
    const std::string prog = d.p(std::string("t.") + dialect);
    ASSERT_EQ(sh("generate --plan " + d.p("plan.json") + " --dialect " + dialect + " -o " + prog).code, 0) << dialect;
    const auto r = sh("check " + prog + " --dialect " + dialect + " --machine " + kMachine + " --plan " + d.p("plan.json"));
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find(prog + ": ok: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("154 probing moves, minimum clearance 5.000 mm"), std::string::npos) << r.out;
  }
  int line = 0;
  spit(d.p("bad.nc"), withRapidThroughTheColumn(slurp(d.p("t.fanuc")), &line));
  const auto bad = sh("check " + d.p("bad.nc") + " --dialect fanuc --machine " + kMachine);
  EXPECT_EQ(bad.code, 1) << bad.out;
  EXPECT_NE(bad.out.find(d.p("bad.nc") + ":" + std::to_string(line) + ": this move comes within"), std::string::npos)
      << bad.out;
  // stderr: the first violation, FILE:LINE: problem, and how many more are listed on stdout.
  EXPECT_NE(bad.out.find("rotacal: error: " + d.p("bad.nc") + ":" + std::to_string(line) + ": this move comes within"),
            std::string::npos)
      << bad.out;
  // Usage: csv has no programs.
  EXPECT_EQ(sh("check " + d.p("bad.nc") + " --dialect csv --machine " + kMachine).code, 2);
}

TEST(CheckCli, CompensateWritesNoProgramThatFailsTheCheck) {
  Dir d;
  ASSERT_EQ(sh("plan --cycle touch154 --machine " + kMachine + " -o " + d.p("plan.json")).code, 0);
  ASSERT_EQ(sh("generate --plan " + d.p("plan.json") + " --dialect fanuc -o " + d.p("t.nc")).code, 0);
  ASSERT_EQ(sh("simulate --plan " + d.p("plan.json") + " --truth " + std::string(ROTACAL_SOURCE_DIR) +
               "/examples/truth/table4_mean.json --dialect fanuc -o " + d.p("r.txt")).code, 0);
  ASSERT_EQ(sh("analyze --plan " + d.p("plan.json") + " --results " + d.p("r.txt") + " --dialect fanuc --json " +
               d.p("report.json")).code, 0);
  // The clean program compensates and its output passes check.
  ASSERT_EQ(sh("compensate --program " + d.p("t.nc") + " --report " + d.p("report.json") + " --dialect fanuc -o " +
               d.p("c.nc")).code, 0);
  const auto ok = sh("check " + d.p("c.nc") + " --dialect fanuc --machine " + kMachine + " --plan " + d.p("plan.json"));
  EXPECT_EQ(ok.code, 0) << ok.out;
  // A program with a rapid through the column: compensate rewrites it, the check refuses it.
  int line = 0;
  spit(d.p("bad.nc"), withRapidThroughTheColumn(slurp(d.p("t.nc")), &line));
  const auto r = sh("compensate --program " + d.p("bad.nc") + " --report " + d.p("report.json") + " --dialect fanuc -o " +
                    d.p("out.nc"));
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("the program fails rotacal check"), std::string::npos) << r.out;
  // Named in the input, at its own line (the rewrite is never written, its lines are not the user's).
  EXPECT_NE(r.out.find("rotacal: error: " + d.p("bad.nc") + ":" + std::to_string(line) + ":"), std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(d.p("out.nc")));
}

// Hand edits of a program rotacal wrote, each unsafe, each found with the plan at its own line:
// the dialect's rules run in `check` as they do before `generate` writes. Each case is what an
// edit does on the control: a guard whose alarm cannot be raised, a call the verifier cannot
// follow, a loop, a lost bracket, a coordinate read in least input increments.
TEST(CheckCli, HandEditsThatMakeAProgramUnsafeFailWithThePlanAtTheirLine) {
  Dir d;
  ASSERT_EQ(sh("plan --cycle one_sphere --machine " + kMachine + " -o " + d.p("plan.json")).code, 0);
  ASSERT_EQ(sh("generate --plan " + d.p("plan.json") + " --dialect fanuc -o " + d.p("t.nc")).code, 0);
  const std::string text = slurp(d.p("t.nc"));
  const auto check = [&](const std::string& name, const std::string& edited) {
    spit(d.p(name), edited);
    return sh("check " + d.p(name) + " --dialect fanuc --machine " + kMachine + " --plan " + d.p("plan.json"));
  };
  const auto ok = check("same.nc", text);
  ASSERT_EQ(ok.code, 0) << ok.out;
  EXPECT_NE(ok.out.find("the fanuc checker's rules (comments, brackets, labels, alarms): ok against the plan"),
            std::string::npos)
      << ok.out;
  const auto lineOf = [&](size_t at) { return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n')); };
  const auto expectAt = [&](const test::CliRun& r, int line, const std::string& what, const std::string& name) {
    EXPECT_EQ(r.code, 1) << name << ": " << r.out;
    EXPECT_NE(r.out.find("rotacal: error: " + d.p(name) + ":" + std::to_string(line) + ": the fanuc checker: " + what),
              std::string::npos)
        << name << ": " << r.out;
  };
  // The guard's jump made unconditional: GT-1.0 on a squared distance is always true.
  const size_t gt = text.find("GT0.0001");
  ASSERT_NE(gt, std::string::npos);
  std::string e = text;
  e.replace(gt, 8, "GT-1.0");
  expectAt(check("gt.nc", e), lineOf(gt), "the no-trigger check must jump past its alarm", "gt.nc");
  // The alarm line deleted: the G31 before it is named.
  const size_t alarm = text.find("#3000=");
  const size_t g31 = text.rfind("G31", alarm);
  e = text;
  e.erase(alarm, text.find('\n', alarm) + 1 - alarm);
  expectAt(check("alarm.nc", e), lineOf(g31), "G31 is not followed by the no-trigger check", "alarm.nc");
  // A subprogram call after the first block.
  const size_t second = text.find('\n', text.find('\n') + 1) + 1;
  e = text;
  e.insert(second, "M98 P9000\n");
  expectAt(check("m98.nc", e), lineOf(second), "M98: a subprogram or macro call the verifier cannot follow", "m98.nc");
  // A jump back to the guard's own label: an endless loop.
  const size_t label = text.find("\nN1001") + 1;
  const size_t after = text.find('\n', label) + 1;
  e = text;
  e.insert(after, "IF[#1GT0.0]GOTO1001\n");
  expectAt(check("loop.nc", e), lineOf(after), "GOTO1001 jumps back to line " + std::to_string(lineOf(label)), "loop.nc");
  // A coordinate without its decimal point: Z183 is 0.183 mm on a control in least input increments.
  const size_t z = text.find("G00 Z");
  ASSERT_NE(z, std::string::npos);
  const size_t dot = text.find('.', z);
  const size_t end = text.find_first_not_of("0123456789", dot + 1);
  e = text;
  e.erase(dot, end - dot);
  expectAt(check("point.nc", e), lineOf(z), "Z", "point.nc");
  EXPECT_NE(check("point.nc", e).out.find("has no decimal point"), std::string::npos);
  // The other guarded dialects: Okuma's alarm deleted, Siemens' condition made never true and its
  // label deleted; each names the probing move whose guard it broke.
  for (const auto& [dialect, from, to] :
       {std::tuple<std::string, std::string, std::string>{"okuma", "VDOUT[992]=1001\n", ""},
        {"siemens", "$AC_MEA[1]==0", "$AC_MEA[1]==2"},
        {"siemens", "\nNOHIT1:", "\n"}}) {
    const std::string prog = d.p("g." + dialect);
    ASSERT_EQ(sh("generate --plan " + d.p("plan.json") + " --dialect " + dialect + " -o " + prog).code, 0) << dialect;
    std::string t = slurp(prog);
    const size_t at = t.find(from);
    ASSERT_NE(at, std::string::npos) << dialect << " " << from;
    t.replace(at, from.size(), to);
    spit(d.p("edit." + dialect), t);
    const auto r = sh("check " + d.p("edit." + dialect) + " --dialect " + dialect + " --machine " + kMachine + " --plan " +
                      d.p("plan.json"));
    EXPECT_EQ(r.code, 1) << dialect << " " << from << ": " << r.out;
    EXPECT_NE(r.out.find("the " + dialect + " checker: "), std::string::npos) << r.out;
  }
}

// A space frame's plan takes the column off the table: its programs pass check with the plan in
// every dialect (they failed on the machine file's column before).
TEST(CheckCli, SpaceframeProgramsPassWithTheirPlanInEveryDialect) {
  Dir d;
  ASSERT_EQ(sh("plan --cycle spaceframe --machine " + kMachine + " --set phi_list=-90,0 --set theta_list=0,90,180,270 -o " +
               d.p("plan.json")).code,
            0);
  for (const std::string& dialect : test::programDialects()) {
    const std::string prog = d.p(std::string("sf.") + dialect);
    ASSERT_EQ(sh("generate --plan " + d.p("plan.json") + " --dialect " + dialect + " -o " + prog).code, 0) << dialect;
    const auto r = sh("check " + prog + " --dialect " + dialect + " --machine " + kMachine + " --plan " + d.p("plan.json"));
    EXPECT_EQ(r.code, 0) << dialect << ": " << r.out;
  }
  // The plan of another machine is refused, naming the plan.
  const auto other = sh("check " + d.p("sf.fanuc") + " --dialect fanuc --machine " + std::string(ROTACAL_SOURCE_DIR) +
                        "/examples/machines/bc_trunnion.json --plan " + d.p("plan.json"));
  EXPECT_EQ(other.code, 1) << other.out;
  EXPECT_NE(other.out.find(d.p("plan.json") + ":0: the plan is of machine"), std::string::npos) << other.out;
}

}  // namespace
}  // namespace rotacal
