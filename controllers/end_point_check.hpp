#pragma once
// The no-trigger check written after each probing move of the dialects whose move ends silently
// at its end point when nothing triggers: its statements written, and read back by the checkers,
// the motion reader and `rotacal compensate`, which must rewrite them with the end point.
#include <optional>
#include <string>
#include <string_view>

#include "controllers/dialect.hpp"

namespace rotacal::ctl {

/// The end-point statements of the no-trigger check of the dialects whose probing move ends
/// silently at its end point when nothing triggers (fanuc and haas G31, okuma G31, siemens
/// MEAS=1): right after the move, one statement per axis `<difference>=<measured>-<end>` with
/// the sign folded into the literal (`#1=#5061-51.0000`, `#2=#5062+235.0000`), then a test of
/// the distance between the probe's stop and the end point. An untriggered move stops exactly
/// at its end point, so the test guards only while these literals are the move's own end point:
/// whatever moves the end point (`rotacal compensate`) must rewrite them with it.
/// Its variables are the dialect's (DialectIdentity::end_point_check).
using rotacal::EndPointCheck;
/// The form of the dialect named `dialect`; nullopt where it has none (its identity) or no such
/// dialect exists.
std::optional<EndPointCheck> endPointCheck(std::string_view dialect);
/// The statement of `axis` (0..2) comparing with end point coordinate `end`, e.g.
/// "#2=#5062+235.0000".
std::string endPointCheckStatement(const EndPointCheck& form, int axis, double end, int decimals);
/// A statement of that form as written (blanks allowed around '=' and the sign; an optional
/// leading N word): its axis, the end point it compares with and that literal's decimals;
/// nullopt for anything else.
struct EndPointCheckStatement {
  int axis = 0;
  double end = 0.0;
  int decimals = 0;
};
std::optional<EndPointCheckStatement> parseEndPointCheckStatement(const EndPointCheck& form, std::string_view code);

}  // namespace rotacal::ctl
