#include "core/json_io.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <vector>

#include <fmt/format.h>
#include <unistd.h>

#include "core/errors.hpp"

namespace rotacal {

namespace {

int lineAt(const std::string& text, size_t pos) {
  pos = std::min(pos, text.size());
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(pos), '\n'));
}

// One step from a node to a child: an object member (key) or an array element (index).
struct Step {
  bool is_key = true;
  std::string key;
  size_t index = 0;
};

// The steps from `root` to the node at address `target`; false when it is not in the tree.
bool pathTo(const Json& root, const Json* target, std::vector<Step>& path) {
  if (&root == target) return true;
  if (root.is_object()) {
    for (auto it = root.begin(); it != root.end(); ++it) {
      path.push_back({true, it.key(), 0});
      if (pathTo(it.value(), target, path)) return true;
      path.pop_back();
    }
  } else if (root.is_array()) {
    for (size_t i = 0; i < root.size(); ++i) {
      path.push_back({false, {}, i});
      if (pathTo(root[i], target, path)) return true;
      path.pop_back();
    }
  }
  return false;
}

// A scan of JSON text that nlohmann has already accepted: finds where the value at a path
// starts. Keys are compared decoded (escapes included); of repeated keys the last one counts,
// as in the parsed document.
class Scanner {
 public:
  explicit Scanner(const std::string& t) : t_(t) {}

  // Position of the deepest step of `path` found: the key of an object member, the first
  // character of an array element, or the start of the document.
  size_t locate(const std::vector<Step>& path) {
    size_t at = skipWs(0);
    size_t value = at;
    for (const Step& s : path) {
      if (value >= t_.size()) break;
      size_t key_pos = 0, found = std::string::npos;
      if (s.is_key && t_[value] == '{') {
        size_t i = skipWs(value + 1);
        while (i < t_.size() && t_[i] == '"') {
          const size_t kstart = i;
          const size_t kend = skipString(i);
          const bool match = keyText(kstart, kend) == s.key;
          i = skipWs(kend);
          if (i < t_.size() && t_[i] == ':') i = skipWs(i + 1);
          if (match) {
            key_pos = kstart;
            found = i;
          }
          i = skipWs(skipValue(i));
          if (i < t_.size() && t_[i] == ',') i = skipWs(i + 1);
          else break;
        }
      } else if (!s.is_key && t_[value] == '[') {
        size_t i = skipWs(value + 1);
        for (size_t k = 0; i < t_.size() && t_[i] != ']'; ++k) {
          if (k == s.index) {
            key_pos = i;
            found = i;
            break;
          }
          i = skipWs(skipValue(i));
          if (i < t_.size() && t_[i] == ',') i = skipWs(i + 1);
          else break;
        }
      }
      if (found == std::string::npos) break;
      at = key_pos;
      value = found;
    }
    return at;
  }

  // Position of the first number whose magnitude overflows a double, or npos.
  size_t firstOverflow() const {
    for (size_t i = 0; i < t_.size();) {
      const char c = t_[i];
      if (c == '"') {
        i = skipString(i);
      } else if (c == '-' || (c >= '0' && c <= '9')) {
        size_t j = i + 1;
        while (j < t_.size() && std::strchr("0123456789.eE+-", t_[j]) != nullptr) ++j;
        const std::string num = t_.substr(i, j - i);
        if (!std::isfinite(std::strtod(num.c_str(), nullptr))) return i;
        i = j;
      } else {
        ++i;
      }
    }
    return std::string::npos;
  }

