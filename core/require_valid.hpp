#pragma once
// The one form of validation (Ceres' Options::IsValid): `bool validate(std::string* why) const`, and
// the one way an options struct with `bool validate(std::string* why) const` is refused where it
// is used: std::invalid_argument naming what the options are for and why.
#include <stdexcept>
#include <string>
#include <utility>

namespace rotacal {

/// What every `validate(std::string* why)` returns on what it refuses: false, and why (when asked).
inline bool invalidBecause(std::string* why, std::string what) {
  if (why) *why = std::move(what);
  return false;
}

/// Throws std::invalid_argument("<what>: <why>") when `options.validate` refuses them.
template <class Options>
void requireValid(const Options& options, const std::string& what) {
  std::string why;
  if (!options.validate(&why)) throw std::invalid_argument(what + ": " + why);
}

}  // namespace rotacal
