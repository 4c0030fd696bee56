#pragma once
// Reading and writing rotacal's JSON files (MACHINE, PLAN, TRUTH, REPORT): parse errors and
// missing, ill-typed or out-of-range fields become InputError with the file and the line of the
// offending value (found by its place in the document, not by the first key of that name).
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rotacal {

using Json = nlohmann::json;

struct JsonDoc {
  Json value;
  std::string file;
  std::string text;

  /// Line (1-based) of the first occurrence of "key" anywhere in the text; 1 when not found.
  /// Ambiguous in any file that repeats a key: prefer lineOf(parent, key).
  int lineOf(std::string_view key) const;
  /// Line of parent[key] (of parent itself when key is empty or absent), parent being a node of
  /// `value`; when parent is not part of this document, the first occurrence of key.
  int lineOf(const Json& parent, std::string_view key) const;
  [[noreturn]] void fail(std::string_view key, const std::string& what) const;
  [[noreturn]] void fail(const Json& parent, std::string_view key, const std::string& what) const;
};

std::string readTextFile(const std::string& path);
JsonDoc readJsonFile(const std::string& path);
JsonDoc parseJsonText(std::string text, std::string file);

/// Runs a loader over `doc` and turns what nlohmann throws for an access the loader did not
/// guard (a field of the wrong type deep in a structure) into InputError naming the file.
template <class F>
auto guardJson(const JsonDoc& doc, F&& load) -> decltype(load());

/// Writes text to path atomically: a temporary file in the same directory, then rename. An
/// existing file is kept as path + ".bak" (never overwrite a user's file without a copy).
void writeFileAtomic(const std::string& path, const std::string& text);

/// Writes (path, text) pairs together or not at all: every target is checked (its directory
/// exists and is writable, it is not a directory or a device), every text written to a
/// temporary file beside its target, then all are renamed into place. On any failure the
/// temporary files are removed and every file that existed is left as it was (a target already
/// renamed is put back); InputError names the target. Replaced files are kept as FILE.bak,
/// the earlier .bak being replaced only once all targets are in place.
void writeFilesTogether(const std::vector<std::pair<std::string, std::string>>& files);

/// The interval a number read from a file must lie in. Every number must also be finite.
struct Limits {
  double lo = -std::numeric_limits<double>::max();
  double hi = std::numeric_limits<double>::max();
  bool lo_open = false;  // lo itself excluded
  std::string_view unit;

  static Limits any(std::string_view unit = {}) {
    return {-std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), false, unit};
  }
  static Limits positive(double hi, std::string_view unit = {}) { return {0.0, hi, true, unit}; }
  static Limits nonNegative(double hi, std::string_view unit = {}) { return {0.0, hi, false, unit}; }
  static Limits symmetric(double max_abs, std::string_view unit = {}) { return {-max_abs, max_abs, false, unit}; }
  bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && v <= hi; }
  std::string describe() const;
};

/// Typed access with a precise error: doc.fail(obj, key, ...) when missing, of the wrong type,
/// not finite or outside the limits. `obj` must be a node of doc.value (an object, else it
/// fails too).
double requireNumber(const JsonDoc& doc, const Json& obj, std::string_view key, const Limits& limits = Limits::any());
double numberOr(const JsonDoc& doc, const Json& obj, std::string_view key, double fallback,
                const Limits& limits = Limits::any());
/// A whole number (3 or 3.0) within [lo, hi].
int requireInt(const JsonDoc& doc, const Json& obj, std::string_view key, int lo, int hi);
int intOr(const JsonDoc& doc, const Json& obj, std::string_view key, int fallback, int lo, int hi);
std::string requireString(const JsonDoc& doc, const Json& obj, std::string_view key);
std::string stringOr(const JsonDoc& doc, const Json& obj, std::string_view key, const std::string& fallback);
bool boolOr(const JsonDoc& doc, const Json& obj, std::string_view key, bool fallback);
/// obj[key], which must be an object (an array for requireArray).
const Json& requireObject(const JsonDoc& doc, const Json& obj, std::string_view key);
const Json& requireArray(const JsonDoc& doc, const Json& obj, std::string_view key);
/// Checks a number that is already in hand (an array element, a computed value) against the
/// limits, failing at obj[key].
double checkNumber(const JsonDoc& doc, const Json& obj, std::string_view key, double v, const Limits& limits);
/// obj[key] as [x, y, z], each number within the limits.
Eigen::Vector3d requireVec3(const JsonDoc& doc, const Json& obj, const char* key, const Limits& limits);

template <class F>
auto guardJson(const JsonDoc& doc, F&& load) -> decltype(load()) {
  try {
    return load();
  } catch (const Json::exception& e) {
    std::string msg = e.what();
    // "[json.exception.type_error.302] type must be string, but is number": keep the reason.
    const auto close = msg.find("] ");
    if (close != std::string::npos) msg = msg.substr(close + 2);
    doc.fail(doc.value, "", "unexpected JSON structure: " + msg);
  }
}

}  // namespace rotacal
