#pragma once
// spheres3's and spaceframe's catalogued causes on machines as their contributors file declares
// them: each machine drawn by the independent generator (bench/independent_machine.hpp) from the
// cycle's bundled example (ac_trunnion.json and the contributors file it names; spaceframe with
// phi_list=-90,-45,0), the effect added through rotacal's exact simulator
// (bench/drawn_effect.hpp), judged as the cycle's `diagnose` judges: against the declaration the
// machine was drawn from. Shared by rotacal_diagnose_bench (spheres3_drawn, spaceframe_drawn) and
// tests/bench/hidden_effects_spheres_test.cpp, which run them on different seeds.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bench/independent_machine.hpp"
#include "core/contributors.hpp"
#include "core/judge.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "cycles/spaceframe/noise.hpp"
#include "cycles/spheres3/analyze.hpp"

namespace rotacal::drawn {

using Hide = std::function<void(Truth*)>;

/// One catalogued cause hidden on a drawn machine, at `k` times the clean world's size.
struct SphereEffect {
  std::string what;   // the row's name, with its size
  Hide hide;
  std::string cause;  // the judge's cause name ("" for none)
  std::string param;  // its parameter checked against `truth` ("" for none)
  double truth = 0.0;
  int repeats = 1;    // runs of the plan (the drift needs repeats and a clock)
};

/// spheres3 on ac_trunnion.json, one run (or `repeats`, 30 min apart, as the clean world's drift).
struct Spheres3World {
  Spheres3World();
  MachineModel machine;
  ContributorSet declared;
  ProbePlan plan;
  Spheres3Noise noise;
  /// What the generator draws (all the declared contributors; the bench switches some off to
  /// trace what hides an effect, ROTACAL_BENCH_DRAW_OFF). The judge still reads the declaration.
  independent::DrawOptions draw;
  static constexpr double kRepeatEvery_s = 1800.0;
  JudgeSummary judge(std::uint64_t seed, const Hide& effect, int repeats) const;
};

/// The spheres3 catalog at k x the clean world's sizes (bench/spheres3_judge_bench.cpp's rows).
std::vector<SphereEffect> spheres3Effects(double k);

/// spaceframe on ac_trunnion.json with phi_list=-90,-45,0, one run, the cycle's outlier screen
/// first (as `diagnose` does). Throws std::runtime_error when the baseline does not converge
/// (where `diagnose` refuses).
struct SpaceframeWorld {
  SpaceframeWorld();
  MachineModel machine;
  ContributorSet declared;
  ProbePlan plan;
  SpaceframeNoise noise;
  /// What the generator draws (all the declared contributors; the bench switches some off to
  /// trace what hides an effect, ROTACAL_BENCH_DRAW_OFF). The judge still reads the declaration.
  independent::DrawOptions draw;
  JudgeSummary judge(std::uint64_t seed, const Hide& effect) const;
};

/// The spaceframe catalog at k x the clean world's sizes (rotacal_diagnose_bench spaceframe's rows,
/// and the frame's temperature).
std::vector<SphereEffect> spaceframeEffects(double k);

/// The bench modes: clean seeds, then each effect at 1, 3 and 10 x on `effect_seeds` machines,
/// printed as docs/diagnosis.md's tables.
void spheres3DrawnBench(int clean_seeds, int effect_seeds);
void spaceframeDrawnBench(int clean_seeds, int effect_seeds);

}  // namespace rotacal::drawn
