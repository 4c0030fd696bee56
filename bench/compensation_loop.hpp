#pragma once
// The compensation loop closed on one simulated machine: shared by
// rotacal_compensation_loop_bench (50 machines, printed) and the test that asserts it on a few.
#include <cstdint>
#include <string>

#include "core/machine.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct LoopSetup {
  MachineModel machine;
  ProbePlan touch154, spheres3;
};

LoopSetup loopSetup(const std::string& machine_file);

struct LoopResult {
  // Largest tool-point deviation from the nominal, seen from the workpiece, um.
  double spheres_before_um = 0.0, spheres_after_um = 0.0;
  double spheres_after_spheres3_only_um = 0.0;  // compensated with the spheres3 report alone
  double path_before_um = 0.0, path_after_um = 0.0;
  int pieces = 0;  // pieces of the path's moves after splitting (24 moves)
};

/// Draws machine `seed` (location errors, the C axis's component errors of 001's size, an error
/// motion of the A axis no cycle models), measures it with both cycles at `noise_um`, analyzes,
/// compensates and evaluates. Throws what the cycles throw.
/// `with_eya` false: the same machine without the A axis's error motion (what limits the worst
/// machines, measured by comparing the two).
LoopResult runLoop(const LoopSetup& setup, std::uint64_t seed, double noise_um, bool with_eya = true);

}  // namespace rotacal
