#pragma once
// A tokenizer of word-address NC programs (LinuxCNC rs274ngc and Fanuc Custom Macro B), used by
// the dialect checkers. It splits a program into blocks (one per line), words and comments; it
// does not evaluate expressions or keep modal state. Pure: odd input never throws, it is
// reported in Block::issues for the checkers to turn into problems.
#include <optional>
#include <string>
#include <vector>

namespace rotacal::nc {

/// One address word: a letter and its value, e.g. X-12.5 or G38.2.
struct Word {
  char letter = 0;            // upper case
  std::string text;           // what follows the letter, as written ("-12.5", "[#1+2]", "#5061")
  bool has_decimal_point = false;
  std::optional<double> value;  // nullopt when the value is an expression or a parameter
};

/// One line of the program.
struct Block {
  int line = 0;                       // 1-based line number in the text
  std::string raw;                    // the line without its end-of-line characters
  std::string code;                   // the line without comments, trimmed
  std::vector<Word> words;            // empty for control blocks
  std::vector<std::string> comments;  // text inside ( ) and after ';', without the delimiters
  /// A control block: LinuxCNC o-word (o100 if ...), Fanuc macro (IF, GOTO, WHILE, END1, DO1),
  /// a parameter assignment (#1=..., #<x> = ...), or DPRNT/BPRNT/POPEN/PCLOS.
  bool control = false;
  /// Control blocks: the upper-case keyword: "IF", "ELSEIF", "ELSE", "ENDIF", "WHILE", "ENDWHILE",
  /// "DO", "REPEAT", "ENDREPEAT", "SUB", "ENDSUB", "CALL", "RETURN", "BREAK", "CONTINUE" (o-words,
  /// with oword set), "IF", "GOTO", "WHILE", "END", "DO" (Fanuc), "#" (assignment), "DPRNT",
  /// "BPRNT", "POPEN", "PCLOS".
  std::string keyword;
  std::string oword;                  // LinuxCNC o-word number or <name> of a control block
  bool percent = false;               // the line is a '%' tape mark
  bool block_delete = false;          // starts with '/'
  std::vector<std::string> issues;    // syntax problems of this line, e.g. "comment not closed"

  bool empty() const { return code.empty() && comments.empty(); }
  /// The first word with this letter, or nullptr.
  const Word* find(char letter) const;
  /// True when a word with this letter has exactly this value (e.g. hasWord('G', 38.2)).
  bool hasWord(char letter, double value) const;
};

/// Splits a program into blocks. Lines end with LF, CR LF or a lone CR.
std::vector<Block> readProgram(const std::string& text);

}  // namespace rotacal::nc
