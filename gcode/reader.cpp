#include "gcode/reader.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <string_view>

namespace rotacal::nc {
namespace {

bool isSpace(char c) { return c == ' ' || c == '\t'; }
bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isAlpha(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
char up(char c) { return static_cast<char>(std::toupper(static_cast<unsigned char>(c))); }

std::string upper(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = up(c);
  return r;
}

std::string trim(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && isSpace(s[b])) ++b;
  while (e > b && isSpace(s[e - 1])) --e;
  return std::string(s.substr(b, e - b));
}

/// A literal number: optional sign, digits with at most one '.', at least one digit.
std::optional<double> literal(std::string_view t) {
  if (t.empty()) return std::nullopt;
  size_t i = 0;
  if (t[0] == '+' || t[0] == '-') i = 1;
  int digits = 0, points = 0;
  for (size_t k = i; k < t.size(); ++k) {
    if (isDigit(t[k])) ++digits;
    else if (t[k] == '.') ++points;
    else return std::nullopt;
  }
  if (digits == 0 || points > 1) return std::nullopt;
  double v = 0.0;
  const char* first = t.data() + i;
  const char* last = t.data() + t.size();
  const auto r = std::from_chars(first, last, v);
  if (r.ec != std::errc() || r.ptr != last || !std::isfinite(v)) return std::nullopt;
  return t[0] == '-' ? -v : v;
}

/// Reads a balanced [ ... ] starting at s[i] == '['; returns the end index (one past ']'), or
/// s.size() when it is not closed.
size_t bracketEnd(std::string_view s, size_t i) {
  int depth = 0;
  for (; i < s.size(); ++i) {
    if (s[i] == '[') ++depth;
    else if (s[i] == ']' && --depth == 0) return i + 1;
  }
  return s.size();
}

const char* const kOwordKeywords[] = {"IF",  "ELSEIF", "ELSE",   "ENDIF",  "WHILE",  "ENDWHILE", "DO",      "REPEAT",
                                      "ENDREPEAT", "SUB", "ENDSUB", "CALL", "RETURN", "BREAK",    "CONTINUE"};

/// Fills the control fields when `rest` (code after an optional N word) is a control statement.
bool detectControl(std::string_view rest, Block& b) {
  const std::string u = upper(rest);
  if (u.empty()) return false;
  if (u[0] == '#') {
    b.keyword = "#";
    return true;
  }
  auto startsWord = [&](std::string_view kw) {
    return u.compare(0, kw.size(), kw) == 0 && (u.size() == kw.size() || !isAlpha(u[kw.size()]));
  };
  // Fanuc macro statements and output commands.
  for (const char* kw : {"IF", "GOTO", "WHILE", "DPRNT", "BPRNT", "POPEN", "PCLOS"}) {
    if (startsWord(kw)) {
      b.keyword = kw;
      return true;
    }
  }
  if (u.size() > 3 && u.compare(0, 3, "END") == 0 && isDigit(u[3])) {
    b.keyword = "END";
    return true;
  }
  if (u.size() > 2 && u.compare(0, 2, "DO") == 0 && isDigit(u[2])) {
    b.keyword = "DO";
    return true;
  }
  // LinuxCNC o-word: o<digits> or o<name>, then a keyword.
  if (u[0] == 'O') {
    size_t i = 1;
    while (i < u.size() && isSpace(u[i])) ++i;
    const size_t name_begin = i;
    if (i < u.size() && u[i] == '<') {
      const size_t close = u.find('>', i);
      if (close == std::string::npos) return false;
      i = close + 1;
    } else {
      while (i < u.size() && isDigit(u[i])) ++i;
    }
    if (i == name_begin) return false;
    const std::string name = trim(rest.substr(name_begin, i - name_begin));
    while (i < u.size() && isSpace(u[i])) ++i;
    size_t k = i;
    while (k < u.size() && isAlpha(u[k])) ++k;
    const std::string kw = u.substr(i, k - i);
    if (kw.empty()) return false;  // Fanuc program number O1234
    for (const char* known : kOwordKeywords) {
      if (kw == known) {
        b.keyword = kw;
        b.oword = name;
        return true;
      }
    }
    b.keyword = kw;  // unknown o-word keyword: still a control block, flagged
    b.oword = name;
    b.issues.push_back("unknown o-word keyword '" + kw + "'");
    return true;
  }
  return false;
}

void readWords(std::string_view s, Block& b) {
  size_t i = 0;
  while (i < s.size()) {
    if (isSpace(s[i])) {
      ++i;
      continue;
    }
    if (!isAlpha(s[i])) {
      {
        // Shown as itself when printable, else as \xNN: a NUL or a line end never reaches a message.
        const auto u = static_cast<unsigned char>(s[i]);
        b.issues.push_back(u >= 0x20 && u < 0x7f ? std::string("unexpected character '") + s[i] + "'"
                                                 : fmt::format("unexpected character \\x{:02x}", u));
      }
      ++i;
      continue;
    }
    Word w;
    bool exponent = false;
    w.letter = up(s[i++]);
    while (i < s.size() && isSpace(s[i])) ++i;
    const size_t begin = i;
    if (i < s.size() && s[i] == '[') {
      i = bracketEnd(s, i);
    } else if (i < s.size() && s[i] == '#') {
      ++i;
      if (i < s.size() && s[i] == '<') {
        const size_t close = s.find('>', i);
        i = close == std::string_view::npos ? s.size() : close + 1;
      } else if (i < s.size() && s[i] == '[') {
        i = bracketEnd(s, i);
      } else {
        while (i < s.size() && isDigit(s[i])) ++i;
      }
    } else {
      while (i < s.size() && (isDigit(s[i]) || s[i] == '.' || s[i] == '+' || s[i] == '-')) ++i;
      // "X1e2" would otherwise read as X1 and a word E2: no control accepts exponent notation,
      // so it is kept as one word and reported. M66E0 (LinuxCNC's compact input wait) is an M
      // code followed by a real E word.
      size_t k = i + 1;
      if (k < s.size() && (s[k] == '+' || s[k] == '-')) ++k;
      if (i > begin && w.letter != 'M' && i < s.size() && (s[i] == 'e' || s[i] == 'E') && k < s.size() &&
          isDigit(s[k])) {
        while (k < s.size() && isDigit(s[k])) ++k;
        i = k;
        exponent = true;
      }
    }
    w.text = std::string(s.substr(begin, i - begin));
    w.has_decimal_point = w.text.find('.') != std::string::npos;
    if (w.text.empty()) {
      b.issues.push_back(std::string("word ") + w.letter + " has no value");
    } else if (exponent) {
      b.issues.push_back(std::string("word ") + w.letter + w.text +
                         " uses exponent notation, which NC controls do not accept: write the plain number");
    } else if (w.text[0] != '[' && w.text[0] != '#') {
      w.value = literal(w.text);
      if (!w.value) b.issues.push_back(std::string("word ") + w.letter + w.text + " is not a number");
    }
    b.words.push_back(std::move(w));
  }
}

void readLine(Block& b) {
  const std::string& s = b.raw;
  std::string code;
  bool in_comment = false;
  std::string comment;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (in_comment) {
      if (c == ')') {
        b.comments.push_back(comment);
        comment.clear();
        in_comment = false;
      } else {
        if (c == '(') b.issues.push_back("'(' inside a comment (nested comment)");
        comment += c;
      }
    } else if (c == '(') {
      in_comment = true;
    } else if (c == ')') {
      b.issues.push_back("')' without '('");
    } else if (c == ';') {
      b.comments.push_back(s.substr(i + 1));
      break;
    } else {
      code += c;
    }
  }
  if (in_comment) {
    b.comments.push_back(comment);
    b.issues.push_back("comment not closed");
  }
  b.code = trim(code);
  int depth = 0;
  for (char c : b.code) {
    if (c == '[') ++depth;
    if (c == ']' && --depth < 0) break;
  }
  if (depth != 0) b.issues.push_back("unbalanced brackets [ ]");

