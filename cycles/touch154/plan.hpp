#pragma once
// The 154-point cycle of 000 Sec. 4.2 on the square-column test piece.
//
// Point layout (000 Fig. 6 is missing from the source; this layout fits its text and is a
// parameter): targets k = 1..4 on the +X face, 5..8 on +Y, 9..12 on -X, 13..16 on -Y (four
// points per side face at one height, `side_depth_mm` below the top, at `side_offsets_mm` along
// the face), and k = 17..28 on the top face: the 4 x 4 grid `top_offsets_mm` x `top_offsets_mm`
// around the top centre without its inner 2 x 2 (12 points).
// Poses I..IV: A = 0, C = 0/90/180/270, all 28 targets. Poses V..VII: A = -90, C = 90/180/270,
// only what a vertical stylus reaches: the face must not point down, and on a face approached
// sideways the probe body (stylus_length above the ball) must clear the piece's top by
// body_clearance. With the defaults that leaves 14 targets per pose, 154 in all.
#include "core/probe_plan.hpp"

namespace rotacal {

struct Touch154Layout {
  std::vector<double> top_offsets_mm{-35, -15, 15, 35};
  bool top_ring = true;  // drop the inner 2 x 2 of the top grid
  std::vector<double> side_offsets_mm{-35, -15, 15, 35};
  double side_depth_mm = 20.0;

  static Touch154Layout fromOptions(const CycleOptions& options);
  CycleOptions toOptions() const;
};

ProbePlan makeTouch154Plan(const MachineModel& machine, const CycleOptions& options);

/// What a PLAN.json of this cycle must satisfy beyond the format (the cycle's identity).
PlanRules touch154PlanRules();

}  // namespace rotacal
