// The regular build's driver of a libFuzzer harness (what libFuzzer's StandaloneFuzzTargetMain
// does): runs LLVMFuzzerTestOneInput once per file named on the command line, `--select N`
// putting the selector byte N before the files after it. CTest replays the bundled inputs this
// way with GCC, so a harness whose source list or code no longer builds, or an input boundary
// that lets an exception other than InputError escape, fails the ordinary test run and not only
// the clang fuzz step of CI.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
  int select = -1;
  int inputs = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--select" && i + 1 < argc) {
      select = std::atoi(argv[++i]);
      continue;
    }
    std::ifstream in(arg, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "%s: cannot be read\n", arg.c_str());
      return 2;
    }
    std::vector<uint8_t> bytes;
    if (select >= 0) bytes.push_back(static_cast<uint8_t>(select));
    bytes.insert(bytes.end(), std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
    ++inputs;
  }
  std::printf("%d inputs replayed, none escaped\n", inputs);
  return inputs > 0 ? 0 : 2;
}
