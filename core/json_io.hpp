#pragma once
// Reading and writing rotacal's JSON files (MACHINE, PLAN, TRUTH, REPORT): parse errors and
// missing or ill-typed fields become InputError with the file and the line of the offending key.
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace rotacal {

using Json = nlohmann::json;

struct JsonDoc {
  Json value;
  std::string file;
  std::string text;

  /// Line (1-based) of the first occurrence of "key" in the text; 1 when not found.
  int lineOf(std::string_view key) const;
  [[noreturn]] void fail(std::string_view key, const std::string& what) const;
};

std::string readTextFile(const std::string& path);
JsonDoc readJsonFile(const std::string& path);
JsonDoc parseJsonText(std::string text, std::string file);

/// Writes text to path atomically: a temporary file in the same directory, then rename. An
/// existing file is kept as path + ".bak" (never overwrite a user's file without a copy).
void writeFileAtomic(const std::string& path, const std::string& text);

/// Typed access with a precise error: doc.fail(key, ...) when missing or of the wrong type.
double requireNumber(const JsonDoc& doc, const Json& obj, std::string_view key);
double numberOr(const JsonDoc& doc, const Json& obj, std::string_view key, double fallback);
std::string requireString(const JsonDoc& doc, const Json& obj, std::string_view key);

}  // namespace rotacal
