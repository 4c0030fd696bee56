// The word-address tokenizer used by the dialect checkers: blocks per line, words with their
// decimal points, comments, control statements of both dialects, and odd input reported, never
// thrown.
#include <gtest/gtest.h>

#include <random>

#include "test_util.hpp"
#include "cycles/cycle.hpp"
#include "controllers/dialect.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "gcode/reader.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal::nc {
namespace {

TEST(GcodeReader, SplitsWordsAndCommentsOfABlock) {
  const auto b = readProgram("G1 X10.5 Y-2 Z+3. F100 (move) (LOG,P1 #5061)\n");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].line, 1);
  EXPECT_FALSE(b[0].control);
  ASSERT_EQ(b[0].words.size(), 5u);
  EXPECT_EQ(b[0].words[1].letter, 'X');
  EXPECT_EQ(*b[0].words[1].value, 10.5);
  EXPECT_TRUE(b[0].words[1].has_decimal_point);
  EXPECT_EQ(*b[0].words[2].value, -2.0);
  EXPECT_FALSE(b[0].words[2].has_decimal_point);
  EXPECT_EQ(*b[0].words[3].value, 3.0);
  EXPECT_TRUE(b[0].words[3].has_decimal_point);
  ASSERT_EQ(b[0].comments.size(), 2u);
  EXPECT_EQ(b[0].comments[1], "LOG,P1 #5061");
  EXPECT_EQ(b[0].code, "G1 X10.5 Y-2 Z+3. F100");
  EXPECT_TRUE(b[0].issues.empty());
}

TEST(GcodeReader, GWordWithFractionIsOneWord) {
  const auto b = readProgram("G38.2 X1 F5");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_TRUE(b[0].hasWord('G', 38.2));
  EXPECT_FALSE(b[0].hasWord('G', 38.0));
}

TEST(GcodeReader, SemicolonStartsARestOfLineComment) {
  const auto b = readProgram("G0 X1 ; to the left (not a comment paren\n");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].words.size(), 2u);
  ASSERT_EQ(b[0].comments.size(), 1u);
  EXPECT_EQ(b[0].comments[0], " to the left (not a comment paren");
  EXPECT_TRUE(b[0].issues.empty());
}

TEST(GcodeReader, PercentLineIsATapeMark) {
  const auto b = readProgram("%\nM2\n%\n");
  ASSERT_EQ(b.size(), 3u);
  EXPECT_TRUE(b[0].percent);
  EXPECT_FALSE(b[1].percent);
  EXPECT_TRUE(b[2].percent);
}

TEST(GcodeReader, LeadingNWordIsASequenceNumberEvenBeforeAControlStatement) {
  const auto b = readProgram("N1001\nN20 #1=#5061-2.0\nN30 G0 X1.\n");
  ASSERT_EQ(b.size(), 3u);
  EXPECT_TRUE(b[0].hasWord('N', 1001));
  EXPECT_FALSE(b[0].control);
  EXPECT_TRUE(b[1].control);
  EXPECT_EQ(b[1].keyword, "#");
  EXPECT_TRUE(b[1].hasWord('N', 20));
  EXPECT_TRUE(b[2].hasWord('N', 30));
  EXPECT_TRUE(b[2].hasWord('X', 1));
}

TEST(GcodeReader, BracketExpressionsAndParametersHaveNoValue) {
  const auto b = readProgram("G10 L2 P1 A[#5224 + 0.5] X#1 Y#<_y>\n");
  ASSERT_EQ(b.size(), 1u);
  const Word* a = b[0].find('A');
  ASSERT_NE(a, nullptr);
  EXPECT_FALSE(a->value.has_value());
  EXPECT_EQ(a->text, "[#5224 + 0.5]");
  EXPECT_FALSE(b[0].find('X')->value.has_value());
  EXPECT_EQ(b[0].find('Y')->text, "#<_y>");
  EXPECT_TRUE(b[0].issues.empty());
}

TEST(GcodeReader, LinuxCncOwordsAreControlBlocks) {
  const auto b = readProgram("o1001 if [#5070 NE 1]\n(ABORT, no)\no1001 endif\no<probe> sub\nO100 (prog)\n");
  ASSERT_EQ(b.size(), 5u);
  EXPECT_TRUE(b[0].control);
  EXPECT_EQ(b[0].keyword, "IF");
  EXPECT_EQ(b[0].oword, "1001");
  EXPECT_FALSE(b[1].control);
  EXPECT_EQ(b[1].comments[0], "ABORT, no");
  EXPECT_EQ(b[2].keyword, "ENDIF");
  EXPECT_EQ(b[3].keyword, "SUB");
  EXPECT_EQ(b[3].oword, "<probe>");
  // A Fanuc program number is a word, not control.
  EXPECT_FALSE(b[4].control);
  EXPECT_TRUE(b[4].hasWord('O', 100));
}

