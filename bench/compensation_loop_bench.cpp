// rotacal_compensation_loop_bench: the compensation loop closed on simulated machines.
// Each machine draws location errors, the C axis's component errors (001's size) and
// an effect no cycle models (an error motion of the A axis); the touch154 and spheres3 cycles
// are simulated on it with probe noise, analyzed as `analyze` does, their REPORT.json read as
// `compensate --report a --report b` reads them, and the volumetric error evaluated on the true
// machine before and after compensation:
//  - spheres: the three spheres' centres at every 30 deg of C, A = 0 (001 Sec. 5's figure),
//  - path: a five-axis path (the tool at radius 150 mm, 100 mm above the table, A tilting
//    between 0 and -90 deg while C turns, 15 deg steps of both), every move compensated and split
//    as `compensate` does, evaluated at 50 points along each piece.
// The truth is written out here as its own HTM product; the code under test never sees it.
// Printed, not asserted (tests/postproc has the assertion on a few machines).
// Run: build/bench/rotacal_compensation_loop_bench [machines=50] [noise_um=0.7] [no-eya]
// (no-eya: the same machines without the A axis's error motion, to see what limits the worst)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/compensation_loop.hpp"

using namespace rotacal;

int main(int argc, char** argv) {
  const int machines = argc > 1 ? std::atoi(argv[1]) : 50;
  const double noise_um = argc > 2 ? std::atof(argv[2]) : 0.7;
  const bool with_eya = !(argc > 3 && std::string(argv[3]) == "no-eya");
  LoopSetup setup = loopSetup(ROTACAL_SOURCE_DIR "/examples/machines/ac_trunnion.json");
  std::vector<double> red_s, red_p, red_s3, after_s, after_p, before_s, before_p;
  std::printf("machine  spheres before -> after (um)  [spheres3 alone]  path before -> after (um)\n");
  for (int m = 0; m < machines; ++m) {
    const LoopResult r = runLoop(setup, static_cast<std::uint64_t>(m), noise_um, with_eya);
    std::printf("%4d     %6.2f -> %5.2f  [%5.2f]        %6.2f -> %5.2f\n", m, r.spheres_before_um, r.spheres_after_um,
                r.spheres_after_spheres3_only_um, r.path_before_um, r.path_after_um);
    red_s.push_back(1.0 - r.spheres_after_um / r.spheres_before_um);
    red_s3.push_back(1.0 - r.spheres_after_spheres3_only_um / r.spheres_before_um);
    red_p.push_back(1.0 - r.path_after_um / r.path_before_um);
    after_s.push_back(r.spheres_after_um);
    after_p.push_back(r.path_after_um);
    before_s.push_back(r.spheres_before_um);
    before_p.push_back(r.path_before_um);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  auto minOf = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  auto maxOf = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
  std::printf("\n%d machines, probe noise %.2f um%s (max volumetric error per machine):\n", machines, noise_um,
              with_eya ? "" : ", without the A axis's error motion");
  std::printf("  spheres (A = 0, 12 C angles): before median %.2f um, after median %.2f um, worst %.2f um; "
              "reduction median %.1f %%, worst %.1f %%\n",
              median(before_s), median(after_s), maxOf(after_s), 100 * median(red_s), 100 * minOf(red_s));
  std::printf("  spheres, spheres3 report alone: reduction median %.1f %%, worst %.1f %%\n", 100 * median(red_s3),
              100 * minOf(red_s3));
  std::printf("  five-axis path (15 deg steps): before median %.2f um, after median %.2f um, worst %.2f um; "
              "reduction median %.1f %%, worst %.1f %%\n",
              median(before_p), median(after_p), maxOf(after_p), 100 * median(red_p), 100 * minOf(red_p));
  return 0;
}