 private:
  size_t skipWs(size_t i) const {
    while (i < t_.size() && (t_[i] == ' ' || t_[i] == '\t' || t_[i] == '\n' || t_[i] == '\r')) ++i;
    return i;
  }
  // i at the opening quote; returns the position after the closing quote.
  size_t skipString(size_t i) const {
    ++i;
    while (i < t_.size() && t_[i] != '"') i += t_[i] == '\\' ? 2 : 1;
    return std::min(i + 1, t_.size());
  }
  size_t skipValue(size_t i) const {
    if (i >= t_.size()) return i;
    if (t_[i] == '"') return skipString(i);
    if (t_[i] == '{' || t_[i] == '[') {
      int depth = 0;
      while (i < t_.size()) {
        const char c = t_[i];
        if (c == '"') {
          i = skipString(i);
          continue;
        }
        if (c == '{' || c == '[') ++depth;
        if (c == '}' || c == ']') --depth;
        ++i;
        if (depth == 0) return i;
      }
      return i;
    }
    while (i < t_.size() && std::strchr(",}] \t\r\n", t_[i]) == nullptr) ++i;
    return i;
  }
  std::string keyText(size_t start, size_t end) const {
    const std::string raw = t_.substr(start, end - start);
    if (raw.find('\\') == std::string::npos) return raw.substr(1, raw.size() >= 2 ? raw.size() - 2 : 0);
    try {
      return Json::parse(raw).get<std::string>();
    } catch (const Json::exception&) {
      return raw;
    }
  }
  const std::string& t_;
};

std::string shortNumber(double v) { return fmt::format("{:g}", v); }

}  // namespace

int JsonDoc::lineOf(std::string_view key) const {
  const std::string quoted = "\"" + std::string(key) + "\"";
  const auto pos = text.find(quoted);
  if (pos == std::string::npos) return 1;
  return lineAt(text, pos);
}

int JsonDoc::lineOf(const Json& parent, std::string_view key) const {
  std::vector<Step> path;
  if (!pathTo(value, &parent, path)) return key.empty() ? 1 : lineOf(key);
  if (!key.empty() && parent.is_object() && parent.contains(std::string(key))) path.push_back({true, std::string(key), 0});
  return lineAt(text, Scanner(text).locate(path));
}

void JsonDoc::fail(std::string_view key, const std::string& what) const {
  throw InputError(file, lineOf(key), what);
}

void JsonDoc::fail(const Json& parent, std::string_view key, const std::string& what) const {
  throw InputError(file, lineOf(parent, key), what);
}

std::string Limits::describe() const {
  const std::string u = unit.empty() ? "" : " " + std::string(unit);
  const double big = std::numeric_limits<double>::max();
  if (lo == -hi && !lo_open) return fmt::format("within +-{}{}", shortNumber(hi), u);
  if (hi >= big) return fmt::format("{} {}{}", lo_open ? ">" : ">=", shortNumber(lo), u);
  return fmt::format("{} {} and <= {}{}", lo_open ? ">" : ">=", shortNumber(lo), shortNumber(hi), u);
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
  } catch (const Json::out_of_range&) {
    // nlohmann names the number but not where it is: a magnitude beyond a double (1e400).
    const size_t at = Scanner(doc.text).firstOverflow();
    throw InputError(doc.file, at == std::string::npos ? 1 : lineAt(doc.text, at),
                     "number too large for a double (beyond 1.8e308)");
  } catch (const Json::exception& e) {
    throw InputError(doc.file, 1, std::string("invalid JSON: ") + e.what());
  }
  return doc;
}

JsonDoc readJsonFile(const std::string& path) { return parseJsonText(readTextFile(path), path); }

void writeFileAtomic(const std::string& path, const std::string& text) { writeFilesTogether({{path, text}}); }

