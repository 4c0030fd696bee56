#pragma once
// The answer a calibration engineer reads first: per identified parameter, with its expanded
// uncertainty U, whether to adjust the machine, and the decision against a tolerance by ISO
// 14253-1 (conformance proven where |value| + U <= T, non-conformance where |value| - U > T,
// undecided between). A value within its own U is not significant: the data do not tell it from
// zero, and the machine is left as it is.
#include <optional>
#include <string>
#include <string_view>

#include "core/json_io.hpp"

namespace rotacal {

/// Tolerances on the location errors: a length's (um) and an angle's (mdeg), either may be unset.
struct LocationTolerance {
  std::optional<double> length_um;
  std::optional<double> angle_mdeg;
  bool any() const { return length_um || angle_mdeg; }
};

enum class ParameterVerdict { NotSignificant, WithinTolerance, Adjust, Undecided, Significant };
std::string_view verdictText(ParameterVerdict v);  // "not significant: leave as is", "adjust", ...

/// The decision for one value with its U (same unit), against `tolerance` when given.
ParameterVerdict decide(double value, double U, std::optional<double> tolerance);

/// REPORT.json's "verdict" block from its "location_errors" (each with value, U, unit: um or
/// mdeg): per parameter its verdict, the rule and the tolerance, and a one-line summary. Null when
/// the report has no location errors with U.
Json verdictJson(const Json& location_errors, const LocationTolerance& tolerance);

/// The block's readable form, the first lines of the text report.
std::string verdictText(const Json& verdict);

}  // namespace rotacal
