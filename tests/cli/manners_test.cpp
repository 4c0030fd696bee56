// Terminal manners (issue 7): progress on a terminal only, --quiet, --json - on stdout alone,
// --version, and --html written beside the JSON. The terminal is a real pseudo-terminal
// (util-linux `script`), so isatty() is what decides, as for a user.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "test_util.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;

struct Out {
  int code;
  std::string text;
};
Out run(const std::string& cmd) {
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (p && fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = p ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

class Manners : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::path(ROTACAL_BINARY_DIR) / "test_tmp" / "manners";
    fs::create_directories(dir);
    cli = ROTACAL_CLI;
    plan = (dir / "plan.json").string();
    ASSERT_EQ(run(cli + " -q plan --cycle touch154 --machine " + test::sourcePath("examples/machines/ac_trunnion.json") +
                  " -o " + plan).code, 0);
    results = (dir / "r.csv").string();
    ASSERT_EQ(run(cli + " -q simulate --plan " + plan + " --truth " + test::sourcePath("examples/truth/table4_mean.json") +
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
  const Out tty = run("script -qec \"" + uncertainty("") + "\" /dev/null");
  ASSERT_EQ(tty.code, 0) << tty.text;
  EXPECT_NE(tty.text.find("400/400 runs"), std::string::npos) << tty.text;
  const Out quiet_tty = run("script -qec \"" + uncertainty(" -q") + "\" /dev/null");
  ASSERT_EQ(quiet_tty.code, 0);
  EXPECT_EQ(quiet_tty.text, "");
  const Out piped = run(uncertainty("") + " 2>&1 >/dev/null");  // stderr only, not a terminal
  ASSERT_EQ(piped.code, 0);
  EXPECT_EQ(piped.text, "");
}

TEST_F(Manners, JsonDashIsTheDocumentAloneOnStdout) {
  const Out a = run(cli + " analyze --plan " + plan + " --results " + results + " --dialect csv --json - --html " +
                    (dir / "a.html").string());
  ASSERT_EQ(a.code, 0);
  const auto j = nlohmann::json::parse(a.text);  // throws if the summary leaked into stdout
  EXPECT_EQ(j["format"], "rotacal-report/1");
  EXPECT_EQ(j["points"].size(), 154u);
  EXPECT_TRUE(fs::exists(dir / "a.html"));
  const Out u = run(cli + " uncertainty --plan " + plan + " --contributors " +
                    test::sourcePath("examples/contributors/table5.json") + " --runs 50 --combined-only --json -");
  ASSERT_EQ(u.code, 0);
  EXPECT_EQ(nlohmann::json::parse(u.text)["format"], "rotacal-uncertainty/1");
}

TEST_F(Manners, Version) {
  const Out v = run(cli + " --version");
  EXPECT_EQ(v.code, 0);
  EXPECT_EQ(v.text.rfind("rotacal ", 0), 0u) << v.text;
}

}  // namespace
}  // namespace rotacal
