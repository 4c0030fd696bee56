#pragma once
// What the touch-probe cycles share between them: the controller's results are read through the
// dialect, and simulated by the exact simulator (full HTMs, ball-on-surface contact).
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cycles/cycle.hpp"
#include "cycles/judge_contract.hpp"
#include "cycles/options.hpp"

namespace rotacal {

/// The face a contact with outward normal n_m (machine frame) reports: the top, or the side the
/// normal points to most.
Face faceOfNormal(const Eigen::Vector3d& n_m);

/// Where a sphere on the table (centre c_m, radius R, machine frame at the pose T = T_m_w) has
/// the machine's test piece within `reach` (the side starts' distance from the centre) plus the
/// ball and the clearance, unless the piece lies wholly below the lowest touch: the reason, or ""
/// when the piece is clear. Every move of a pose round such a sphere (down from the index height
/// at a start, start to start, up again) stays within that reach, so the pose's safe height need
/// only clear the sphere (PlanRules::safe_height_over_artefact; the program verifier still checks
/// every move against the piece).
std::string sphereReachRefusal(const MachineModel& machine, const Eigen::Isometry3d& T_m_w, const Eigen::Vector3d& c_m,
                               double R, double reach);

/// The radius about the rotary axes' intersection that everything on the table sweeps when it
/// indexes: the table, a sphere at c_w with radius R, the test piece. Under a spindle head the
/// table turns C alone: the highest point of the sphere and the test piece.
double tableSweepRadius(const MachineModel& machine, const Eigen::Vector3d& c_w, double R);

/// The last step of a touch cycle's plan: throws std::invalid_argument naming the first point
/// beyond the machine's strokes, then estimates the points' times.
void finishTouchPlan(ProbePlan& plan);

/// A plan point's trigger in one results file.
struct PlannedTrigger {
  size_t point_index = 0;  // in plan.points
  int run = 0;             // the results file's index
  const TriggerPoint* trigger = nullptr;
  /// The controller's clock, else the plan's time from the run's start, the runs taken back to
  /// back (run x the plan's last time).
  double t_s = 0.0;
};

/// Every plan point's trigger of every run, each run in plan order. Throws InputError naming the
/// run's file when it has no trigger for some plan point.
std::vector<PlannedTrigger> triggersInPlanOrder(const ProbePlan& plan, const std::vector<MeasurementRun>& runs);

/// Every results file of the request, read by the dialect's reader against the plan.
std::vector<MeasurementRun> readProbeRuns(const ProbePlan& plan, const std::vector<InputFile>& results,
                                          const DialectIO& dialect);

/// `diagnose` of a touch cycle whose baseline is one fit judged as a whole (cycles/judge_contract.hpp):
/// the request's results read through the dialect, judged at the request's alpha by `judged`, and
/// the documents under the cycle's name. (A name, not the Cycle: the fuzz harnesses link this file
/// without the registry, and the sanitizer's vptr check would need Cycle's type information.)
CycleDocuments judgedFitDocuments(std::string_view cycle, const DiagnoseRequest& request,
                                  JudgedFit (*judged)(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                                      const JudgeOptions& options));

/// The triggers of every plan point on the machine of the truth file, written as the dialect's
/// results. Throws InputError naming the truth file when the probe would not trigger.
Simulated simulateProbing(const SimulateRequest& request);

}  // namespace rotacal
