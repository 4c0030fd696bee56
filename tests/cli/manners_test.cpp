// Terminal manners (issue 7): progress on a terminal only, --quiet, --json - on stdout alone,
// --version, and --html written beside the JSON. The terminal is a real pseudo-terminal
// (util-linux `script`), so isatty() is what decides, as for a user.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;

// stdout alone: what goes where is the subject here.
using Out = test::CliRun;
using test::runCommand;

class Manners : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::path(ROTACAL_BINARY_DIR) / "test_tmp" / "manners";
    fs::create_directories(dir);
    cli = ROTACAL_CLI;
    plan = (dir / "plan.json").string();
    ASSERT_EQ(runCommand(cli + " -q plan --cycle touch154 --machine " + test::sourcePath("examples/machines/ac_trunnion.json") +
                  " -o " + plan).code, 0);
    results = (dir / "r.csv").string();
    ASSERT_EQ(runCommand(cli + " -q simulate --plan " + plan + " --truth " + test::sourcePath("examples/truth/table4_mean.json") +
                  " --noise-um 0.7 --dialect csv -o " + results).code, 0);
  }
  std::string uncertainty(const std::string& extra) const {
    return cli + " uncertainty --plan " + plan + " --contributors " +
           test::sourcePath("examples/contributors/table5.json") + " --runs 400 --combined-only --json " +
           (dir / "u.json").string() + extra;
  }
  fs::path dir;
  std::string cli, plan, results;
};

TEST_F(Manners, ProgressOnlyOnATerminalAndNotWhenQuiet) {
  const Out tty = runCommand("script -qec \"" + uncertainty("") + "\" /dev/null");
  ASSERT_EQ(tty.code, 0) << tty.out;
  EXPECT_NE(tty.out.find("400/400 runs"), std::string::npos) << tty.out;
  const Out quiet_tty = runCommand("script -qec \"" + uncertainty(" -q") + "\" /dev/null");
  ASSERT_EQ(quiet_tty.code, 0);
  EXPECT_EQ(quiet_tty.out, "");
  const Out piped = runCommand(uncertainty("") + " 2>&1 >/dev/null");  // stderr only, not a terminal
  ASSERT_EQ(piped.code, 0);
  EXPECT_EQ(piped.out, "");
}

TEST_F(Manners, JsonDashIsTheDocumentAloneOnStdout) {
  const Out a = runCommand(cli + " analyze --plan " + plan + " --results " + results + " --dialect csv --json - --html " +
                    (dir / "a.html").string());
  ASSERT_EQ(a.code, 0);
  const auto j = nlohmann::json::parse(a.out);  // throws if the summary leaked into stdout
  EXPECT_EQ(j["format"], "rotacal-report/1");
  EXPECT_EQ(j["points"].size(), 154u);
  EXPECT_TRUE(fs::exists(dir / "a.html"));
  const Out u = runCommand(cli + " uncertainty --plan " + plan + " --contributors " +
                    test::sourcePath("examples/contributors/table5.json") + " --runs 50 --combined-only --json -");
  ASSERT_EQ(u.code, 0);
  EXPECT_EQ(nlohmann::json::parse(u.out)["format"], "rotacal-uncertainty/1");
}

TEST_F(Manners, Version) {
  const Out v = runCommand(cli + " --version");
  EXPECT_EQ(v.code, 0);
  EXPECT_EQ(v.out.rfind("rotacal ", 0), 0u) << v.out;
  // "rotacal X.Y.Z (git REV)": the revision it was built from, or "unknown" outside a checkout.
  EXPECT_NE(v.out.find(" (git "), std::string::npos) << v.out;
  EXPECT_EQ(v.out.find(" (git )"), std::string::npos) << v.out;
}

// `plan --show-options` lists what --set can change with the values the plan uses (its defaults
// on this machine): the same as the options the written PLAN.json records.
TEST_F(Manners, PlanShowsItsOptionsWithTheValuesThePlanUses) {
  const std::string bc = test::sourcePath("examples/machines/bc_head_table.json");
  const std::string written = (dir / "os_plan.json").string();
  ASSERT_EQ(runCommand(cli + " -q plan --cycle one_sphere --machine " + bc + " -o " + written).code, 0);
  const Out shown = runCommand(cli + " plan --cycle one_sphere --machine " + bc + " --show-options");
  ASSERT_EQ(shown.code, 0) << shown.out;
  const nlohmann::json options = test::loadJson(written)["options"];
  ASSERT_GE(options.size(), 3u);
  for (const auto& [key, value] : options.items())
    EXPECT_NE(shown.out.find("  " + key + "=" + value.get<std::string>() + "\n"), std::string::npos) << key;
  // Without it, the plan's file is required: a usage error.
  EXPECT_EQ(runCommand(cli + " plan --cycle one_sphere --machine " + bc).code, 2);
}

}  // namespace
}  // namespace rotacal
