#pragma once
// Helpers shared by the dialects: locale-independent fixed-point text, strict number parsing,
// line splitting, the collection of parsed points with precise errors, the plausibility limit
// of written corrections and the stroke check of a parsed program.
#include <Eigen/Core>
#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "controllers/dialect.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "gcode/program.hpp"
#include "gcode/reader.hpp"

namespace rotacal::ctl {

/// Plausibility limits of a written correction (request.force overrides them).
constexpr double kMaxLengthCorrectionMm = 0.5;     // a larger pivot error is a setup blunder, not drift
constexpr double kMaxAngleCorrectionMdeg = 100.0;  // 0.1 deg: likewise

/// Tolerance of the stroke check on printed coordinates: covers the rounding of 4-5 printed
/// decimals (<= 0.5e-4 mm, inch 0.5e-5 in) with margin.
constexpr double kStrokeTolMm = 1e-3;

/// `v` with `decimals` digits after the point, through fmt (locale-independent). Never "-0.000".
/// Throws std::invalid_argument for NaN or infinity (no NC text may contain them).
std::string fixed(double v, int decimals);

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

/// Collects the points of one results file and enforces: ids in the plan, each once, all
/// present. Errors are rotacal::InputError(file, line, message).
class PointCollector {
 public:
  PointCollector(const ProbePlan& plan, std::string file);
  /// Records point `id` read at `line`. Throws on an id not in the plan or a repeated id.
  void add(int line, int id, const Eigen::Vector3d& position_m_mm, double t_s);
  /// Throws naming the first plan point not seen (at `last_line`), else returns the run in
  /// file order.
  MeasurementRun finish(int last_line) const;
  /// First plan point not seen yet, or 0.
  int firstMissing() const;
  size_t size() const { return run_.points.size(); }

