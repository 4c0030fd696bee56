#pragma once
// Runs the rotacal binary under test (ROTACAL_CLI, set per test target) as a shell would: the
// CLI tests check exit codes and messages exactly as a script or CAM post sees them.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rotacal::test {

struct CliRun {
  int code;         // exit status, -1 when the command did not exit normally
  std::string out;  // stdout and stderr together
};

inline CliRun sh(const std::string& args) {
  const std::string cmd = std::string(ROTACAL_CLI) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (p && fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = p ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

/// A file's whole content (empty when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace rotacal::test
