#pragma once
// What the touch-probe cycles share between them: the controller's results are read through the
// dialect, and simulated by the exact simulator (full HTMs, ball-on-surface contact).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cycles/cycle.hpp"

namespace rotacal {

/// A plan option "x,y,z" (mm). Throws std::invalid_argument naming the option.
Eigen::Vector3d parseVec3Option(const std::string& key, const std::string& text);

/// A list option "a,b,c" as parseNumberList reads it back ({:g} each).
std::string numberListOption(const std::vector<double>& values);

/// The face a contact with outward normal n_m (machine frame) reports: the top, or the side the
/// normal points to most.
Face faceOfNormal(const Eigen::Vector3d& n_m);

/// The last step of a touch cycle's plan: throws std::invalid_argument naming the first point
/// beyond the machine's strokes, then estimates the points' times.
void finishTouchPlan(ProbePlan& plan);

/// Every results file of the request, read by the dialect's reader against the plan.
std::vector<MeasurementRun> readProbeRuns(const ProbePlan& plan, const std::vector<InputFile>& results,
                                          const DialectIO& dialect);

/// The triggers of every plan point on the machine of the truth file, written as the dialect's
/// results. Throws InputError naming the truth file when the probe would not trigger.
Simulated simulateProbing(const SimulateRequest& request);

}  // namespace rotacal
