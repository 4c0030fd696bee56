#pragma once
// The dialect-neutral NC program: what a probing program does, in the controller's own
// coordinates (machine XYZ with the work offset at the rotary-axis intersection, in the
// program's length unit; rotary angles in the controller's own sign), before any dialect
// decides how to spell it. controllers/ turns it into text; postproc/ builds it from a plan.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace rotacal::nc {

enum class Unit { Millimetre, Inch };

/// One step of a probing program.
struct Op {
  enum class Kind {
    Comment,   // text
    Rapid,     // G0 to xyz
    Linear,    // G1 to xyz at feed
    Index,     // rotary axes to `rotary` (clear of the piece: the writer needs nothing else)
    Probe,     // guarded move from the current position toward xyz at feed; must trigger
    // The fixed-tool-tip cycle (004). Probing is never allowed under inverse time.
    Mode,          // distance mode (G90 / G91) and feed mode (G94 / G93), `incremental`, `inverse_time`
    RotaryLinear,  // G1 of the linear axes named in `axes` (xyz, increments under G91) together with
                   // `rotary`; under G93 `feed` is 1 / minutes of the move and goes on every block.
                   // Lengths with rotaryLinearDecimals(), angles without trailing zeros ("A5.", 004).
    Pause,         // dwell_s > 0: dwell for a reading; dwell_s = 0: program stop (M0) for the operator
    Dwell,        // wait `seconds` (R-test: the sensors settle before the static reading)
    Read,         // trigger a reading of an external device (the R-test logger), point_id
    RepeatBegin,  // run the ops up to the matching RepeatEnd `count` times (>= 1); nestable
    RepeatEnd,
  } kind = Kind::Comment;
  bool incremental = false;   // Mode
  bool inverse_time = false;  // Mode
  std::string axes;           // RotaryLinear: linear axes to write, e.g. "YZ"
  double dwell_s = 0.0;       // Pause
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  std::vector<std::pair<char, double>> rotary;  // for Index: axis letter, controller angle (deg)
  bool z_only = false;                          // Rapid: move Z alone (X, Y stay where they are)
  double feed = 0.0;                            // per minute, program units (Index: deg/min, 0 = rapid)
  double seconds = 0.0;                         // Dwell
  int count = 0;                                // RepeatBegin
  std::string text;                             // Comment
  int point_id = 0;                             // Probe: plan point id (1-based)
  // Probe, double touch (what real probing macros do against trigger latency): when
  // retract_mm > 0, the first touch at `feed` is followed by a back-off of retract_mm along the
  // approach and a second touch at slow_feed toward xyz; the second touch is the one recorded.
  // A dialect that cannot do it must throw std::invalid_argument.
  double retract_mm = 0.0;   // program units
  double slow_feed = 0.0;    // per minute, program units
  Eigen::Vector3d nominal_trigger = Eigen::Vector3d::Zero();  // Probe: expected ball centre
  std::string pose_name;                                      // Probe: e.g. "III"
};

/// Decimals of the RotaryLinear lengths: 004 Table 1 writes inch to 0.0001; mm to 0.001.
inline int rotaryLinearDecimals(Unit unit) { return unit == Unit::Inch ? 4 : 3; }

struct Program {
  std::string name;                  // e.g. "ROTACAL_TOUCH154"
  std::string cycle;
  Unit unit = Unit::Millimetre;
  std::vector<std::string> header;   // comment lines for the operator
  std::vector<char> rotary_axes;     // letters used, e.g. {'A', 'C'}
  int probe_tool = 0;                // 0: no tool change / length compensation
  std::string results_file;          // base name of the file the program writes
  int point_count = 0;
  /// The program number in the control's memory (the O-word of Fanuc, Haas and Okuma). Each
  /// cycle states its own, so that two cycles' programs never overwrite each other; 0 = none
  /// (a dialect that needs one refuses the program).
  int number = 0;
  std::vector<Op> ops;
};

/// What a program's text must show, as its neutral program states it: the dialect checkers
/// hold the text to this and never ask which cycle wrote it.
struct Shape {
  size_t probes = 0;          // Probe ops, as written (a repeated block counts once)
  size_t reads = 0;           // Read ops (external device readings), as written
  bool inverse_time = false;  // some Mode op switches to inverse-time feed (G93)
  int number = 0;             // Program::number
};
Shape shapeOf(const Program& program);

}  // namespace rotacal::nc
