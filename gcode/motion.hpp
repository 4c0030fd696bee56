#pragma once
// What a program does, read back from its text: the moves, probing moves, no-trigger checks and
// program numbers of any dialect, in one neutral form (controllers/motion_reader.hpp reads each
// dialect into it; postproc/program_check.hpp simulates it on a machine). The reader resolves
// what depends on the dialect's syntax (which word is a probing move, which statements are a
// no-trigger check, the modal motion of a block without a G word, the unit and distance modes);
// the simulation (absolute positions, feeds in force, clearances) is left to the checker.
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rotacal::nc {

struct Motion {
  enum class Kind {
    Rapid,          // G0 / FMAX: positioning at rapid
    Feed,           // G1 / L .. F: a move at the feed in force (linear and/or rotary words)
    Probe,          // a guarded probing move (G31, G38.x, MEAS=1 G1, TCH PROBE)
    Check,          // a no-trigger check of the last probing move
    Setting,        // a block that sets a feed or a mode without moving (e.g. "G91 G01 G93 F2.")
    ProgramNumber,  // the program's number (Fanuc/Haas/Okuma O word)
    End,            // end of the main program (M2, M30, END PGM): what follows runs only after a jump
    Unreadable,     // a block the checker cannot follow (arc, expression, offset change): `problem`
  } kind = Kind::Setting;
  int line = 0;  // 1-based line of the program text

  // Rapid, Feed, Probe: the axis words as written (X Y Z in program units, rotary letters in the
  // controller's degrees), absolute unless `incremental`.
  std::vector<std::pair<char, double>> words;
  bool incremental = false;    // G91 in force
  bool inch = false;           // G20 / G70 in force (program units are inches)
  bool inverse_time = false;   // G93 in force
  std::optional<double> feed;  // F on this block (per minute, or 1/min under G93)
  /// Rapid: Z alone to this far (program units, <= 0) from the machine's Z reference, the top of
  /// its stroke (G28 / G30 with G91 Z0: 0; G53 Z-10.: -10), the words empty. Where the program's
  /// zero is does not matter: the reference is a place on the machine.
  std::optional<double> z_from_reference;

  // Probe
  bool alarms = false;          // the control stops the program by itself when nothing triggers (G38.2, G38.4)
  bool feed_from_control = false;  // the probing feed is the control's (Heidenhain touch-probe table), not an F word
  /// Heidenhain cycle 0: the words are the pre-position and the move runs along one axis (0..2)
  /// in direction `travel_sign` for the maximum travel set in the control's touch-probe table.
  std::optional<int> travel_axis;
  int travel_sign = 1;

  // Check: the end point its statements compare the probe's stop with, per axis X Y Z (program
  // units; nullopt for an axis it does not compare). All nullopt: a check of the trigger flag
  // alone (#5070, $AC_MEA), which needs no end point.
  std::array<std::optional<double>, 3> check_end;

  int number = 0;       // ProgramNumber
  std::string problem;  // Unreadable
};

}  // namespace rotacal::nc
