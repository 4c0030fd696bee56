// rotacal_judge_bench: the judge's (core/judge.hpp) false-alarm rate and power, measured on the
// synthetic probe design of tests/core/judge_test.cpp with more seeds than a unit test affords.
// Prints figures (docs/diagnosis.md, "The judge"); not a test.
//   build/bench/rotacal_judge_bench [clean_seeds=2000] [effect_seeds=200]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/judge.hpp"
#include "core/rng.hpp"
#include "judge_probe_design.hpp"

using namespace rotacal;

namespace {

// The judge test's design and problem (tests/judge_probe_design.hpp): the rates printed here
// are of the problem the test asserts on.
using Design = test::ProbeDesign;
Design design() { return test::probeDesign(); }
JudgeProblem problem(const Design& d) { return test::probeProblem(d, Eigen::VectorXd(), 0.7); }

/// Upper end of the two-sided 95 % Clopper-Pearson-like interval by the normal approximation
/// with continuity correction (enough for a printed figure).
double upper95(int k, int n) {
  const double p = (k + 0.5) / n;
  return std::min(1.0, p + 1.96 * std::sqrt(p * (1 - p) / n));
}

}  // namespace

int main(int argc, char** argv) {
  const int clean = argc > 1 ? std::atoi(argv[1]) : 2000;
  const int effect_seeds = argc > 2 ? std::atoi(argv[2]) : 200;
  const Design d = design();
  JudgeProblem p = problem(d);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(d.n());
  std::printf("judge benchmark: probe design, n = %d, 4 baseline parameters, 3 causes, 0.7 um declared noise\n", d.n());

  for (double alpha : {0.01, 0.05}) {
    JudgeOptions o;
    o.alpha = alpha;
    int found = 0, inadequate = 0, baseline_fail = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (int seed = 1; seed <= clean; ++seed) {
      p.y = test::probeData(d, static_cast<std::uint64_t>(seed), 0.7, zero);
      const JudgeSummary s = judge(p, o);
      found += s.verdict == JudgeVerdict::EffectFound;
      inadequate += s.verdict == JudgeVerdict::ModelInadequate;
      baseline_fail += !s.baseline.passes;
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / clean;
    const int alarms = found + inadequate;
    std::printf("clean, alpha %.2f: %d seeds, false alarms %d (%.2f %%, 95 %% upper %.2f %%): effect_found %d, "
                "model_inadequate %d (baseline adequacy failed %d); %.2f ms per judge\n",
                alpha, clean, alarms, 100.0 * alarms / clean, 100.0 * upper95(alarms, clean), found, inadequate,
                baseline_fail, ms);
  }

  struct Case {
    const char* cause;
    Eigen::VectorXd theta;
  };
  const std::vector<Case> cases = {{"thermal_drift", (Eigen::VectorXd(3) << 0.4, -0.3, 0.3).finished()},
                                   {"rotary_error_motion", (Eigen::VectorXd(2) << 0.5, 0.3).finished()},
                                   {"linear_axis_scale", (Eigen::VectorXd(1) << 0.6).finished()}};
  for (const auto& c : cases) {
    const JudgeCause* cause = nullptr;
    for (const auto& x : p.causes)
      if (x.name == c.cause) cause = &x;
    for (double size : {0.5, 0.75, 1.0, 1.5}) {
      const Eigen::VectorXd effect = cause->J * (size * c.theta);
      int right = 0, within = 0, wrong = 0, inadequate = 0;
      for (int seed = 1; seed <= effect_seeds; ++seed) {
        p.y = test::probeData(d, 100000 + static_cast<std::uint64_t>(seed), 0.7, effect);
        const JudgeSummary s = judge(p);
        inadequate += s.verdict == JudgeVerdict::ModelInadequate;
        if (s.verdict != JudgeVerdict::EffectFound) continue;
        if (s.findings.size() != 1 || s.findings[0].cause != c.cause) {
          ++wrong;
          continue;
        }
        ++right;
        bool ok = true;
        for (Eigen::Index k = 0; k < c.theta.size(); ++k) {
          const auto& e = s.findings[0].parameters[static_cast<size_t>(k)];
          ok = ok && std::abs(e.value - size * c.theta[k]) <= 3.0 * e.u;
        }
        within += ok;
      }
      std::printf("%-20s x%.2f of the test's size: found %3d / %d (within 3 u %d), another or more causes %d, "
                  "model_inadequate %d\n",
                  c.cause, size, right, effect_seeds, within, wrong, inadequate);
    }
  }
  return 0;
}
