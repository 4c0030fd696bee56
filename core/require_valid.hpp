#pragma once
// The one way an options struct with `bool validate(std::string* why) const` is refused where it
// is used: std::invalid_argument naming what the options are for and why.
#include <stdexcept>
#include <string>

namespace rotacal {

/// Throws std::invalid_argument("<what>: <why>") when `options.validate` refuses them.
template <class Options>
void requireValid(const Options& options, const std::string& what) {
  std::string why;
  if (!options.validate(&why)) throw std::invalid_argument(what + ": " + why);
}

}  // namespace rotacal
