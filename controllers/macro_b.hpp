#pragma once
// Custom Macro B programs shared by the Fanuc-compatible dialects (fanuc, haas): G31 skip
// moves with an explicit no-trigger check, results through POPEN/DPRNT/PCLOS with the
// control's date and time in the header and the ms timer per point, and the strict checker.
// Each dialect supplies its flavour (program number, retained variables, look-ahead) and its
// own offset writer (../shared/reference/controllers.md Sec. 2 and 3).
//
// Results, as the program's DPRNTs print them (rotacal's rendering, see macro_b::dprntNumber):
//   ROTACAL-RESULTS DIALECT FANUC CYCLE TOUCH154 POINTS 154 UNIT MM
//   DATE 20261122 TIME  14119
//   P17 X 123.4560 Y-200.0000 Z 173.0000 T   12345
//   END
// DATE/TIME = #3011 (YYYYMMDD) and #3012 (HHMMSS) read at the start, where the ms timer #3001 is
// zeroed; T = #3001 at the trigger. t_s = seconds of (DATE, TIME) since 2000-01-01 + T / 1000:
// a clock common to all repeats (the header's second is truncated, so every t_s of a run is
// early by the same fraction of a second, < 1 s; drift analysis works on hours). Every DPRNT
// field [ab] keeps a + b <= 8 (kMaxDprntDigits in macro_b.cpp), T included: [80], 27.7 h of ms.
#include <string>
#include <vector>

#include "controllers/dialect.hpp"

namespace rotacal {

struct MacroBFlavor {
  std::string name;                 // the dialect's name, as registered
  std::string tag;                  // in the results header: "FANUC"
  std::string title;                // in the program's first comment
  int program_digits = 4;           // O1234 (Fanuc), O01234 (Haas: O + 5 digits)
  int store_base = 700;             // retained variables of the current pose, 4 per point
  int max_points_per_pose = 70;     // store_base + 4 n - 1 must stay retained
  bool lookahead_g103 = false;      // Haas: DPRNT runs at look-ahead time -> G103 P1
  char dwell_word = 'X';            // G04 X2. (Fanuc: seconds with a decimal point) or G04 P2. (Haas)
  std::vector<std::string> notes;   // extra operator comments at the top
};

class MacroBDialect : public Dialect {
 public:
  MacroBDialect(MacroBFlavor flavor, DialectIdentity identity) : Dialect(std::move(identity)), f_(std::move(flavor)) {}
  std::string_view name() const override { return f_.name; }
  std::string_view programExtension() const override { return ".nc"; }
  std::string_view resultsExtension() const override { return ".txt"; }
  std::string writeProgram(const nc::Program& program) const override;
  std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const override;
  MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const override;
  std::vector<std::string> commentLines(std::string_view text) const override;
  std::vector<std::string> check(const std::string& program_text, const ProbePlan& plan, const nc::Shape& shape) const override;

 protected:
  const MacroBFlavor& flavor() const { return f_; }

 private:
  MacroBFlavor f_;
};

namespace macro_b {
/// What every Macro B dialect is: ISO G-code in numbered programs, each G31 skip followed by
/// its no-trigger check (#1-#3 = skip position #5061-#5063 minus the end point).
inline DialectIdentity identity() {
  DialectIdentity d;
  d.language = ProgramLanguage::IsoGcode;
  d.numbers_programs = true;
  d.end_point_check = EndPointCheck{{"#1", "#2", "#3"}, {"#5061", "#5062", "#5063"}};
  d.z_reference_at_stroke_top = true;
  return d;
}
/// Upper-case comment lines "(...)" of at most 80 characters in Fanuc's safe character set.
std::vector<std::string> comments(std::string_view text);
/// DPRNT text: A-Z 0-9 and '-', '.', '/'.
std::string dprntText(std::string_view text);
/// A number as DPRNT prints #v[ab] (a integer digits, b decimals), in rotacal's chosen
/// form: the sign (only when negative) directly before the digits, the whole right-aligned in
/// a + (b > 0 ? b + 1 : 0) characters (leading spaces; wider when it does not fit), no decimal
/// point when b == 0. E.g. [44]: 123.456 -> " 123.4560", -200 -> "-200.0000"; [90]: 12345 ->
/// "    12345". UNVERIFIED against a real control (parameter 6001 changes padding and sign).
std::string dprntNumber(double value, int integer_digits, int decimals);
}  // namespace macro_b

}  // namespace rotacal
