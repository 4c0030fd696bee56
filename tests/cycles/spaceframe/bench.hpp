#pragma once
// What the spaceframe tests of the declared noise, the screen and the drawn machines share: a
// reduced map on the bundled A/C machine (4 turns x 3 tilts: 12 orientations, its contributors
// 000 Table 5), results through the csv dialect, chips.
#include <string>

#include "controllers/dialect.hpp"
#include "core/contributors.hpp"
#include "core/simulation.hpp"
#include "cycles/cycle.hpp"
#include "test_util.hpp"

namespace rotacal::spaceframe_test {

inline ProbePlan reducedPlan() {
  return makePlan("spaceframe", test::acMachine(), {{"phi_list", "-90,-45,0"}, {"theta_list", "0,90,180,270"}});
}

inline ContributorSet table5() { return loadContributors(test::sourcePath("examples/contributors/table5.json")); }

inline const DialectIO& csvIO() {
  static const Dialect& csv = dialectByName("csv");
  static const DialectIO io{std::string(csv.name()),
                            [](const std::string& text, const std::string& file, const ProbePlan& plan) {
                              return csv.parseResults(text, file, plan);
                            },
                            [](const ProbePlan& plan, const MeasurementRun& run) { return csv.writeResults(plan, run); }};
  return io;
}

/// A chip under plan point index k: the probe stops `chip_mm` early along its approach.
inline MeasurementRun chipped(const ProbePlan& plan, MeasurementRun run, size_t k, double chip_mm) {
  for (auto& t : run.points)
    if (t.point_id == plan.points[k].id) t.position_m_mm -= chip_mm * plan.points[k].approach_m;
  return run;
}

inline CycleDocuments analyzeThrough(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const ContributorSet* cs, std::uint64_t mc_seed = 1) {
  AnalyzeRequest a;
  a.plan = &plan;
  a.dialect = &csvIO();
  a.contributors = cs;
  a.mc_runs = 100;  // the least the budget takes
  a.mc_seed = mc_seed;
  for (size_t k = 0; k < runs.size(); ++k)
    a.results.push_back({"results" + std::to_string(k + 1) + ".csv", csvIO().write_results(plan, runs[k])});
  return cycleByName("spaceframe").analyze(a);
}

}  // namespace rotacal::spaceframe_test
