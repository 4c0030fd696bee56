#pragma once
// Runs the rotacal binary under test (ROTACAL_CLI, set per test target) as a shell would: the
// CLI tests check exit codes and messages exactly as a script or CAM post sees them. Also the
// scratch directories and JSON files they share.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_util.hpp"

namespace rotacal::test {

namespace fs = std::filesystem;

struct CliRun {
  int code;         // exit status, -1 when the command did not exit normally
  std::string out;  // stdout and stderr together
};

/// Runs a whole shell command line; `out` is its stdout (the command redirects stderr itself).
inline CliRun runCommand(const std::string& cmd) {
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (p && fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = p ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

/// `rotacal ARGS`, stdout and stderr together.
inline CliRun sh(const std::string& args) { return runCommand(std::string(ROTACAL_CLI) + " " + args + " 2>&1"); }

/// The running test's name (a scratch directory per test keeps tests independent).
inline std::string testName() { return ::testing::UnitTest::GetInstance()->current_test_info()->name(); }

/// An empty scratch directory <build>/test_tmp/<name>, whatever an earlier run left there.
inline std::filesystem::path freshDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(ROTACAL_BINARY_DIR) / "test_tmp" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// A test with a scratch directory of its own, named after its suite and itself (ctest runs the
/// tests of a file as separate processes, in parallel): p(name) is a path in it.
class ScratchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir = freshDir(std::string(info->test_suite_name()) + "_" + info->name());
  }
  std::string p(const std::string& name) const { return (dir / name).string(); }
  std::filesystem::path dir;
};

/// A scratch test on the bundled A/C trunnion, with 000 Table 4's mean errors as the truth (a
/// test may point `truth` at a file of its own).
class AcTrunnionTest : public ScratchTest {
 protected:
  const std::string machine = sourcePath("examples/machines/ac_trunnion.json");
  std::string truth = sourcePath("examples/truth/table4_mean.json");
};

/// Whether a command was refused the contract's way: exit `code`, its output naming `what`, and
/// nothing written at `not_written`. The failure says which of the three.
inline ::testing::AssertionResult refused(const CliRun& r, int code, const std::string& what,
                                          const std::filesystem::path& not_written) {
  if (r.code != code) return ::testing::AssertionFailure() << "exit " << r.code << ", expected " << code << ": " << r.out;
  if (r.out.find(what) == std::string::npos) return ::testing::AssertionFailure() << "no '" << what << "' in: " << r.out;
  if (std::filesystem::exists(not_written)) return ::testing::AssertionFailure() << not_written << " was written";
  return ::testing::AssertionSuccess();
}

/// A JSON file's content (throws when it is missing or not JSON).
inline nlohmann::json loadJson(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

/// A file's whole content (empty when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace rotacal::test
