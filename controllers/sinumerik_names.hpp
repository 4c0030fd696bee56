#pragma once
// The names of Sinumerik's language in a block (TRAORI, SOFT, CYCLE800(...), X=-10): what the
// program verifier and `compensate` make of a block of a program a user brings, where the
// word-address reader alone would read TRAORI as the words T, R, A, ... The language's own
// names are listed once here; anything else of two letters or more in a motion block is a name
// the verifier does not know, and it says so rather than guess.
#include <optional>
#include <string>
#include <string_view>

namespace rotacal::ctl {

/// The first name in `code` (outside strings) that changes what the program's coordinates mean:
/// a transformation (TRAORI, TRANSMIT, ...), a swivel or tool-carrier frame (CYCLE800, TCARR),
/// a programmable frame (ROT, TRANS, SCALE, MIRROR and their A forms) or SUPA, as
/// "NAME (what it does)"; nullopt when there is none.
std::optional<std::string> sinumerikFrameChange(std::string_view code);

/// A Sinumerik block (its code: the generic reader has taken a parenthesis for a comment, so a
/// call comes as its name) as the word-address reader can follow it: settings without motion
/// removed (SOFT, FFWON, TRAFOOF, CYCLE832, MSG, ...) and axis words written as assignments of a
/// plain number read as the word (X=-10 is X-10). `problem` names what cannot be followed: an axis
/// assigned an expression (A=DC(90), X=R1+5), a name rotacal does not know (a cycle's or a
/// subprogram's call, a variable). Frame changes are sinumerikFrameChange's.
struct SinumerikBlock {
  std::string code;      // upper case, what the word-address reader follows
  std::string settings;  // the settings read as absent, space-separated as written ("" when none)
  std::string problem;
};
SinumerikBlock readSinumerikBlock(std::string_view code);


}  // namespace rotacal::ctl
