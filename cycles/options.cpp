#include "cycles/options.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rotacal {

Eigen::Vector3d parseVec3Option(const std::string& key, const std::string& text) {
  const auto v = parseNumberList(key, text);
  if (v.size() != 3) throw std::invalid_argument("option " + key + ": expected x,y,z in mm, got '" + text + "'");
  return {v[0], v[1], v[2]};
}

int parseCountOption(const std::string& key, const std::string& text, int lo, int hi) {
  const double v = parseNumber(key, text);
  if (!(v >= lo && v <= hi && v == std::floor(v)))
    throw std::invalid_argument(fmt::format("option {} must be a whole number from {} to {}, not '{}'", key, lo, hi, text));
  return static_cast<int>(v);
}

std::string numberListOption(const std::vector<double>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + fmt::format("{:g}", v[i]);
  return s;
}

void requireKnownOptions(std::string_view cycle, const CycleOptions& options, const std::vector<std::string>& known) {
  for (const auto& [key, value] : options)
    if (std::find(known.begin(), known.end(), key) == known.end())
      throw std::invalid_argument(
          fmt::format("unknown option '{}' for cycle {} (known: {})", key, cycle, fmt::join(known, ", ")));
}

OptionTable& OptionTable::on(const std::string& key, Reader read) {
  readers_.emplace_back(key, std::move(read));
  return *this;
}

OptionTable& OptionTable::number(const std::string& key, double* to) {
  return on(key, [to](const std::string& k, const std::string& v) { *to = parseNumber(k, v); });
}

OptionTable& OptionTable::list(const std::string& key, std::vector<double>* to) {
  return on(key, [to](const std::string& k, const std::string& v) { *to = parseNumberList(k, v); });
}

OptionTable& OptionTable::vec3(const std::string& key, Eigen::Vector3d* to) {
  return on(key, [to](const std::string& k, const std::string& v) { *to = parseVec3Option(k, v); });
}

OptionTable& OptionTable::count(const std::string& key, int* to, int lo, int hi) {
  return on(key, [to, lo, hi](const std::string& k, const std::string& v) { *to = parseCountOption(k, v, lo, hi); });
}

OptionTable& OptionTable::text(const std::string& key, std::string* to) {
  return on(key, [to](const std::string&, const std::string& v) { *to = v; });
}

std::vector<std::string> OptionTable::keys() const {
  std::vector<std::string> k;
  for (const auto& r : readers_) k.push_back(r.first);
  return k;
}

void OptionTable::read(const CycleOptions& options) const {
  requireKnownOptions(cycle_, options, keys());
  for (const auto& [key, value] : options)
    for (const auto& [k, read] : readers_)
      if (k == key) read(key, value);
}

}  // namespace rotacal
