#include "core/json_io.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/errors.hpp"

namespace rotacal {

int JsonDoc::lineOf(std::string_view key) const {
  const std::string quoted = "\"" + std::string(key) + "\"";
  const auto pos = text.find(quoted);
  if (pos == std::string::npos) return 1;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(pos), '\n'));
}

void JsonDoc::fail(std::string_view key, const std::string& what) const {
  throw InputError(file, lineOf(key), what);
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

JsonDoc parseJsonText(std::string text, std::string file) {
  JsonDoc doc;
  doc.file = std::move(file);
  doc.text = std::move(text);
  try {
    doc.value = Json::parse(doc.text);
  } catch (const Json::parse_error& e) {
    const size_t byte = std::min(e.byte, doc.text.size());
    const int line =
        1 + static_cast<int>(std::count(doc.text.begin(), doc.text.begin() + static_cast<long>(byte), '\n'));
    std::string msg = e.what();
    const auto p = msg.find("parse error");
    throw InputError(doc.file, line, "invalid JSON: " + (p == std::string::npos ? msg : msg.substr(p)));
  }
  return doc;
}

JsonDoc readJsonFile(const std::string& path) { return parseJsonText(readTextFile(path), path); }

void writeFileAtomic(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::random_device rd;
  const fs::path tmp = dir / ("." + target.filename().string() + ".tmp" + std::to_string(rd()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, 0, "cannot write (directory missing or not writable)");
    out << text;
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw InputError(path, 0, "write failed");
    }
  }
  std::error_code ec;
  if (fs::exists(target, ec)) {
    fs::path bak = target;
    bak += ".bak";
    fs::copy_file(target, bak, fs::copy_options::overwrite_existing, ec);
    if (ec) {
      fs::remove(tmp, ec);
      throw InputError(path, 0, "cannot keep the previous version as " + bak.string());
    }
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(path, 0, "cannot rename the temporary file into place");
  }
}

double requireNumber(const JsonDoc& doc, const Json& obj, std::string_view key) {
  const auto it = obj.find(std::string(key));
  if (it == obj.end()) doc.fail(key, "missing field '" + std::string(key) + "'");
  if (!it->is_number()) doc.fail(key, "field '" + std::string(key) + "' must be a number");
  return it->get<double>();
}

double numberOr(const JsonDoc& doc, const Json& obj, std::string_view key, double fallback) {
  const auto it = obj.find(std::string(key));
  if (it == obj.end()) return fallback;
  if (!it->is_number()) doc.fail(key, "field '" + std::string(key) + "' must be a number");
  return it->get<double>();
}

std::string requireString(const JsonDoc& doc, const Json& obj, std::string_view key) {
  const auto it = obj.find(std::string(key));
  if (it == obj.end()) doc.fail(key, "missing field '" + std::string(key) + "'");
  if (!it->is_string()) doc.fail(key, "field '" + std::string(key) + "' must be a string");
  return it->get<std::string>();
}

}  // namespace rotacal
