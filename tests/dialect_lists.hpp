#pragma once
// The dialects a battery takes, from the registry (controllers/registry.cpp) and the dialects'
// identities: a new dialect joins every battery with its registry line, never with an edit here.
#include <string>
#include <vector>

#include "controllers/dialect.hpp"

namespace rotacal::test {

/// The names of the dialects `keep` accepts, in the registry's order.
template <class Keep>
std::vector<std::string> dialectsWhere(Keep keep) {
  std::vector<std::string> out;
  for (const Dialect* d : dialects())
    if (keep(*d)) out.emplace_back(d->name());
  return out;
}

/// The dialects that write NC programs (all but the neutral csv).
inline std::vector<std::string> programDialects() {
  return dialectsWhere([](const Dialect& d) { return d.hasPrograms(); });
}

/// The dialects whose programs are word-address G-code: `compensate` rewrites them.
inline std::vector<std::string> wordAddressDialects() {
  return dialectsWhere([](const Dialect& d) { return isWordAddress(d.language()); });
}

/// The dialects that follow each probing move with an end-point no-trigger check.
inline std::vector<std::string> endPointCheckDialects() {
  return dialectsWhere([](const Dialect& d) { return d.endPointCheck().has_value(); });
}

/// The dialects that write inverse-time feed (G93).
inline std::vector<std::string> inverseTimeDialects() {
  return dialectsWhere([](const Dialect& d) { return d.hasPrograms() && d.inverseTimeRefusal().empty(); });
}

}  // namespace rotacal::test
