#pragma once
// The three-sphere cycle of 001 (Chen, Yang, Liu): three calibration spheres fixed near the edge
// of the C table at different heights, each touched from +X, -X, +Y, -Y (at its equator) and
// from above (-Z), at N C angles c_start + n * c_step_deg (001: 12 angles, 30 deg apart). The
// tilt axis (A or B) stays at 0.
//
// 001's Fig. 4 / Fig. 8 (the exact layout) are missing from the source; these defaults fit its
// text and are options: spheres at `edge_radius_mm` (table radius - 30 mm) from the C axis at
// 90, 210 and 330 deg (away from the test piece of the bundled A/C machine), centres at
// z = 60, 100, 140 mm, radius 19 mm (001: "approximately 18.999 mm").
// Touch order at each angle: sphere 1..3, each +X, +Y, -X, -Y, top (target k = 5 (i-1) + j).
#include <array>

#include "core/probe_plan.hpp"

namespace rotacal {

struct Spheres3Layout {
  double c_step_deg = 30.0;
  double c_start_deg = 0.0;
  double radius_mm = 19.0;                       // nominal sphere radius R
  std::array<Eigen::Vector3d, 3> centers_w_mm;   // nominal centres, workpiece frame

  /// Defaults for a machine (edge radius from its table), overridden by the options
  /// c_step_deg, c_start_deg, radius_mm, sphere1_w_mm, sphere2_w_mm, sphere3_w_mm ("x,y,z").
  static Spheres3Layout fromOptions(const MachineModel& machine, const CycleOptions& options);
  CycleOptions toOptions() const;
  int angleCount() const;  // 360 / c_step_deg; throws std::invalid_argument unless a whole number >= 4
};

/// The approach directions of the five touches of one sphere (machine frame, the direction the
/// ball moves): -X (touches the +X side), -Y, +X, +Y, -Z.
const std::array<Eigen::Vector3d, 5>& spheres3Approaches();

ProbePlan makeSpheres3Plan(const MachineModel& machine, const CycleOptions& options);

/// What a PLAN.json of this cycle must satisfy beyond the format (the cycle's identity).
PlanRules spheres3PlanRules();

}  // namespace rotacal
