#pragma once
// The text of programs, results and offsets files, read and written the same way by every dialect:
// locale-independent fixed-point numbers (never "-0.000", never NaN), numbers parsed strictly
// (the whole token or nothing), lines whatever their line ends, tokens, and the case and
// printable-ASCII reductions the controls' character sets need.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rotacal::ctl {

/// `v` with `decimals` digits after the point, through fmt (locale-independent). Never "-0.000".
/// Throws std::invalid_argument for NaN or infinity (no NC text may contain them).
std::string fixed(double v, int decimals);
/// `v` with at most `decimals` digits, trailing zeros dropped, the point kept: 5 -> "5.",
/// 2.5 -> "2.5" (004 Table 1's "A5.", "F2.").
std::string trimmed(double v, int decimals);

struct TextLine {
  int number = 0;  // 1-based
  std::string text;
};
/// Lines of a text file; LF, CR LF and lone CR all end a line. A final line without an
/// end-of-line is kept.
std::vector<TextLine> splitLines(std::string_view text);

/// Whitespace-separated tokens (spaces and tabs; repeated separators collapse).
std::vector<std::string> tokens(std::string_view line);

std::string trim(std::string_view s);
/// Outside text (file and machine names) reduced to one line of printable ASCII: every other
/// byte (line ends, control characters, UTF-8) becomes a space, so it can never end a comment
/// line early and put the rest of a file name on an executable line of its own.
std::string printableLine(std::string_view text);
/// `text` split at blanks into pieces of at most `width` characters (a longer word is cut),
/// each trimmed; empty when `text` is blank.
std::vector<std::string> wrap(std::string_view text, size_t width);
std::string upper(std::string_view s);
std::string lower(std::string_view s);

/// A decimal number that is exactly the token: optional sign, digits, at most one '.', optional
/// exponent; finite. nullopt otherwise ("1.2.3", "12a", "nan", "").
std::optional<double> parseNumber(std::string_view token);
/// A non-negative integer made of digits only.
std::optional<long> parseDigits(std::string_view token);

}  // namespace rotacal::ctl
