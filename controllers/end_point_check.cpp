#include "controllers/end_point_check.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>

#include "controllers/text.hpp"

namespace rotacal::ctl {

std::optional<EndPointCheck> endPointCheck(std::string_view dialect) {
  const Dialect* d = findDialect(dialect);
  if (!d) return std::nullopt;
  return d->endPointCheck();
}

std::string endPointCheckStatement(const EndPointCheck& form, int axis, double end, int decimals) {
  const auto a = static_cast<size_t>(axis);
  return fmt::format("{}={}{}{}", form.difference.at(a), form.measured[a], end < 0 ? "+" : "-",
                     fixed(std::abs(end), decimals));
}

std::optional<EndPointCheckStatement> parseEndPointCheckStatement(const EndPointCheck& form, std::string_view code) {
  size_t i = 0;
  auto blanks = [&] {
    while (i < code.size() && (code[i] == ' ' || code[i] == '\t')) ++i;
  };
  auto word = [&](std::string_view w) {
    if (upper(code.substr(i, w.size())) != upper(w)) return false;
    i += w.size();
    return true;
  };
  blanks();
  if (i < code.size() && (code[i] == 'N' || code[i] == 'n') && i + 1 < code.size() && std::isdigit(static_cast<unsigned char>(code[i + 1]))) {
    ++i;
    while (i < code.size() && std::isdigit(static_cast<unsigned char>(code[i]))) ++i;
    blanks();
  }
  const size_t start = i;
  for (int a = 0; a < 3; ++a) {
    i = start;
    const auto k = static_cast<size_t>(a);
    if (!word(form.difference[k])) continue;
    blanks();
    if (!word("=")) continue;
    blanks();
    if (!word(form.measured[k])) continue;
    // The next character must end the variable's name: "#50610" is another variable.
    if (i < code.size() && std::isalnum(static_cast<unsigned char>(code[i]))) continue;
    blanks();
    if (i >= code.size() || (code[i] != '+' && code[i] != '-')) continue;
    const bool plus = code[i++] == '+';
    blanks();
    const std::string number = trim(code.substr(i));
    if (number.empty() || number[0] == '+' || number[0] == '-' || number.find_first_of("eE") != std::string::npos)
      continue;
    const auto v = parseNumber(number);
    if (!v) continue;
    const size_t point = number.find('.');
    const int decimals = point == std::string::npos ? 0 : static_cast<int>(number.size() - point - 1);
    return EndPointCheckStatement{a, plus ? -*v : *v, decimals};
  }
  return std::nullopt;
}

}  // namespace rotacal::ctl