void writeFilesTogether(const std::vector<std::pair<std::string, std::string>>& files) {
  namespace fs = std::filesystem;
  struct Job {
    std::string path;
    fs::path target, tmp, saved;
    bool existed = false;
  };
  std::vector<Job> jobs;
  std::random_device rd;
  auto sibling = [&](const fs::path& target, const char* what) {
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    return dir / ("." + target.filename().string() + what + std::to_string(rd()));
  };
  auto discard = [&] {
    std::error_code ec;
    for (const auto& j : jobs) {
      if (!j.tmp.empty()) fs::remove(j.tmp, ec);
      if (!j.saved.empty()) fs::remove(j.saved, ec);
    }
  };

  // 1. Every target must be writable before anything is written.
  for (const auto& [path, text] : files) {
    (void)text;
    std::error_code ec;
    Job j;
    j.path = path;
    j.target = fs::path(path);
    const fs::path dir = j.target.has_parent_path() ? j.target.parent_path() : fs::path(".");
    if (j.target.filename().empty() || j.target.filename() == "." || j.target.filename() == "..")
      throw InputError(path, 0, "cannot write: not a file name");
    if (!fs::is_directory(dir, ec))
      throw InputError(path, 0, "cannot write: directory '" + dir.string() + "' does not exist");
    if (::access(dir.c_str(), W_OK) != 0)
      throw InputError(path, 0, "cannot write: directory '" + dir.string() + "' is not writable");
    const auto st = fs::status(j.target, ec);
    j.existed = fs::exists(st);
    // The rename that puts a new file in place would replace a device or a directory entry.
    if (j.existed && !fs::is_regular_file(st))
      throw InputError(path, 0, "cannot write: it exists and is not a regular file (use - for stdout)");
    fs::path bak = j.target;
    bak += ".bak";
    if (j.existed && fs::exists(bak, ec) && !fs::is_regular_file(bak, ec))
      throw InputError(path, 0, "cannot keep the previous version: " + bak.string() + " is not a regular file");
    jobs.push_back(j);
  }
  try {
    // 2. The new contents, each beside its target.
    for (size_t k = 0; k < files.size(); ++k) {
      Job& j = jobs[k];
      j.tmp = sibling(j.target, ".tmp");
      std::ofstream out(j.tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw InputError(j.path, 0, "cannot write (directory missing or not writable)");
      out << files[k].second;
      out.flush();
      if (!out) throw InputError(j.path, 0, "write failed (disk full?)");
    }
    // 3. A copy of each file about to be replaced: the rollback below, then FILE.bak.
    for (Job& j : jobs) {
      if (!j.existed) continue;
      std::error_code ec;
      j.saved = sibling(j.target, ".old");
      fs::copy_file(j.target, j.saved, fs::copy_options::overwrite_existing, ec);
      if (ec) throw InputError(j.path, 0, "cannot keep the previous version (" + ec.message() + ")");
    }
  } catch (...) {
    discard();
    throw;
  }
  // 4. Into place, all of them; on a failure the ones already placed are put back.
  for (size_t k = 0; k < jobs.size(); ++k) {
    std::error_code ec;
    fs::rename(jobs[k].tmp, jobs[k].target, ec);
    if (!ec) continue;
    for (size_t i = 0; i < k; ++i) {
      std::error_code ignore;
      if (jobs[i].existed) fs::rename(jobs[i].saved, jobs[i].target, ignore);
      else fs::remove(jobs[i].target, ignore);
      jobs[i].saved.clear();
      jobs[i].tmp.clear();
    }
    const std::string path = jobs[k].path;
    discard();
    throw InputError(path, 0, "cannot rename the temporary file into place (" + ec.message() + ")");
  }
  // 5. Only now, with every output in place, may earlier backups be replaced.
  for (const Job& j : jobs) {
    if (!j.existed) continue;
    std::error_code ec;
    fs::path bak = j.target;
    bak += ".bak";
    fs::rename(j.saved, bak, ec);
    if (ec) fs::remove(j.saved, ec);
  }
}

namespace {

const Json* member(const JsonDoc& doc, const Json& obj, std::string_view key) {
  if (!obj.is_object()) doc.fail(obj, "", "expected a JSON object holding '" + std::string(key) + "'");
  const auto it = obj.find(std::string(key));
  return it == obj.end() ? nullptr : &*it;
}

const Json& present(const JsonDoc& doc, const Json& obj, std::string_view key) {
  const Json* v = member(doc, obj, key);
  if (v == nullptr) doc.fail(obj, key, "missing field '" + std::string(key) + "'");
  return *v;
}

double numberFrom(const JsonDoc& doc, const Json& obj, std::string_view key, const Json& v, const Limits& limits) {
  if (!v.is_number()) doc.fail(obj, key, "field '" + std::string(key) + "' must be a number");
  return checkNumber(doc, obj, key, v.get<double>(), limits);
}

int intFrom(const JsonDoc& doc, const Json& obj, std::string_view key, const Json& v, int lo, int hi) {
  const double d = numberFrom(doc, obj, key, v, Limits::any());
  if (d != std::floor(d) || d < lo || d > hi)
    doc.fail(obj, key, fmt::format("field '{}' must be a whole number from {} to {} (got {})", key, lo, hi, shortNumber(d)));
  return static_cast<int>(d);
}

}  // namespace

Eigen::Vector3d requireVec3(const JsonDoc& doc, const Json& obj, const char* key, const Limits& limits) {
  const Json& a = requireArray(doc, obj, key);
  if (a.size() != 3) doc.fail(obj, key, std::string("field '") + key + "' must be [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!a[i].is_number()) doc.fail(obj, key, std::string("field '") + key + "' must hold numbers");
    v[i] = checkNumber(doc, obj, key, a[i].get<double>(), limits);
  }
  return v;
}

double checkNumber(const JsonDoc& doc, const Json& obj, std::string_view key, double v, const Limits& limits) {
  if (!std::isfinite(v)) doc.fail(obj, key, "field '" + std::string(key) + "' must be a finite number");
  if (!limits.contains(v))
    doc.fail(obj, key, fmt::format("field '{}' must be {} (got {})", key, limits.describe(), shortNumber(v)));
  return v;
}

double requireNumber(const JsonDoc& doc, const Json& obj, std::string_view key, const Limits& limits) {
  return numberFrom(doc, obj, key, present(doc, obj, key), limits);
}

double numberOr(const JsonDoc& doc, const Json& obj, std::string_view key, double fallback, const Limits& limits) {
  const Json* v = member(doc, obj, key);
  return v == nullptr ? fallback : numberFrom(doc, obj, key, *v, limits);
}

int requireInt(const JsonDoc& doc, const Json& obj, std::string_view key, int lo, int hi) {
  return intFrom(doc, obj, key, present(doc, obj, key), lo, hi);
}

int intOr(const JsonDoc& doc, const Json& obj, std::string_view key, int fallback, int lo, int hi) {
  const Json* v = member(doc, obj, key);
  return v == nullptr ? fallback : intFrom(doc, obj, key, *v, lo, hi);
}

std::string requireString(const JsonDoc& doc, const Json& obj, std::string_view key) {
  const Json& v = present(doc, obj, key);
  if (!v.is_string()) doc.fail(obj, key, "field '" + std::string(key) + "' must be a string");
  return v.get<std::string>();
}

std::string stringOr(const JsonDoc& doc, const Json& obj, std::string_view key, const std::string& fallback) {
  const Json* v = member(doc, obj, key);
  if (v == nullptr) return fallback;
  if (!v->is_string()) doc.fail(obj, key, "field '" + std::string(key) + "' must be a string");
  return v->get<std::string>();
}

bool boolOr(const JsonDoc& doc, const Json& obj, std::string_view key, bool fallback) {
  const Json* v = member(doc, obj, key);
  if (v == nullptr) return fallback;
  if (!v->is_boolean()) doc.fail(obj, key, "field '" + std::string(key) + "' must be true or false");
  return v->get<bool>();
}

const Json& requireObject(const JsonDoc& doc, const Json& obj, std::string_view key) {
  const Json& v = present(doc, obj, key);
  if (!v.is_object()) doc.fail(obj, key, "field '" + std::string(key) + "' must be an object {...}");
  return v;
}

const Json& requireArray(const JsonDoc& doc, const Json& obj, std::string_view key) {
  const Json& v = present(doc, obj, key);
  if (!v.is_array()) doc.fail(obj, key, "field '" + std::string(key) + "' must be an array [...]");
  return v;
}

}  // namespace rotacal
