#pragma once
// Times as documents record them: Unix seconds <-> ISO 8601 UTC ("2026-11-25T19:46:44Z"; a date
// alone is midnight UTC). One reading for the history's calibrations and the reports' dates.
#include <string>

namespace rotacal {

/// Throws std::invalid_argument on anything else, including dates that do not exist
/// (2024-02-30, 2023-02-29) and years outside 1970..9999.
double parseIsoTime(const std::string& text);
std::string isoTime(double unix_s);

}  // namespace rotacal
