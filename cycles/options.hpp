#pragma once
// The one rule for a cycle's plan options: every key a cycle knows has its reader, and any other
// key is refused with the list of the known keys, drawn from the same table. (When each cycle
// wrote its own list beside its readers, two of the lists lost keys their cycle read: three
// frame options of the space-frame map and the start angle of the fixed-tool-tip test.)
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/probe_plan.hpp"

namespace rotacal {

/// A plan option "x,y,z" (mm). Throws std::invalid_argument naming the option.
Eigen::Vector3d parseVec3Option(const std::string& key, const std::string& text);

/// A whole-number plan option from lo to hi. Throws std::invalid_argument naming the option.
int parseCountOption(const std::string& key, const std::string& text, int lo, int hi);

/// A list option "a,b,c" as parseNumberList reads it back ({:g} each).
std::string numberListOption(const std::vector<double>& values);

/// Throws std::invalid_argument "unknown option 'k' for cycle <cycle> (known: a, b, c)" for the
/// first option (in key order) whose key is not in `known`.
void requireKnownOptions(std::string_view cycle, const CycleOptions& options, const std::vector<std::string>& known);

/// A cycle's options, each key with where its value goes. read() takes the options in key order
/// and throws std::invalid_argument at the first unknown key or unreadable value, naming it.
class OptionTable {
 public:
  using Reader = std::function<void(const std::string& key, const std::string& value)>;
  explicit OptionTable(std::string cycle) : cycle_(std::move(cycle)) {}
  OptionTable& on(const std::string& key, Reader read);
  OptionTable& number(const std::string& key, double* to);
  OptionTable& list(const std::string& key, std::vector<double>* to);
  OptionTable& vec3(const std::string& key, Eigen::Vector3d* to);
  OptionTable& count(const std::string& key, int* to, int lo, int hi);
  OptionTable& text(const std::string& key, std::string* to);
  std::vector<std::string> keys() const;
  void read(const CycleOptions& options) const;

 private:
  std::string cycle_;
  std::vector<std::pair<std::string, Reader>> readers_;
};

}  // namespace rotacal