 private:
  const ProbePlan& plan_;
  std::string file_;
  MeasurementRun run_;
  std::map<int, int> seen_line_;  // id -> line
};

/// Throws rotacal::InputError(file, line, what).
[[noreturn]] void fail(const std::string& file, int line, const std::string& what);

/// Why location error `index` of `kinematics` with value `v` (mm / rad) is no plausible
/// correction: not finite, or beyond kMaxLengthCorrectionMm / kMaxAngleCorrectionMdeg (with the
/// parameter, its value and the limit); "" when it is plausible. The one limit of everything
/// that writes a correction: the offsets writers and `rotacal compensate`.
std::string implausibility(Kinematics kinematics, int index, double v);

/// Throws std::invalid_argument naming the parameter, its value and the limit when any
/// identified location error exceeds the plausibility limits and !request.force. Also throws
/// when request.plan is null or a value is not finite.
void requirePlausible(const OffsetRequest& request);

/// "value +- u unit" lines of the identified errors, e.g. "dx_AY (X0A)  14.600 um +- 0.900 um".
std::vector<std::string> identifiedLines(const OffsetRequest& request);

/// Paper-convention angle of `axis` in a pose.
double poseAngle(const Pose& pose, char axis);

/// Machine-stroke problems of the motion blocks of a parsed program ("LINE: ..."): X/Y/Z
/// endpoints (absolute mode, converted to mm under G20) against the machine's strokes, A/B/C
/// against the rotary strokes in the papers' convention (controller angle / controller sign of
/// `dialect`). Blocks with G10, G53 or G92 are not motion endpoints and are skipped; so are
/// words whose value is an expression.
std::vector<std::string> strokeProblems(const std::vector<nc::Block>& blocks, const ProbePlan& plan,
                                        const std::string& dialect);

/// Syntax issues recorded by the reader, as "LINE: issue".
std::vector<std::string> readerIssues(const std::vector<nc::Block>& blocks);

/// Index of the next non-blank block after `i` (blocks.size() when none).
size_t nextNonBlank(const std::vector<nc::Block>& blocks, size_t i);
/// Indices of the (up to) `n` non-blank blocks after block `i`, in order: where a checker looks
/// for the no-trigger check that must follow a probing move.
std::vector<size_t> nextBlocks(const std::vector<nc::Block>& blocks, size_t i, int n);
/// The checks every block-based checker (Macro B, LinuxCNC) makes of the whole program: its
/// inverse-time problems, then its stroke problems.
std::vector<std::string> blockProblems(const std::vector<nc::Block>& blocks, const ProbePlan& plan,
                                       const std::string& dialect);


// ---- Additions for the haas / siemens / heidenhain / okuma dialects and the Fanuc clock ----

/// Epoch of the controllers' wall clocks in results files: 2000-01-01 00:00:00 (control local
/// time, no time zone: every repeat of a calibration runs on the same control). t_s of a point =
/// seconds since this epoch, so repeats share one clock (contract.md "Neutral results").
constexpr int kClockEpochYear = 2000;

/// Seconds since kClockEpochYear-01-01 00:00:00 of a date YYYYMMDD and a time HHMMSS (as Fanuc
/// #3011/#3012 hold them); nullopt when the date or the time is not a valid calendar value.
std::optional<double> clockSeconds(long yyyymmdd, long hhmmss);

struct ClockStamp {
  long yyyymmdd = 0;
  long hhmmss = 0;
};
/// Date and time of floor(seconds) since the epoch (inverse of clockSeconds on whole seconds).
/// Throws std::invalid_argument for a non-finite value or a year outside 1900..9999.
ClockStamp clockStamp(double seconds_since_epoch);

/// The text after each letter of `letters` in a line "P<id> X.. Y.. Z.. ...": the line starts
/// with 'P' and the id digits, then each letter of `letters` in order, each followed by its
/// field (spaces between a letter and its field, and between fields, are allowed; a field ends
/// at the next space after its first character or at the next expected letter). Throws
/// InputError(file, line, ...) naming what is wrong. Returns the id and the field texts.
struct LetteredLine {
  long id = 0;
  std::vector<std::string> fields;
};
LetteredLine letteredFields(const std::string& s, std::string_view letters, const std::string& file, int line);

/// Like parseNumber, also accepting a decimal comma instead of the point (Heidenhain prints
/// "-293,733" with a German language setting) and a trailing point or comma ("12." "12,").
std::optional<double> parseNumberComma(std::string_view token);

/// Converts a program's text lines into neutral blocks for strokeProblems: each entry is a line
/// number and its X/Y/Z/A/B/C values (absolute, in the program's unit) of one motion endpoint.
struct MotionEndpoint {
  int line = 0;
  std::vector<std::pair<char, double>> axes;
};
std::vector<nc::Block> motionBlocks(const std::vector<MotionEndpoint>& endpoints, bool inch);

/// Unit direction of a probing move (from the nominal trigger toward the end point) when it is
/// along one machine axis: axis index 0..2 and sign +-1; nullopt when it is not axis-aligned
/// within 1e-9.
struct AxisDirection {
  int axis = 0;
  int sign = 1;
};
std::optional<AxisDirection> axisAligned(const Eigen::Vector3d& direction);

/// The results text of the dialects that print tagged lines with their own output statements
/// (Siemens WRITE, Okuma PUT): the header "ROTACAL-RESULTS DIALECT <tag> CYCLE <cycle_token>
/// POINTS <n> UNIT MM|INCH", one "P<id> X<x> Y<y> Z<z>" line per point (any spacing),
/// "NOT-TRIGGERED P<id>" where the program stopped, and "END". `second_header_why` is added to
/// the message when a second header shows an appended old run.
/// The lines of a results file as every line-based reader takes them (tagged, Macro B,
/// Heidenhain): trimmed, blank lines and `skip` lines passed over, with the rules they share: the
/// header first and once, nothing after the END line, a NOT-TRIGGERED line where the program
/// stopped, and at the end an empty file or a missing END named. Errors are InputError(file, line).
class ResultLines {
 public:
  ResultLines(const std::string& text, std::string file, std::string header_token, std::string expected_header,
              std::string second_header_why, std::string skip = "");
  /// Moves to the next line (number, s, t); false after the last. Throws at text after END, at a
  /// line before the header and at a second header.
  bool next();
  /// This line is the header (its checks are the reader's).
  bool isHeader() const { return !t.empty() && t[0] == header_token_; }
  /// This line is "END": marks it, and anything after it is refused.
  bool isEnd();
  /// Throws at a "NOT-TRIGGERED P<id>" line, naming the point where the program stopped.
  void refuseNotTriggered() const;
  /// After the last line: throws for an empty file, or a file without END (naming the first plan
  /// point not read, and `stopped_why` after "the program stopped early").
  void finish(const PointCollector& points, std::string_view stopped_why = "") const;
  int last() const { return last_; }

