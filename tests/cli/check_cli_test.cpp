// `rotacal check` from the command line, and the check `generate` and `compensate` run before
// they write (docs/safety.md): exit codes, the FILE:LINE lines, nothing written on a violation.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_run.hpp"

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

}  // namespace
}  // namespace rotacal