TEST(GcodeReader, FanucMacroStatementsAreControlBlocks) {
  const auto b = readProgram(
      "#1=#5061-51.0000\nIF[[#1*#1]GT0.0001]GOTO1001\n#3000=1(POINT 1 NOT TRIGGERED)\nWHILE[#2LT3]DO1\nEND1\n"
      "DPRNT[P1*X#700[44]]\nPOPEN\nPCLOS\nGOTO10\n");
  const char* kw[] = {"#", "IF", "#", "WHILE", "END", "DPRNT", "POPEN", "PCLOS", "GOTO"};
  ASSERT_EQ(b.size(), 9u);
  for (size_t i = 0; i < b.size(); ++i) {
    EXPECT_TRUE(b[i].control) << b[i].raw;
    EXPECT_EQ(b[i].keyword, kw[i]) << b[i].raw;
    EXPECT_TRUE(b[i].words.empty()) << b[i].raw;
    EXPECT_TRUE(b[i].issues.empty()) << b[i].raw;
  }
  EXPECT_EQ(b[2].comments[0], "POINT 1 NOT TRIGGERED");
}

TEST(GcodeReader, UnbalancedParenthesesAndBracketsAreIssuesNotExceptions) {
  const auto b = readProgram("G0 X1 (open\nG0 X1 ) Y2\n(a (nested) one)\nIF[[#1GT2]GOTO5\n");
  ASSERT_EQ(b.size(), 4u);
  for (const auto& blk : b) EXPECT_FALSE(blk.issues.empty()) << blk.raw;
}

TEST(GcodeReader, CrLfAndLoneCrEndLines) {
  const auto b = readProgram("G0 X1\r\nG0 X2\rG0 X3\nG0 X4");
  ASSERT_EQ(b.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(b[i].line, i + 1);
    EXPECT_TRUE(b[i].hasWord('X', i + 1.0));
    EXPECT_EQ(b[i].raw.find('\r'), std::string::npos);
  }
}

TEST(GcodeReader, NotANumberAndMissingValueAreIssues) {
  const auto b = readProgram("G0 X1.2.3 Y\n");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].issues.size(), 2u);
  EXPECT_FALSE(b[0].find('X')->value.has_value());
}

TEST(GcodeReader, ExponentNotationIsOneWordWithAnIssueNotTwoWords) {
  // "X1e2" must not become X1 and E2 (a control reads neither 100 nor 1).
  for (const char* text : {"G0 X1e2", "G0 X1.5E+2", "G0 X-2e-3"}) {
    const auto b = readProgram(text);
    ASSERT_EQ(b.size(), 1u);
    ASSERT_EQ(b[0].words.size(), 2u) << text;
    EXPECT_EQ(b[0].words[1].letter, 'X');
    EXPECT_FALSE(b[0].words[1].value.has_value()) << text;
    ASSERT_EQ(b[0].issues.size(), 1u) << text;
    EXPECT_NE(b[0].issues[0].find("exponent notation"), std::string::npos) << b[0].issues[0];
  }
  // A real E word after a space, and LinuxCNC's compact M66E0, stay words.
  const auto spaced = readProgram("G1 X1 E2");
  ASSERT_EQ(spaced[0].words.size(), 3u);
  EXPECT_EQ(*spaced[0].words[1].value, 1.0);
  EXPECT_EQ(spaced[0].words[2].letter, 'E');
  EXPECT_TRUE(spaced[0].issues.empty());
  const auto m66 = readProgram("M66E0L0");
  ASSERT_EQ(m66[0].words.size(), 3u);
  EXPECT_TRUE(m66[0].issues.empty());
}

TEST(GcodeReader, ArbitraryBytesNeverThrow) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int k = 0; k < 200; ++k) {
    std::string s;
    for (int i = 0; i < 300; ++i) s += static_cast<char>(byte(rng));
    EXPECT_NO_THROW(readProgram(s));
  }
}

TEST(GcodeReader, GeneratedProgramsTokenizeCleanly) {
  const char* machine = R"({"name": "ac", "kinematics": "table_ac",
    "strokes": {"X": [-625, 625], "Y": [-330, 330], "Z": [-140, 400]},
    "rotary_axes": {"A": {"stroke_deg": [-110, 20], "dialect_sign": {"linuxcnc": -1}},
                    "C": {"continuous": true, "dialect_sign": {"linuxcnc": -1}}},
    "probe": {"ball_diameter_mm": 6, "stylus_length_mm": 50},
    "artefact": {"type": "square_column", "top_centre_w_mm": [0, -200, 170], "size_mm": [100, 100, 150]}})";
  const JsonDoc doc = parseJsonText(machine, "m.json");
  const ProbePlan plan = makePlan("touch154", machineFromJson(doc, doc.value), {});
  for (const auto& [dialect, probe_g] : {std::pair<std::string, double>{"linuxcnc", 38.2}, {"fanuc", 31.0}}) {
    const auto blocks = readProgram(dialectByName(dialect).writeProgram(test::cycleProgram(plan, dialect)));
    size_t probes = 0;
    for (const auto& b : blocks) {
      EXPECT_TRUE(b.issues.empty()) << dialect << " line " << b.line << ": " << b.raw;
      probes += b.hasWord('G', probe_g);
    }
    EXPECT_EQ(probes, plan.points.size()) << dialect;
    EXPECT_TRUE(blocks.front().percent) << dialect;
  }
}

}  // namespace
}  // namespace rotacal::nc