  int number = 0;
  std::string s;
  std::vector<std::string> t;

 private:
  std::vector<TextLine> lines_;
  size_t at_ = 0;
  std::string file_, header_token_, expected_header_, second_header_why_, skip_;
  bool header_ = false;
  int end_line_ = 0;
  int last_ = 1;
};

/// The header line of a tagged results file, "ROTACAL-RESULTS DIALECT <tag> CYCLE <cycle_token>
/// POINTS <n> UNIT MM|INCH" (the trimmed text `s` of line `line` of `file`): throws InputError
/// naming what differs from the plan; returns the file's mm per unit (1 or 25.4).
double taggedHeaderMmPerUnit(const std::string& s, const std::string& file, int line, const ProbePlan& plan,
                             std::string_view tag, std::string_view cycle_token);

MeasurementRun parseTaggedResults(const std::string& text, const std::string& file, const ProbePlan& plan,
                                  std::string_view tag, std::string_view cycle_token, std::string_view second_header_why);

/// The fixed-tool-tip ops (nc::Op Mode, RotaryLinear, Pause; 004 Table 1).
/// `v` with at most `decimals` digits, trailing zeros dropped, the point kept: 5 -> "5.",
/// 2.5 -> "2.5" (004 Table 1's "A5.", "F2.").
std::string trimmed(double v, int decimals);
/// The words of a RotaryLinear op: "Y-1.3073Z-0.0571A5.F2." (sep = "") or with spaces.
std::string rotaryLinearWords(const nc::Op& op, nc::Unit unit, const std::string& sep);

/// The motion blocks the word-address writers (Macro B, Okuma, Siemens) share, in the dialect's
/// G spelling (`g`: "G0"/"G00" for a rapid, "G1"/"G01" for a feed), coordinates with `decimals`,
/// feeds with 3 decimals in inch and 1 in mm: "G00 Z150.0000" for a Z-only rapid, else
/// "G00 X.. Y.. Z..", and "G01 X.. Y.. Z.. F..".
std::string rapidBlock(std::string_view g, const nc::Op& op, int decimals);
std::string linearBlock(std::string_view g, const nc::Op& op, int decimals, bool inch);
/// Throws std::invalid_argument for a rotary move at a feed (the R-test's reciprocation), which
/// only the LinuxCNC writer writes.
void requireRapidIndex(const nc::Op& op, std::string_view dialect);
/// Modal state of a writer: throws std::invalid_argument for a probing move under inverse time
/// (LinuxCNC: "Cannot probe with zero feed rate") or an inverse-time move without F.
class ModeGuard {
 public:
  void apply(const nc::Op& op);
  bool inverseTime() const { return inverse_time_; }

