// The compensation loop closed (issue 18, item 5) on a few simulated machines: the truth (location
// errors, the C axis's error motions of 001's size, an error motion of the A axis no cycle
// models) is written out in bench/compensation_loop.cpp as its own HTM product; the touch154 and
// spheres3 cycles measure it with 0.7 um probe noise, their reports are combined as `compensate`
// combines them, and the tool point is evaluated on the true machine. The 50-machine figures are
// the bench's (README); here the claim is asserted on 6 machines.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "bench/compensation_loop.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

TEST(CompensationLoop, MeasuredErrorsCompensatedCutTheVolumetricErrorByNinetyPercent) {
  const LoopSetup setup = loopSetup(test::sourcePath("examples/machines/ac_trunnion.json"));
  std::vector<double> spheres, path, spheres3_alone;
  for (std::uint64_t m = 0; m < 6; ++m) {
    const LoopResult r = runLoop(setup, m, 0.7);
    std::printf("machine %d: spheres %.2f -> %.2f um (spheres3 alone %.2f um), path %.2f -> %.2f um in %d pieces\n",
                static_cast<int>(m), r.spheres_before_um, r.spheres_after_um, r.spheres_after_spheres3_only_um,
                r.path_before_um, r.path_after_um, r.pieces);
    spheres.push_back(1.0 - r.spheres_after_um / r.spheres_before_um);
    path.push_back(1.0 - r.path_after_um / r.path_before_um);
    spheres3_alone.push_back(1.0 - r.spheres_after_spheres3_only_um / r.spheres_before_um);
    // The after figure is the probe noise propagated, the unmodelled A-axis motion (1 um) and the
    // printing: a few um, never the tens before.
    EXPECT_LT(r.spheres_after_um, 4.0);
    EXPECT_LT(r.path_after_um, 4.0);
    EXPECT_GT(r.spheres_before_um, 10.0);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  EXPECT_GT(median(spheres), 0.90);
  EXPECT_GT(median(path), 0.90);
  // The three-sphere report alone cannot see the table's height or the C axis's angular zero
  // (sphere positions for that cycle): it must do visibly worse, which is why the reports combine.
  EXPECT_LT(median(spheres3_alone), median(spheres) - 0.1);
}

}  // namespace
}  // namespace rotacal
