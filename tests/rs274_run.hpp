// LinuxCNC's own interpreter (rs274 -g, Debian linuxcnc-uspace) run on a program, for the tests
// that check generated G-code against a real interpreter.
//
// Every run gets its own directory, and HOME points there: rs274 creates $HOME/.tool.mmap with
// O_TRUNC and maps it, so two runs sharing one HOME (ctest -j) truncate each other's mapping and
// one dies of SIGBUS ("Bus error") at random.
#pragma once

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rotacal::test {

#ifdef ROTACAL_RS274
inline const char* const kRs274 = ROTACAL_RS274;
#else
inline const char* const kRs274 = "/usr/bin/rs274";
#endif

inline bool haveRs274() { return std::filesystem::exists(kRs274); }

struct Rs274Run {
  int exit_code = -1;  // -1: killed by a signal
  std::string out;     // the canon calls (stdout)
  std::string err;     // the interpreter's messages (stderr)
};

inline Rs274Run runRs274(const std::string& program) {
  namespace fs = std::filesystem;
  static std::atomic<int> serial{0};
  const fs::path dir = fs::temp_directory_path() / fmt::format("rotacal_rs274_{}_{}", ::getpid(), serial++);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "p.ngc", std::ios::binary) << program;
  const std::string cmd =
      fmt::format("cd '{0}' && HOME='{0}' '{1}' -g p.ngc < /dev/null > out.txt 2> err.txt", dir.string(), kRs274);
  const int status = std::system(cmd.c_str());
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  Rs274Run r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(dir / "out.txt");
  r.err = slurp(dir / "err.txt");
  fs::remove_all(dir);
  return r;
}

inline size_t countOf(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + what.size())) ++n;
  return n;
}

}  // namespace rotacal::test