 private:
  bool inverse_time_ = false;
};
/// Why `dialect` writes no inverse-time feed (G93), "" when it does. The one policy of every
/// writer and checker: G93 is written where controllers.md names it for the control - LinuxCNC
/// (verified with rs274), Haas ([HaasMan]), Fanuc and Siemens (only their "F on every G93 block"
/// rule is UNVERIFIED, and rotacal writes F on every block) - and refused where G93 itself is
/// UNVERIFIED (the dialect's DialectIdentity::inverse_time_refusal): a program that moves under
/// G93 is refused there, with this reason and the dialects that write it.
std::string inverseTimeRefusal(std::string_view dialect);
/// Throws std::invalid_argument(inverseTimeRefusal(dialect)) when `program` switches to inverse
/// time and the dialect refuses it.
void requireInverseTimeAllowed(const nc::Program& program, std::string_view dialect);

/// ISO word-address checks of the modes: under G93 every G1/G2/G3 block with an axis word
/// carries F, and no block under G93 probes (`isProbe`).
std::vector<std::string> inverseTimeProblems(const std::vector<nc::Block>& blocks,
                                             bool (*isProbe)(const nc::Block& block));
/// The program number a program carries (nc::Program::number, stated by the cycle that wrote
/// it: docs/dialects.md lists them). Throws std::invalid_argument outside 1-9999.
int programNumber(const nc::Program& program);

/// Any dialect's probing block: G31, G38.x, MEAS=, TCH PROBE.
bool isProbingBlock(const nc::Block& block);

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

// ---- The steps every writer and checker of a program took in its own words ----

/// The probing moves of `program`. Throws std::invalid_argument when it states another
/// point_count: the cycle's plan and its program would then disagree on what a results line is.
int probeCount(const nc::Program& program);

/// Appends `s` and '\n' to `out`. Throws std::invalid_argument when `s` is longer than
/// `max_chars`: the control would cut the block or refuse the program.
void appendLine(std::string& out, const std::string& s, size_t max_chars);

/// A program or offsets file written line by line: `text` gains each line and its "\n"; with
/// `max_chars` > 0 a longer line throws (appendLine's rule); comment() writes a text as the
/// dialect's comment lines (`comments` cuts and wraps it in the dialect's syntax).
class LineWriter {
 public:
  using Comments = std::vector<std::string> (*)(std::string_view text);
  explicit LineWriter(Comments comments, size_t max_chars = 0) : comments_(comments), max_chars_(max_chars) {}
  void line(const std::string& s) {
    if (max_chars_ > 0) appendLine(text, s, max_chars_);
    else text += s + "\n";
  }
  void comment(std::string_view s) {
    for (const auto& c : comments_(s)) line(c);
  }
  /// The comments every offsets file carries: `heading`, then each identified location error with
  /// its standard uncertainty (identifiedLines).
  void identified(const OffsetRequest& r, std::string_view heading) {
    comment(heading);
    for (const auto& s : identifiedLines(r)) comment(s);
  }
  /// The comments every program opens with: what generated it, for which dialect, then the
  /// program's own header lines.
  void provenance(const nc::Program& p, std::string_view dialect) {
    comment(p.name + " generated by rotacal, dialect " + std::string(dialect));
    for (const auto& h : p.header) comment(h);
  }
  std::string text;

