#pragma once
// The most a user can ask of rotacal, stated once. Every count a user sets (list lengths, angle
// steps that divide a turn, repeats, Monte Carlo runs) is checked against these before anything
// is built, so that a typo fails at once with the option's name instead of running for hours or
// exhausting memory; and every number read from a file is checked against a plausible range so
// that nonsense cannot reach the arithmetic (README "Limits", docs/conventions.md).
#include <string>

namespace rotacal {

// ---- Counts -------------------------------------------------------------------------------
// Touches (or readings) in one plan. The largest bundled use is the three-sphere cycle at 1 deg steps (5400
// touches); a plan this size still analyses in seconds.
constexpr int kMaxPlanPoints = 10000;
// Rotary poses in one plan: one per degree of a full turn.
constexpr int kMaxPlanPoses = 360;
// Values in one list option (top_offsets_mm, c_list, theta_list, other_deg, --a-deg, ...).
constexpr int kMaxListValues = 360;
// Repeats of a measurement: results files given to analyze/diagnose, R-test cycles of a
// thermal test, tool-tip sweeps.
constexpr int kMaxRepeats = 1000;
// Monte Carlo runs of `uncertainty` and `design` (1000 in 000), and worker threads.
constexpr int kMaxMonteCarloRuns = 1000000;
constexpr int kMaxThreads = 256;
// Exchange passes of `design` after its greedy selection.
constexpr int kMaxExchangePasses = 100;

// ---- Values read from MACHINE.json, PLAN.json, TRUTH.json and the command line --------------
// Machine coordinates, strokes and artefact positions: 100 m covers any machine tool.
constexpr double kMaxCoordinateMm = 100000.0;
// Rotary angles and strokes: a multi-turn axis may count many turns, but not without bound.
constexpr double kMaxAngleDeg = 100000.0;
// Probe ball diameter, stylus length and the clearances around the artefact.
constexpr double kMaxProbeLengthMm = 1000.0;
// A touch probe's repeatability (one sigma): beyond this it is not a calibration probe.
constexpr double kMaxRepeatabilityUm = 100.0;
// Feeds (mm/min) and rotary speeds (deg/min).
constexpr double kMaxFeedPerMin = 1000000.0;
// T and H words of the probe.
constexpr int kMaxToolNumber = 9999;
// Clock of the controllers' results files: seconds since 2000-01-01; 1e10 s is year 2316.
constexpr double kMaxClockSeconds = 1e10;
// Simulated machine errors (TRUTH.json): beyond these the touches miss the artefact.
constexpr double kMaxLocationErrorUm = 10000.0;
constexpr double kMaxAngleErrorMdeg = 10000.0;
// Probe noise of the simulator (--noise-um, probe_noise_um) and pre-travel.
constexpr double kMaxNoiseUm = 1000.0;
// Contributor uncertainties (CONTRIB.json), in their own units: um, um/m or mdeg.
constexpr double kMaxContributorU = 10000.0;

}  // namespace rotacal
