#pragma once
// Where a command's documents go. Every file a command writes passes through one OutputSet:
// collected first, written together or not at all (writeFilesTogether: temporary files, then
// renames, the old versions kept as .bak), so that a failure on the third output leaves the
// first two as they were. `--json -` sends a document to stdout so that a pipeline can read it
// (the readable summary then stays off stdout); stdout is written only after the files.
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "cli/command.hpp"
#include "core/json_io.hpp"
#include "core/limits.hpp"
#include "report/html_report.hpp"

namespace rotacal {

/// Now (s since 1970, UTC), or SOURCE_DATE_EPOCH when it is set (reproducible outputs: the
/// convention of reproducible-builds.org), for the dates documents record.
inline double nowUnixS() {
  if (const char* e = std::getenv("SOURCE_DATE_EPOCH")) {
    char* end = nullptr;
    const long long v = std::strtoll(e, &end, 10);
    if (end != e && *end == '\0' && v >= 0) return static_cast<double>(v);
  }
  return static_cast<double>(std::time(nullptr));
}

class OutputSet {
 public:
  /// `inputs`: the files the command reads; no output may replace one of them.
  explicit OutputSet(std::vector<std::string> inputs = {}) : inputs_(std::move(inputs)) {}

  /// Queues `text` for the output `option` at `path` ("-": stdout; empty: not asked for,
  /// skipped). A path given to two outputs, or naming an input, is a usage error
  /// (CLI::ValidationError), raised here, before anything is written.
  void add(const std::string& option, const std::string& path, std::string text) {
    if (path.empty()) return;
    for (const auto& o : outputs_)
      if (samePath(o.path, path))
        throw CLI::ValidationError(option, "'" + path + "' is also the output of " + o.option +
                                               ": each output needs its own file");
    if (path != "-")
      for (const auto& in : inputs_)
        if (samePath(in, path))
          throw CLI::ValidationError(option, "'" + path + "' is an input of this command: it would be overwritten");
    outputs_.push_back({option, path, std::move(text)});
  }

  /// Writes every queued output; on failure none is (InputError naming the target).
  void commit() {
    std::vector<std::pair<std::string, std::string>> files;
    for (const auto& o : outputs_)
      if (o.path != "-") files.emplace_back(o.path, o.text);
    writeFilesTogether(files);
    for (const auto& o : outputs_)
      if (o.path == "-") {
        std::fwrite(o.text.data(), 1, o.text.size(), stdout);
        std::fflush(stdout);
      }
    outputs_.clear();
  }

  bool toStdout() const {
    for (const auto& o : outputs_)
      if (o.path == "-") return true;
    return false;
  }

  /// Both name the same file: "-" only matches "-"; otherwise the same place after resolving
  /// "." / ".." and symbolic links, or the same existing file (a hard link).
  static bool samePath(const std::string& a, const std::string& b) {
    namespace fs = std::filesystem;
    if (a == "-" || b == "-") return a == b;
    std::error_code ea, eb;
    const fs::path ca = fs::weakly_canonical(fs::absolute(a), ea), cb = fs::weakly_canonical(fs::absolute(b), eb);
    if (!ea && !eb && ca == cb) return true;
    std::error_code ec;
    return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
  }

 private:
  struct Output {
    std::string option, path, text;
  };
  std::vector<std::string> inputs_;
  std::vector<Output> outputs_;
};

/// The usage errors of a command's outputs, checked before its work starts (a long Monte Carlo
/// should not end in "--json and --text name the same file"): (option, path) pairs.
inline void checkOutputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                         const std::vector<std::string>& inputs) {
  OutputSet probe(inputs);
  for (const auto& [option, path] : outputs) probe.add(option, path, {});
}

/// The HTML page drawn from a document, queued as the output `--html`.
inline void addHtml(OutputSet& out, const std::string& path, const Json& doc) {
  if (path.empty()) return;
  std::string html;
  try {
    html = report::reportHtml(doc);
  } catch (const std::invalid_argument& e) {
    failFile(path, std::string("cannot draw the report: ") + e.what());
  }
  out.add("--html", path, std::move(html));
}

/// The summary goes to stdout unless quiet or stdout carries a document.
inline void sayUnlessPiped(const Common& c, const std::string& text, const std::string& json_out,
                           const std::string& html_out = "") {
  if (json_out == "-" || html_out == "-") return;
  say(c, text);
}

/// Everything an analysis or a diagnosis hands the user: the JSON document (file or stdout), the
/// HTML page drawn from it, and the readable summary (file and terminal), written together.
/// Empty paths are skipped.
inline void writeDocuments(const Common& c, const Json& doc, const std::string& text, const std::string& json_out,
                           const std::string& text_out, const std::string& html_out) {
  OutputSet out;
  out.add("--json", json_out, doc.dump(1) + "\n");
  addHtml(out, html_out, doc);
  out.add("--text", text_out, text);
  out.commit();
  sayUnlessPiped(c, text, json_out, html_out);
}

/// The results files of analyze / diagnose, read: each a distinct repeat. The same file given
/// twice (by any path) is a usage error; two files with identical content are refused as bad
/// input, since counting one measurement twice would shrink u by sqrt(2).
inline std::vector<std::string> readResultsFiles(const std::vector<std::string>& files) {
  if (files.size() > static_cast<size_t>(kMaxRepeats))
    throw CLI::ValidationError("--results", std::to_string(files.size()) + " files; at most " +
                                                std::to_string(kMaxRepeats) + " repeats are allowed");
  std::vector<std::string> texts;
  for (size_t i = 0; i < files.size(); ++i) {
    for (size_t k = 0; k < i; ++k)
      if (OutputSet::samePath(files[k], files[i]))
        throw CLI::ValidationError("--results", "'" + files[i] + "' is given twice (as '" + files[k] +
                                                    "'): each repeat must be its own measurement");
    texts.push_back(readTextFile(files[i]));
    for (size_t k = 0; k < i; ++k)
      if (texts[k] == texts[i])
        failFile(files[i], "identical to " + files[k] +
                               ": the same measurement given twice would count as two repeats (u too small by "
                               "sqrt(2)); give each repeat once");
  }
  return texts;
}

}  // namespace rotacal
