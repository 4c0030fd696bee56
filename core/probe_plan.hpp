#pragma once
// A probing plan: the ordered touches of a cycle with everything the program writer, the
// simulator and the identification need (contract.md, PLAN.json). Poses are in the papers'
// convention; positions are ball-centre machine coordinates (origin at the rotary-axis
// intersection), mm.
#include <Eigen/Core>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/artefact.hpp"
#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/measurement.hpp"

namespace rotacal {

/// A calibration sphere touched by a sphere cycle (three table spheres, a space frame): its id, its nominal
/// centre in the workpiece (table) frame and its radius (contract.md, PLAN.json "sphere").
struct SphereTarget {
  int id = 0;
  Eigen::Vector3d center_w_mm = Eigen::Vector3d::Zero();
  double radius_mm = 0.0;
};

struct ProbePoint {
  int id = 0;                   // 1-based, order of probing
  std::string pose_name;        // e.g. "I" .. "VII" (000 Fig. 5)
  Pose pose;                    // commanded angles, deg, papers' convention
  int target = 0;               // the point on the artefact (000 Fig. 6 index k), same at every pose
  Face face = Face::Top;
  Eigen::Vector3d contact_w_mm = Eigen::Vector3d::Zero();  // nominal contact, workpiece frame
  Eigen::Vector3d normal_w = Eigen::Vector3d::UnitZ();     // outward normal, workpiece frame
  Eigen::Vector3d trigger_m_mm = Eigen::Vector3d::Zero();  // ball centre at trigger, perfect machine
  Eigen::Vector3d approach_m = -Eigen::Vector3d::UnitZ();  // unit direction of the probing move
  double t_s = 0.0;                                        // planned seconds from cycle start
  std::optional<SphereTarget> sphere;                      // set on sphere cycles: the touched sphere

  Eigen::Vector3d start_m(double approach_mm) const { return trigger_m_mm - approach_mm * approach_m; }
  Eigen::Vector3d end_m(double overtravel_mm) const { return trigger_m_mm + overtravel_mm * approach_m; }
};

/// A named pose and the heights used around it.
struct PlanPose {
  std::string name;
  Pose pose;
  double safe_z_mm = 0.0;  // ball-centre Z for moves between points at this pose
};

struct ProbePlan {
  std::string cycle;
  MachineModel machine;
  std::map<std::string, std::string> options;  // the cycle options used (after defaults)
  std::vector<PlanPose> poses;
  double index_z_mm = 0.0;  // ball-centre Z at which the rotary axes may index
  std::vector<ProbePoint> points;

  const ProbePoint* findPoint(int id) const;
  const PlanPose& poseByName(const std::string& name) const;  // throws std::invalid_argument
};

/// Cycle options from `--set KEY=VALUE`.
using CycleOptions = std::map<std::string, std::string>;

Json planToJson(const ProbePlan& plan);
/// What a plan's cycle requires of it beyond the file format: the cycle states it
/// (Cycle::planRules), the loader checks it and names FILE:LINE.
struct PlanRules {
  bool heights = true;           // safe heights clear what is touched (false: no probing moves)
  bool artefact_touched = true;  // the machine's artefact is what the probe moves over
  /// false: a pose's safe height need clear only what is touched at it, the cycle keeping its
  /// way clear of the artefact sideways (and the program verifier checking every move against
  /// it); the index height still clears the artefact.
  bool safe_height_over_artefact = true;
  int spheres = 0;               // > 0: every touch names sphere 1..spheres, >= 4 of each per pose
  std::function<void(const ProbePlan&)> check_options;  // the options the cycle reads back; throws
};

ProbePlan planFromJson(const JsonDoc& doc, const PlanRules& rules = {});
ProbePlan loadPlan(const std::string& path, const PlanRules& rules = {});

/// One move of a cycle's path: the one move model of every cycle (the probing paths and the
/// R-test's dwell-and-read path). ClimbZ moves Z alone; Position and Retract are G1 moves at the
/// positioning feed; Dwell waits; Read takes the R-test's reading where it stands.
struct Waypoint {
  enum class Kind { ClimbZ, Rapid, Position, Index, Probe, Retract, Dwell, Read } kind;
  Eigen::Vector3d position_m;  // ball (or R-test sphere) centre, machine frame, mm
  Pose pose;                   // rotary pose in force (deg, papers' convention)
  int point_id = 0;            // Probe/Retract/Read (Read: 0 = the R-test's reset reading)
  double seconds = 0.0;        // Dwell
};
/// Positions the probe passes through, in order, for the whole plan (shared by the time
/// estimate, the program writer and the stroke check).
std::vector<Waypoint> plannedPath(const ProbePlan& plan);

/// The time of one move from (from_m, pose_from) at the machine's feeds: rapid, positioning,
/// indexing at the rotary feed (the largest angle), dwell. 0 for Probe and Read: how far a
/// probing move runs is the cycle's to say.
double moveTime_s(const Waypoint& move, const Eigen::Vector3d& from_m, const Pose& pose_from, const Feeds& feeds);

/// Checks every waypoint and pose against the machine's strokes; returns the violations.
std::vector<std::string> strokeViolations(const ProbePlan& plan);
/// The one stroke check every path model uses: a linear-axis position (`where` is appended to
/// each line) and a pose's rotary angles (continuous axes have none), one line per violation.
void linearStrokeViolations(const MachineModel& machine, const Eigen::Vector3d& position_m, const std::string& where,
                            std::vector<std::string>* out);
void rotaryStrokeViolations(const MachineModel& machine, const Pose& pose, const std::string& pose_name,
                            std::vector<std::string>* out);

/// Fills t_s of every point from the path, the feeds and the rotary speed.
void estimateTimes(ProbePlan& plan);

/// Splits "a,b,c" into doubles; throws std::invalid_argument naming the option, also beyond
/// kMaxListValues values (core/limits.hpp).
std::vector<double> parseNumberList(const std::string& key, const std::string& text);
double parseNumber(const std::string& key, const std::string& text);

/// Throws std::invalid_argument naming `options` (what the user set, e.g. "option c_step_deg =
/// 1e-06") when a plan of that many touches or poses would exceed kMaxPlanPoints or
/// kMaxPlanPoses. Called with the predicted counts before a plan is built.
void requirePlanSize(const std::string& options, double points, double poses);

/// Measured scalar of a trigger: its displacement along the approach from the nominal trigger (mm).
inline double alongApproach(const ProbePoint& point, const TriggerPoint& trigger) {
  return point.approach_m.dot(trigger.position_m_mm - point.trigger_m_mm);
}

}  // namespace rotacal
