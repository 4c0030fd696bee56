#pragma once
// The one-line form of an error message, for the command line's stderr and the public library's
// rotacal::Error alike.
#include <string>

namespace rotacal {

/// A message as the one line on stderr the contract promises: control characters (a line end,
/// a NUL or an escape from an input file quoted in the message) become \xNN, and a message
/// beyond 1000 characters (a 1 MB line quoted whole) is cut, saying so.
inline std::string oneLine(const std::string& s) {
  constexpr size_t kMax = 1000;
  std::string out;
  for (const char ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u == 0x7f) {
      static const char* const hex = "0123456789abcdef";
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    } else {
      out += ch;
    }
    if (out.size() >= kMax) {
      if (&ch != &s.back()) out += "... (message cut at 1000 characters)";
      break;
    }
  }
  return out;
}

}  // namespace rotacal
