#pragma once
// The HTML report: one self-contained page (inline CSS, inline SVG, one small inline
// script for the magnification choice; no network, no external fonts or scripts) drawn from the
// content of REPORT.json (analyze), DIAGNOSIS.json (diagnose) or a history trend
// (rotacal-history/1). Every `figures` entry of the document is drawn generically.
#include <string>

#include "core/json_io.hpp"

namespace rotacal::report {

/// The page for a document of format rotacal-report/1, rotacal-diagnosis/1 or rotacal-history/1
/// (any other format: its figures only). Throws std::invalid_argument on a malformed figure.
std::string reportHtml(const Json& doc);

}  // namespace rotacal::report
