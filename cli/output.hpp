#pragma once
// Where a command's documents go: a file (written whole through writeFileAtomic, the old one kept
// as .bak), or stdout for `--json -` so that a pipeline can read it (the readable summary then
// stays off stdout). The HTML report is drawn from the same JSON document.
#include <cstdio>
#include <string>

#include "cli/command.hpp"
#include "core/json_io.hpp"
#include "report/html_report.hpp"

namespace rotacal {

inline void writeOutput(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::fwrite(text.data(), 1, text.size(), stdout);
    std::fflush(stdout);
    return;
  }
  writeFileAtomic(path, text);
}

inline void writeHtml(const std::string& path, const Json& doc) {
  if (path.empty()) return;
  std::string html;
  try {
    html = report::reportHtml(doc);
  } catch (const std::invalid_argument& e) {
    failFile(path, std::string("cannot draw the report: ") + e.what());
  }
  writeOutput(path, html);
}

/// The summary goes to stdout unless quiet or stdout carries a document.
inline void sayUnlessPiped(const Common& c, const std::string& text, const std::string& json_out,
                           const std::string& html_out = "") {
  if (json_out == "-" || html_out == "-") return;
  say(c, text);
}

/// Everything an analysis or a diagnosis hands the user: the JSON document (file or stdout), the
/// HTML page drawn from it, and the readable summary (file and terminal). Empty paths are skipped.
inline void writeDocuments(const Common& c, const Json& doc, const std::string& text, const std::string& json_out,
                           const std::string& text_out, const std::string& html_out) {
  if (!json_out.empty()) writeOutput(json_out, doc.dump(1) + "\n");
  writeHtml(html_out, doc);
  if (!text_out.empty()) writeFileAtomic(text_out, text);
  sayUnlessPiped(c, text, json_out, html_out);
}

}  // namespace rotacal
