#pragma once
// What every libFuzzer harness of rotacal's input boundaries shares (tests/fuzz/README.md).
// The oracle: bad input may only end in InputError naming the file it came from;
// any other exception (a nlohmann, std::out_of_range, std::regex error, ...), a crash, a hang or
// a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "core/errors.hpp"
#include "core/json_io.hpp"

namespace rotacal::fuzz {

[[noreturn]] inline void finding(const char* what, const std::string& detail) {
  std::fprintf(stderr, "FUZZ FINDING: %s: %s\n", what, detail.c_str());
  std::abort();
}

/// Runs `f` on input that may be anything: it returns normally or throws InputError naming
/// `file` (rotacal's main prints it on one line, control characters escaped).
template <class F>
void expectInputErrorOnly(const std::string& file, F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (e.file() != file) finding("InputError names another file", what);
    if (e.line() < 0) finding("InputError with a negative line", what);
  } catch (const std::exception& e) {
    finding("exception other than InputError escaped", e.what());
  }
}

/// The path of a file under the source tree.
inline std::string sourcePath(const std::string& rel) { return std::string(ROTACAL_SOURCE_DIR) + "/" + rel; }

/// A JSON document from fuzz bytes, as readJsonFile would give it (parse errors are InputError).
inline std::string asText(const uint8_t* data, size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

}  // namespace rotacal::fuzz
