#include "controllers/text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace rotacal::ctl {

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) throw std::invalid_argument("cannot write a non-finite number into NC text");
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (!s.empty() && s[0] == '-' && s.find_first_of("123456789") == std::string::npos) s.erase(0, 1);
  return s;
}

std::string trimmed(double v, int decimals) {
  std::string s = fixed(v, decimals);
  if (s.find('.') != std::string::npos)
    while (!s.empty() && s.back() == '0') s.pop_back();
  if (s == "-0." || s == "-.") s = "0.";
  return s;
}

std::vector<TextLine> splitLines(std::string_view text) {
  std::vector<TextLine> lines;
  int n = 1;
  size_t start = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n' || text[i] == '\r') {
      lines.push_back({n++, std::string(text.substr(start, i - start))});
      if (text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      start = i + 1;
    }
  }
  if (start < text.size()) lines.push_back({n, std::string(text.substr(start))});
  return lines;
}

std::vector<std::string> tokens(std::string_view line) {
  std::vector<std::string> t;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) t.emplace_back(line.substr(b, i - b));
  }
  return t;
}

std::string trim(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return std::string(s.substr(b, e - b));
}

std::string printableLine(std::string_view text) {
  std::string s(text);
  for (auto& c : s)
    if (c < 0x20 || c > 0x7e) c = ' ';
  return s;
}

std::vector<std::string> wrap(std::string_view text, size_t width) {
  const std::string s = trim(text);
  std::vector<std::string> out;
  size_t i = 0;
  while (i < s.size()) {
    size_t n = std::min(width, s.size() - i);
    if (i + n < s.size()) {
      const size_t sp = s.rfind(' ', i + n);
      if (sp != std::string::npos && sp > i) n = sp - i;
    }
    out.push_back(trim(s.substr(i, n)));
    i += n;
    while (i < s.size() && s[i] == ' ') ++i;
  }
  return out;
}

std::string upper(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return r;
}

std::string lower(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

std::optional<double> parseNumber(std::string_view t) {
  size_t i = 0;
  const size_t n = t.size();
  auto digit = [&](size_t k) { return k < n && t[k] >= '0' && t[k] <= '9'; };
  bool negative = false;
  if (i < n && (t[i] == '+' || t[i] == '-')) negative = t[i++] == '-';
  const size_t body = i;
  size_t mantissa_digits = 0;
  while (digit(i)) ++i, ++mantissa_digits;
  if (i < n && t[i] == '.') {
    ++i;
    while (digit(i)) ++i, ++mantissa_digits;
  }
  if (mantissa_digits == 0) return std::nullopt;
  if (i < n && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < n && (t[i] == '+' || t[i] == '-')) ++i;
    if (!digit(i)) return std::nullopt;
    while (digit(i)) ++i;
  }
  if (i != n) return std::nullopt;
  double v = 0.0;
  // from_chars takes no '+' and no sign after we skipped it; a body like "12." or ".5" is fine.
  const auto r = std::from_chars(t.data() + body, t.data() + n, v);
  if (r.ec != std::errc() || r.ptr != t.data() + n || !std::isfinite(v)) return std::nullopt;
  return negative ? -v : v;
}

std::optional<long> parseDigits(std::string_view t) {
  if (t.empty() || t.size() > 9) return std::nullopt;
  long v = 0;
  for (char c : t) {
    if (c < '0' || c > '9') return std::nullopt;
    v = v * 10 + (c - '0');
  }
  return v;
}

}  // namespace rotacal::ctl
