// spaceframe (003): length errors of a 7-sphere frame against U = +-(A + K L), and what explains them.
#include "core/errors.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/spaceframe/budget.hpp"
#include "cycles/spaceframe/diagnose.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "postproc/probe_program.hpp"
#include "core/singleton.hpp"

namespace rotacal {
namespace {

class Spaceframe final : public Cycle {
 public:
  Spaceframe() : Cycle({"spaceframe", "003: length errors of a 7-sphere frame against U = +-(A + K L), and what explains them",
                         {"examples/machines/ac_trunnion.json", {{"phi_list", "-90,-45,0"}}},
                         7003,  // 7000 + its source document (003)
                         makeSpaceframePlan, probeProgram, {},
                         "a spaceframe analysis is a performance test: it writes no offsets (calibrate with touch154 "
                         "and use its offsets)"}) {}

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    const std::vector<MeasurementRun> runs = readProbeRuns(plan, r.results, *r.dialect);
    const SpaceframeAnalysis a = analyzeSpaceframe(plan, runs);
    const std::vector<std::string> files = pathsOf(r.results);
    CycleDocuments out;
    out.doc = spaceframeReportJson(a, plan, files);
    // What analyze signs (issue 17): u_A from the data, u_B from the declared contributors and
    // the frame's calibration by Monte Carlo through the same estimator (cycles/spaceframe/budget.hpp).
    std::vector<SpaceframeAnalysis> per_run;
    if (runs.size() >= 2)
      for (const auto& run : runs) per_run.push_back(analyzeSpaceframe(plan, {run}));
    SpaceframeBudgetOptions bo;
    bo.runs = r.mc_runs;
    bo.seed = r.mc_seed;
    const UncertaintyBudget b = spaceframeBudget(plan, a, per_run, r.contributors, bo);
    const Eigen::VectorXd values = spaceframeBudgetValues(plan, a);
    addSpaceframeBudget(&out.doc, b, values);
    out.text = spaceframeText(a, plan, &b) + "\n" + budgetText(b, values);
    if (a.summary.termination != "converged") out.warnings.push_back("spaceframe identification " + a.summary.termination);
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    SpaceframeDiagnosisOptions o;
    o.judge.alpha = r.alpha;
    o.sigma_um = plan.machine.probe.repeatability_um;  // declared, never the fits' own
    const SpaceframeDiagnosis d = diagnoseSpaceframe(plan, readProbeRuns(plan, r.results, *r.dialect), o);
    if (!d.baseline.converged)
      throw InputError(r.results.front().path, 0, "spaceframe diagnosis: a model fit did not converge");
    return documents(spaceframeDiagnosisJson(d, plan), spaceframeDiagnosisText(d));
  }
};

}  // namespace

const Cycle& spaceframeCycle() { return singleton<Spaceframe>(); }

}  // namespace rotacal
