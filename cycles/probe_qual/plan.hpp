#pragma once
// probe_qual (ISO 230-10's idea, Heidenhain's sphere-radius check): the
// probe's qualification on the calibration sphere of the one_sphere cycle, in the approach
// directions rotacal's touch cycles use: horizontal (`azimuths` of them, from +X) and down (-Z,
// the top). One pose (every rotary axis at 0). Each horizontal approach touches the sphere at
// every contact latitude of `latitude_list` (0 = the equator; above it the contact normal tilts
// up while the approach stays horizontal, which is what separates the top's pretravel from the
// sphere's height), the top once; the whole set `repeats` times in the same order (a drift then
// follows the clock, not the direction), each repeat a pose of its own at the same angles. A start `approach_mm` back along a horizontal approach
// at a latitude above the equator lies nearer the sphere: a latitude whose start the program
// verifier would call too near (core: min(clearance, approach) less the compensation allowance)
// is refused.
// Named probe_qual, not probe: a cycle's name is a word no file outside its folder may use
// (tests/cycles/layering_test.cpp), and "probe" is everywhere.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/probe_plan.hpp"

namespace rotacal {

struct ProbeQualLayout {
  Eigen::Vector3d center_w_mm = Eigen::Vector3d(120.0, 0.0, 80.0);  // the one_sphere cycle's default
  double radius_mm = 12.7;
  double stem_length_mm = 60.0;
  double stem_diameter_mm = 8.0;
  int azimuths = 8;                              // horizontal approaches, from +X every 360 / azimuths deg
  std::vector<double> latitude_deg = {0.0, 25.0};  // contact latitudes of the horizontal approaches
  int repeats = 5;

  /// Overridden by center_w_mm ("x,y,z"), radius_mm, stem_length_mm, stem_diameter_mm,
  /// azimuths (4-36), latitude_list (deg, 0-80), repeats (2-100). Throws std::invalid_argument.
  static ProbeQualLayout fromOptions(const CycleOptions& options);
  CycleOptions toOptions() const;

  /// One touch of a repeat: its approach direction (index into approaches(): azimuths, then the
  /// top) and its contact's outward normal (workpiece frame = machine frame at the pose).
  struct Touch {
    int approach = 0;
    Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
    std::string name;  // "az 45 lat 25", "top"
  };
  /// The touches of one repeat, in the order run; a point's `target` is its index + 1.
  std::vector<Touch> touches() const;
  /// The approach directions (unit, toward the sphere): `azimuths` horizontal ones, then -Z.
  std::vector<Eigen::Vector3d> approaches() const;
  std::vector<std::string> approachNames() const;  // "-X", "az 45", ..., "-Z (top)"
};

ProbePlan makeProbeQualPlan(const MachineModel& machine, const CycleOptions& options);

/// The plan's layout read back. Throws std::invalid_argument.
ProbeQualLayout probeQualLayoutOf(const ProbePlan& plan);

/// What a PLAN.json of this cycle must satisfy beyond the format (the cycle's identity).
PlanRules probeQualPlanRules();

}  // namespace rotacal