 private:
  Comments comments_;
  size_t max_chars_;
};

/// Throws std::invalid_argument: the R-test program's dwell, logger trigger and loops (002) are
/// spelled for linuxcnc only so far.
[[noreturn]] void refuseRtestOps(std::string_view dialect);

/// How a word-address writer (Macro B, Okuma, Siemens) spells the moves they all write alike.
struct WordAddressMoves {
  std::string_view dialect;
  std::string_view rapid;  // "G00" or "G0"
  std::string_view feed;   // "G01" or "G1"
  int decimals = 4;        // of coordinates and angles
  std::string rotary_linear_sep;  // between the words of a RotaryLinear op
};
/// The ops of `program` in order, each after ModeGuard::apply: the moves spelled alike (Rapid,
/// Linear, Index at rapid only, RotaryLinear) written to `w`, the R-test's ops refused
/// (refuseRtestOps), and the dialect's own (Comment, Mode, Pause, Probe) given to `own`.
/// `before_index` runs before an index block is written.
void writeOps(const nc::Program& program, const WordAddressMoves& moves, LineWriter& w,
              const std::function<void(const nc::Op&)>& own,
              const std::function<void()>& before_index = {});
/// The block of a Mode op in ISO words (004 Table 1): "G91 G01 G93 F2." when it switches to
/// inverse time at a feed (G1 in force for the word-only blocks after it), else "G90 G94" and the
/// like.
std::string isoModeBlock(const nc::Op& op);
/// Throws std::invalid_argument unless probing move `op` has a feed and no retract: these
/// dialects' programs record a single touch.
void requireSingleTouch(const nc::Op& op, std::string_view dialect);

/// What the offsets writers of a table A/C or B/C machine start from, the request checked by
/// requirePlausible first.
struct OffsetBasis {
  explicit OffsetBasis(const OffsetRequest& request);
  const ProbePlan& plan;
  const MachineModel& machine;
  const LocationErrors& e;
  bool ac;   // table A/C, else B/C
  bool inch;
  double k;  // mm -> the machine's unit
  char tilt;  // the tilting axis, 'A' or 'B'
  /// The tilting axis' pivot error: (dx_AY, dy_AY, dz_AY), or (dx_BY, dy_CB, dz_BY).
  Eigen::Vector3d pivot() const;
  /// The C axis' offset from the tilting axis: (0, dy_CA, 0), or (dx_CB, 0, 0).
  Eigen::Vector3d second() const;
  /// The tilting axis' zero error in `dialect`'s sign of that axis (+1 without it), degrees.
  double zeroDeg(std::string_view dialect) const;
};

/// The results side of the dialects whose programs print tagged lines with their own output
/// statements (okuma PUT, siemens WRITE): parseTaggedResults reads what writeResults writes, the
/// header, "P<id> X<x> Y<y> Z<z>" per point with the coordinates in 5 decimals in inch and 4 in
/// mm, right-aligned in `width` characters (0: unpadded), and "END", every line ended by `eol`,
/// in a .txt file.
class TaggedResultsDialect : public Dialect {
 public:
  struct Form {
    std::string_view name;               // the dialect's
    std::string_view program_extension;  // ".min"
    std::string_view tag;                // "OKUMA"
    std::string (*cycle_token)(std::string_view);  // the cycle's name as the programs print it
    int width = 0;
    std::string_view eol;
    std::string_view second_header_why;  // parseTaggedResults'
  };
  TaggedResultsDialect(const Form& form, DialectIdentity identity) : Dialect(std::move(identity)), form_(form) {}
  std::string_view name() const override { return form_.name; }
  std::string_view programExtension() const override { return form_.program_extension; }
  std::string_view resultsExtension() const override { return ".txt"; }
  /// Decimals of the printed coordinates, the programs' and writeResults': 4 in mm, 5 in inch (4
  /// inch decimals would round by up to 1.27 um and move the identified errors by up to 3.1 um,
  /// docs/dialects.md).
  static int resultDecimals(bool inch) { return inch ? 5 : 4; }
  std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const override;
  MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const override;

 private:
  Form form_;
};

/// A line-based program check (the dialects whose programs the NC reader does not parse: okuma,
/// siemens, heidenhain): the text's lines, each line's code without its comments (the dialect
/// fills `code`, knowing its comment syntax) and the problems found, "LINE: what".
class TextCheck {
 public:
  explicit TextCheck(std::string_view text);
  const std::vector<TextLine> lines;
  std::vector<std::string> code;
  std::vector<std::string> problems;

  void problem(int line, const std::string& what);
  /// The number of the text's last line (1 for an empty text).
  int lastLine() const;
  /// Index of the next non-empty `code` entry after `i` (lines.size() when none).
  size_t nextCode(size_t i) const;
  /// Line `i` longer than `max` characters.
  void lineLength(size_t i, size_t max);
  /// "<found> <moves>, the plan has <planned> points" at the last line when the counts differ.
  void probeCount(int found, size_t planned, std::string_view moves);
  /// The checks a line-based checker ends with, in this order: the inverse-time problems of the
  /// whole text, the stroke problems of `motion_text` (the motion blocks at their lines' places,
  /// the others blank, read after the unit line of `inch`), and "LINE: the program does not end
  /// with <end>" when the last code is not `end`. Returns every problem found.
  std::vector<std::string> finish(std::string_view end, const std::string& motion_text, bool inch,
                                  const ProbePlan& plan, const std::string& dialect);

 private:
  std::string text_;
};

}  // namespace rotacal::ctl
