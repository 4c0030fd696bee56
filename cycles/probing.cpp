#include "cycles/probing.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "core/errors.hpp"
#include "core/simulation.hpp"

namespace rotacal {

void finishTouchPlan(ProbePlan& plan) {
  const auto bad = strokeViolations(plan);
  if (!bad.empty()) throw std::invalid_argument("plan does not fit the machine: " + bad.front());
  estimateTimes(plan);
}

std::vector<MeasurementRun> readProbeRuns(const ProbePlan& plan, const std::vector<InputFile>& results,
                                          const DialectIO& dialect) {
  std::vector<MeasurementRun> runs;
  for (const auto& f : results) runs.push_back(dialect.read_results(f.text, f.path, plan));
  return runs;
}

Simulated simulateProbing(const SimulateRequest& r) {
  const ProbePlan& plan = *r.plan;
  Truth truth = truthFromJson(parseJsonText(r.truth.text, r.truth.path), plan.machine.kinematics);
  if (r.noise_um) truth.noise_um = *r.noise_um;
  if (r.start_s) truth.start_time_s = *r.start_s;
  MeasurementRun run;
  try {
    run = simulate(plan, truth, {r.seed});
  } catch (const std::exception& e) {
    throw InputError(r.truth.path, 0, e.what());
  }
  return {r.dialect->write_results(plan, run),
          fmt::format("simulated {} triggers (noise {:.3f} um, seed {}) as {} results", run.points.size(), truth.noise_um,
                      r.seed, r.dialect->name)};
}

}  // namespace rotacal