  std::string_view rest = b.code;
  if (rest == "%") {
    b.percent = true;
    return;
  }
  if (!rest.empty() && rest[0] == '/') {
    b.block_delete = true;
    rest.remove_prefix(1);
  }
  // A leading N word (sequence number / label).
  size_t i = 0;
  while (i < rest.size() && isSpace(rest[i])) ++i;
  if (i < rest.size() && up(rest[i]) == 'N' && i + 1 < rest.size() && isDigit(rest[i + 1])) {
    size_t k = i + 1;
    while (k < rest.size() && isDigit(rest[k])) ++k;
    Word n;
    n.letter = 'N';
    n.text = std::string(rest.substr(i + 1, k - i - 1));
    n.value = literal(n.text);
    b.words.push_back(n);
    rest.remove_prefix(k);
  }
  const std::string after = trim(rest);
  if (detectControl(after, b)) {
    b.control = true;
    return;
  }
  readWords(after, b);
}

}  // namespace

const Word* Block::find(char letter) const {
  for (const auto& w : words)
    if (w.letter == letter) return &w;
  return nullptr;
}

bool Block::hasWord(char letter, double v) const {
  for (const auto& w : words)
    if (w.letter == letter && w.value && std::abs(*w.value - v) < 1e-9) return true;
  return false;
}

std::vector<Block> readProgram(const std::string& text) {
  std::vector<Block> blocks;
  int line = 1;
  size_t start = 0;
  auto emit = [&](size_t end) {
    Block b;
    b.line = line;
    b.raw = text.substr(start, end - start);
    readLine(b);
    blocks.push_back(std::move(b));
  };
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n' || text[i] == '\r') {
      emit(i);
      if (text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      start = i + 1;
      ++line;
    }
  }
  if (start < text.size()) emit(text.size());
  return blocks;
}

}  // namespace rotacal::nc
