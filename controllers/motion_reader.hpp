#pragma once
// Reads a generated (or compensated) program back into neutral motions (gcode/motion.hpp) for
// the program verifier: one reader for the word-address languages (gcode/reader.hpp's blocks plus
// each dialect's probing words and no-trigger checks) and one for Heidenhain Klartext, chosen by
// the dialect's ProgramLanguage. A free function keyed on the dialect's name rather than a new
// virtual of Dialect: the dialects of one language share one implementation.
#include <string>
#include <string_view>
#include <vector>

#include "gcode/motion.hpp"

namespace rotacal::ctl {

/// The motions of `text` in the order the control meets them, up to and including the end of
/// the main program. Blocks the reader cannot follow come back as Motion::Kind::Unreadable with
/// their line and why (they are violations for the checker). Throws std::invalid_argument for a
/// dialect without programs (csv) or an unknown one.
std::vector<nc::Motion> readMotions(std::string_view dialect, const std::string& text);

/// Whether a line of the richer dialects is a statement, not a word-address block: an assignment
/// to a named variable (R90=, VC1=, TXT=, $TC_CARR1=), a call or keyword (WRITE(, MSG(, DEF,
/// GOTOF, PUT, FWRITC, ...; IF too when `if_is_statement`), or a label (NOHIT1:). An assignment
/// to an axis letter (X=10, Siemens) is a motion, never a statement.
bool isStatement(const std::string& code, bool if_is_statement);

/// Whether the dialect's programs carry a program number (O word; Dialect::numbersPrograms), false
/// for a name no dialect has.
bool numbersPrograms(std::string_view dialect);

}  // namespace rotacal::ctl
