#pragma once
// The screen of gross readings of the tooltip cycle (a laser glitch, a chip on the sphere: one
// reading tens of micrometres or millimetres off). Each read value (the transverse component and
// Z of every reading apart) is tested against what every other value predicts for it under the
// declared noise (cycles/tooltip/noise.hpp: the per-reading laser part and the shared part the
// linear axes and the beams leave), the generalized least squares deletion residual of the joint
// model (core/declared_noise.hpp deletionStatistics), Bonferroni over the values at
// kTooltipScreenAlpha, worst first and refitted after each (core/outliers.hpp).
// What leaves is the whole READING (both components): each commanded angle has its own angular
// error, which takes up the tangential part of a glitch, so a glitch shows only in the radial
// combination of its reading's two components and their deletion residuals are alike; leaving
// one component out would let the angular error absorb the other one's glitch entirely. With one
// run, the angle of a reading left out then has no value (null in REPORT.json, said so); repeats
// still estimate it.
// At most kTooltipScreenMaxFraction of the values tested are screening steps (one reading each:
// one reading of a static 0..90 deg run of 18); more still beyond is not a few glitches but a
// model that does not fit or a noise declared too small: nothing is left out and analyze holds
// its values back.
#include <string>
#include <utility>
#include <vector>

#include "core/declared_noise.hpp"
#include "core/json_io.hpp"
#include "core/outliers.hpp"
#include "cycles/tooltip/plan.hpp"

namespace rotacal {

constexpr double kTooltipScreenAlpha = 0.01;        // a clean run loses a reading in at most 1 %
constexpr double kTooltipScreenMaxFraction = 0.05;  // beyond: the model or the noise, not glitches

struct TooltipScreen {
  OutlierOptions options;
  OutlierScreen screen;  // run (0-based), point_id = 2 k + c (k the plan point, c = 0 transverse, 1 Z)
  /// (run, plan point) of the readings left out, sorted.
  std::vector<std::pair<int, int>> excludedReadings() const;
};

TooltipScreen screenTooltipReadings(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const DeclaredNoise& noise);

/// The runs with the screen's readings left out (both components NaN: not fitted); unchanged when
/// the screen found too many (nothing is left out then).
std::vector<TooltipRun> withoutScreened(const std::vector<TooltipRun>& runs, const TooltipScreen& s);

/// REPORT.json's `outliers` block, and its one line.
Json tooltipScreenJson(const ProbePlan& plan, const TooltipScreen& s);
std::string tooltipScreenText(const ProbePlan& plan, const TooltipScreen& s);

}  // namespace rotacal
