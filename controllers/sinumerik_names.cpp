#include "controllers/sinumerik_names.hpp"

#include <array>
#include <cctype>
#include <vector>

#include <fmt/format.h>

#include "controllers/text.hpp"

namespace rotacal::ctl {
namespace {

struct Name {
  std::string_view name;
  std::string_view what;
};

// What changes the meaning of the coordinates after it (Siemens programming manual, "Frames",
// "Transformations", "Swivel - CYCLE800", "Tool carrier"); the verifier follows plain program
// coordinates only.
constexpr std::array kFrameChanges{
    Name{"TRAORI", "five-axis transformation: tool-centre-point control"},
    Name{"TRANSMIT", "face-end transformation"},
    Name{"TRACYL", "cylinder-surface transformation"},
    Name{"TRAANG", "inclined-axis transformation"},
    Name{"TRACON", "chained transformation"},
    Name{"CYCLE800", "swivel cycle: a tilted work plane"},
    Name{"TCARR", "orientable tool carrier"},
    Name{"TCOFR", "tool length along the active frame"},
    Name{"TOFRAME", "frame along the tool"},
    Name{"TOROT", "frame rotated to the tool"},
    Name{"PAROT", "frame rotated to the workpiece"},
    Name{"ROT", "programmable frame rotation"},
    Name{"AROT", "programmable frame rotation"},
    Name{"RPL", "programmable frame rotation in the plane"},
    Name{"TRANS", "programmable frame shift"},
    Name{"ATRANS", "programmable frame shift"},
    Name{"SCALE", "programmable frame scale"},
    Name{"ASCALE", "programmable frame scale"},
    Name{"MIRROR", "programmable frame mirror"},
    Name{"AMIRROR", "programmable frame mirror"},
    Name{"SUPA", "work offsets suppressed: machine coordinates"},
};

// Settings that move nothing and leave the coordinates' meaning alone: path control, feed and
// orientation modes, the transformation switched off. They are read as if absent.
constexpr std::array<std::string_view, 26> kSettings{
    "TRAFOOF", "SOFT",    "BRISK",    "DRIVE",    "FFWON",  "FFWOF", "CFTCP",  "CFC",   "CFIN",
    "ORIWKS",  "ORIMKS",  "ORIAXES",  "ORIVECT",  "ORIEULER", "ORIRPY", "UPATH", "SPATH", "COMPOF",
    "COMPON",  "COMPCURV", "COMPCAD", "FNORM",    "FLIN",   "FCUB",  "DIAMOF", "TCOABS",
};

// Calls the control executes without moving an axis: messages, alarms, file output, and the
// high-speed cycle's tolerances.
constexpr std::array<std::string_view, 6> kQuietCalls{"WRITE", "MSG", "SETAL", "CYCLE832", "SPRINT", "PUT"};

bool isNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '$'; }

struct Token {
  size_t begin, end;  // [begin, end) in the upper-case code
  std::string text;
};

/// The names of the block outside strings: runs of letters, digits, '_' and '$' whose first two
/// characters are not a letter and a digit or sign (X10, G0, N20, R90 are words, not names).
std::vector<Token> names(const std::string& u) {
  std::vector<Token> out;
  bool quote = false;
  for (size_t i = 0; i < u.size();) {
    if (u[i] == '"') quote = !quote;
    if (quote || !isNameChar(u[i]) || std::isdigit(static_cast<unsigned char>(u[i]))) {
      ++i;
      continue;
    }
    size_t k = i;
    while (k < u.size() && isNameChar(u[k])) ++k;
    const std::string t = u.substr(i, k - i);
    const bool word = t.size() == 1 || std::isdigit(static_cast<unsigned char>(t[1]));
    if (!word) out.push_back({i, k, t});
    i = k;
  }
  return out;
}

template <class List>
bool listed(const List& list, std::string_view name) {
  for (const auto& n : list)
    if (n == name) return true;
  return false;
}

}  // namespace

std::optional<std::string> sinumerikFrameChange(std::string_view code) {
  for (const Token& t : names(upper(code)))
    for (const Name& n : kFrameChanges)
      if (t.text == n.name) return fmt::format("{} ({})", n.name, n.what);
  return std::nullopt;
}

namespace {

bool isNumberChar(char c) { return std::isdigit(static_cast<unsigned char>(c)) || c == '.'; }

/// The length of a plain number at u[i] ([-+]digits[.digits] or [-+].digits), 0 when none.
size_t plainNumber(const std::string& u, size_t i) {
  size_t k = i;
  if (k < u.size() && (u[k] == '-' || u[k] == '+')) ++k;
  const size_t digits = k;
  bool point = false;
  while (k < u.size() && isNumberChar(u[k])) {
    if (u[k] == '.') {
      if (point) return 0;
      point = true;
    }
    ++k;
  }
  if (k == digits || (k == digits + 1 && point)) return 0;
  return k - i;
}

}  // namespace

SinumerikBlock readSinumerikBlock(std::string_view code) {
  SinumerikBlock b;
  const std::string u = upper(code);
  // X=-10: the assignment form of an axis word, which the control needs for an expression and
  // accepts for a plain number. A plain number is the word itself; anything else is an
  // expression the verifier cannot evaluate. Scanned by hand: a block may be any length here
  // (the length check is the verifier's), and std::regex recurses per character.
  std::string words;
  for (size_t i = 0; i < u.size(); ++i) {
    const char c = u[i];
    const bool axis = std::string_view("XYZABCF").find(c) != std::string_view::npos && (i == 0 || !isNameChar(u[i - 1]));
    size_t eq = i + 1;
    while (axis && eq < u.size() && (u[eq] == ' ' || u[eq] == '\t')) ++eq;
    if (!axis || eq >= u.size() || u[eq] != '=') {
      words += c;
      continue;
    }
    size_t v = eq + 1;
    while (v < u.size() && (u[v] == ' ' || u[v] == '\t')) ++v;
    const size_t n = plainNumber(u, v);
    if (n == 0 || (v + n < u.size() && u[v + n] != ' ' && u[v + n] != '\t')) {
      size_t end = v;
      while (end < u.size() && u[end] != ' ' && u[end] != '\t' && end - v < 40) ++end;
      b.problem = fmt::format("{}={} is an expression or a parameter: rotacal needs literal coordinates", c,
                              u.substr(v, end - v));
      return b;
    }
    words += c;
    words += u.substr(v, n);
    i = v + n - 1;
  }
  std::string kept;
  size_t from = 0;
  for (const Token& t : names(words)) {
    if (listed(kSettings, t.text) || listed(kQuietCalls, t.text)) {
      kept += words.substr(from, t.begin - from);
      b.settings += (b.settings.empty() ? "" : " ") + t.text;
      from = t.end;
      continue;
    }
    b.problem = fmt::format("{}: a name rotacal does not know (a subprogram, a cycle, a variable or a keyword of the "
                            "control): it cannot follow this block",
                            t.text);
    return b;
  }
  kept += words.substr(from);
  b.code = trim(kept);
  return b;
}

}  // namespace rotacal::ctl
