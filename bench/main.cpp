// rotacal's speed figures: printed, never asserted. A small harness on std::chrono:
// each figure is the median (and the minimum) of repeated timings after one warm-up call.
//
//   build-dir/bench/rotacal_bench [--quick]
//
// The figures: the Monte Carlo of the 154-point chain (1000 runs, linearised, per estimator and
// all together, with and without the per-contributor table, on all cores and on one), building
// the linear chain, one identification by each estimator, one run of the exact chain, plan
// generation and design, program generation, and parsing a 10 MB results dump.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "cycles/cycle.hpp"
#include "controllers/dialect.hpp"
#include "cycles/touch154/causes.hpp"
#include "cycles/touch154/closed_form.hpp"
#include "core/contributors.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/machine.hpp"
#include "cycles/touch154/design.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "cycles/touch154/uncertainty.hpp"
#include "postproc/probe_program.hpp"

#ifndef ROTACAL_SOURCE_DIR
#define ROTACAL_SOURCE_DIR "."
#endif

namespace {

using namespace rotacal;

struct Figure {
  double median_ms = 0, min_ms = 0;
  int repeats = 0;
};

template <class F>
Figure timeIt(int repeats, F&& f) {
  f();  // warm-up: caches, first-touch allocation, thread start-up paths
  std::vector<double> ms;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return {ms[ms.size() / 2], ms.front(), repeats};
}

void print(const std::string& what, const Figure& f) {
  std::printf("  %-64s %10.3f %10.3f %6d\n", what.c_str(), f.median_ms, f.min_ms, f.repeats);
  std::fflush(stdout);
}

/// Times and prints one figure; a figure whose code throws is reported, not fatal.
template <class F>
Figure figure(const std::string& what, int repeats, F&& f) {
  try {
    const Figure r = timeIt(repeats, f);
    print(what, r);
    return r;
  } catch (const std::exception& e) {
    std::printf("  %-64s failed: %s\n", what.c_str(), e.what());
    return {};
  }
}

UncertaintyOptions mc(int runs, bool combined_only, std::vector<UncertaintyMethod> methods, int threads) {
  UncertaintyOptions o;
  o.runs = runs;
  o.combined_only = combined_only;
  o.methods = std::move(methods);
  o.threads = threads;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int R = quick ? 5 : 51;  // repeats of the fast figures
  const std::string src = ROTACAL_SOURCE_DIR;
  const MachineModel machine = loadMachine(src + "/examples/machines/ac_trunnion.json");
  const ContributorSet cs = loadContributors(src + "/examples/contributors/table5.json");
  const ProbePlan plan = makePlan("touch154", machine, {});
  const unsigned cores = std::thread::hardware_concurrency();

  std::printf("rotacal benchmark: %u core(s) (std::thread::hardware_concurrency), %s build\n", cores,
#ifdef NDEBUG
              "optimised (NDEBUG)"
#else
              "debug (assertions on: figures not representative)"
#endif
  );
  std::printf("  %-64s %10s %10s %6s\n", "figure", "median ms", "min ms", "reps");

  std::printf("Monte Carlo of the 154-point chain, 1000 runs, linearised, 000 Table 5 contributors:\n");
  const LinearChain chain = lineariseChain(plan, LocationErrors{});
  using M = UncertaintyMethod;
  const std::vector<M> all = {};  // every estimator that applies
  auto runs = [&](bool combined_only, std::vector<M> methods, int threads) {
    runUncertainty(plan, chain, cs, mc(1000, combined_only, std::move(methods), threads));
  };
  const Figure both = figure("closed_form + least_squares, combined (Table 6), all cores", R,
                             [&] { runs(true, {M::ClosedForm, M::LeastSquares}, 0); });
  figure("closed_form alone, combined, all cores", R, [&] { runs(true, {M::ClosedForm}, 0); });
  figure("least_squares alone, combined, all cores", R, [&] { runs(true, {M::LeastSquares}, 0); });
  figure("all four estimators, combined, all cores", R, [&] { runs(true, all, 0); });
  figure("all four estimators + per-contributor table (Table 5), all cores", R, [&] { runs(false, all, 0); });
  figure("closed_form + least_squares, combined, 1 thread", R, [&] { runs(true, {M::ClosedForm, M::LeastSquares}, 1); });
  figure("building the linear chain (once per plan)", quick ? 2 : 11, [&] { lineariseChain(plan, LocationErrors{}); });
  figure("exact chain, one run (simulate + the four estimators)", quick ? 2 : 11, [&] {
    RunDraw d;
    drawRun(drawModel(cs), chain, 1, 0, &d);
    MethodMask m;
    m.fill(true);
    exactDeviation(plan, chain, m, LocationErrors{}, d, nullptr);
  });

  std::printf("one identification of the 154 points (simulated, 0.7 um noise):\n");
  Truth truth;
  truth.noise_um = 0.7;
  const MeasurementRun run = simulate(plan, truth, {1});
  figure("closed form (touch154Patterns + solvePatterns)", R, [&] { solvePatterns(touch154Patterns(plan, run)); });
  IdentificationOptions lsq;
  figure("least squares lsq_per_point, identify() (analyze's default)", R, [&] { identify(plan, {run}, lsq); });
  IdentificationOptions lsq_sq;
  lsq_sq.extensions = {linearAxisSquareness()};
  figure("least squares with the squareness fitted, identify()", R, [&] { identify(plan, {run}, lsq_sq); });

  std::printf("plans and programs:\n");
  figure("plan generation: touch154 (makePlan)", R, [&] { makePlan("touch154", machine, {}); });
  figure("plan design: 77 touches, A-optimal (designPlan)", quick ? 1 : 3, [&] { designPlan(machine, cs, DesignOptions{}); });
  for (const char* d : {"linuxcnc", "fanuc"})
    figure(std::string("program generation: ") + d + " (probeProgram + writeProgram)", R,
           [&] { dialectByName(d).writeProgram(probeProgram(plan, d)); });

  // A 10 MB dump: the 154-point plan repeated (ids renumbered) until the LinuxCNC log passes 10 MB.
  ProbePlan big = plan;
  big.points.clear();
  MeasurementRun big_run;
  const auto& lcnc = dialectByName("linuxcnc");
  const double per_point = static_cast<double>(lcnc.writeResults(plan, run).size()) / static_cast<double>(plan.points.size());
  const int copies = static_cast<int>(10.0e6 / per_point / static_cast<double>(plan.points.size())) + 1;
  for (int c = 0; c < copies; ++c)
    for (size_t i = 0; i < plan.points.size(); ++i) {
      ProbePoint p = plan.points[i];
      p.id = static_cast<int>(big.points.size()) + 1;
      big.points.push_back(p);
      TriggerPoint t = run.points[i];
      t.point_id = p.id;
      big_run.points.push_back(t);
    }
  std::printf("results parsing (%zu points):\n", big.points.size());
  for (const char* d : {"linuxcnc", "csv"}) {
    std::string text;
    try {
      text = dialectByName(d).writeResults(big, big_run);
    } catch (const std::exception& e) {
      std::printf("  %s dump: cannot write it: %s\n", d, e.what());
      continue;
    }
    figure(fmt::format("parse a {:.1f} MB {} dump", static_cast<double>(text.size()) / 1e6, d), quick ? 1 : 5,
           [&] { dialectByName(d).parseResults(text, "dump", big); });
  }

  std::printf("target: 1000 runs of the 154-point chain <= 10 ms on 2 cores: %.3f ms (closed_form + "
              "least_squares, median) -> %s\n",
              both.median_ms, both.median_ms <= 10.0 ? "met" : "NOT met");
  return 0;
}
