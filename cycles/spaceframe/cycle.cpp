// spaceframe (003): length errors of a 7-sphere frame against U = +-(A + K L), and what explains them.
#include "core/errors.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/spaceframe/budget.hpp"
#include "cycles/spaceframe/diagnose.hpp"
#include "cycles/spaceframe/noise.hpp"
#include "cycles/spaceframe/screen.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "postproc/probe_program.hpp"
#include "core/singleton.hpp"

namespace rotacal {
namespace {

/// The declared noise; two declarations of the probe's repeatability that disagree are the
/// contributors file's error (its path leads the message).
SpaceframeNoise noiseOrFail(const ProbePlan& plan, const ContributorSet* declared) {
  try {
    return spaceframeDeclaredNoise(plan, declared);
  } catch (const std::invalid_argument& e) {
    throw InputError(declared && !declared->file.empty() ? declared->file : "MACHINE.json contributors", 0, e.what());
  }
}

/// The cycle writes no offsets; what it identifies is what explains dL. When that must not be
/// used, REPORT.json, the text and the warnings say why (and `--offsets` gives it).
void holdBack(CycleDocuments* out, const std::string& why) {
  if (why.empty() || !out->offsets_refused.empty()) return;
  out->offsets_refused = why;
  out->warnings.push_back(why);
  out->doc["corrections_held_back"] = why;
  out->text += "identification held back: " + why + "\n";
}

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
    const SpaceframeNoise noise = noiseOrFail(plan, r.contributors);
    const std::vector<MeasurementRun> runs = readProbeRuns(plan, r.results, *r.dialect);
    // Touches that hit a chip: found against the declared noise, left out of every fit below
    // (and out of every repeat) with the reason; too many: nothing left out, and the
    // identification is held back.
    const SpaceframeScreen screened = screenSpaceframeTouches(plan, runs, noise);
    const SpaceframeAnalysis& a = screened.fit;
    SpaceframeOptions so;
    so.held_out_ids = screened.heldOutIds();
    const std::vector<std::string> files = pathsOf(r.results);
    CycleDocuments out;
    out.doc = spaceframeReportJson(a, plan, files);
    // What analyze signs (issue 17): u_A from the data, u_B from the declared contributors and
    // the frame's calibration by Monte Carlo through the same estimator (cycles/spaceframe/budget.hpp).
    std::vector<SpaceframeAnalysis> per_run;
    if (runs.size() >= 2)
      for (const auto& run : runs) per_run.push_back(analyzeSpaceframe(plan, {run}, so));
    SpaceframeBudgetOptions bo;
    bo.runs = r.mc_runs;
    bo.seed = r.mc_seed;
    const UncertaintyBudget b = spaceframeBudget(plan, a, per_run, r.contributors, bo);
    const Eigen::VectorXd values = spaceframeBudgetValues(plan, a);
    addSpaceframeBudget(&out.doc, b, values);
    out.text = spaceframeText(a, plan, &b) + "\n" + budgetText(b, values);
    if (a.summary.termination != "converged") out.warnings.push_back("spaceframe identification " + a.summary.termination);
    out.doc["outliers"] = screened.json();
    out.text += screened.text() + "\n";
    if (!screened.screen.excluded.empty()) out.warnings.push_back(screened.text());
    if (screened.screen.too_many) holdBack(&out, screened.text());
    // The centres against what the machine's contributors declare (the budget's own model):
    // beyond it, the model does not explain this machine.
    const SpaceframeCentreProblem cp = spaceframeCentreProblem(plan, a, noise);
    const DeclaredNoiseTest test = testAgainstDeclared(cp.residual_um, cp.J, cp.covariance_um2);
    out.doc["declared_noise"] = spaceframeDeclaredNoiseJson(noise, test);
    out.text += "declared noise: " + out.doc["declared_noise"]["summary"].get<std::string>() + " (" +
                noise.touch.declaration + ")\n";
    holdBack(&out, offsetsHeldBack(noise.touch, test));
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    SpaceframeDiagnosisOptions o;
    o.judge.alpha = r.alpha;
    o.sigma_um = plan.machine.probe.repeatability_um;  // declared, never the fits' own
    // The judge reads the centres' declared covariance: the machine's contributors, or the
    // probe's repeatability alone when none are declared.
    const SpaceframeNoise noise = noiseOrFail(plan, r.contributors);
    o.noise = &noise;
    // The judge sees the touches the screen keeps (all of them when it found too many).
    const std::vector<MeasurementRun> runs = readProbeRuns(plan, r.results, *r.dialect);
    const SpaceframeScreen screened = screenSpaceframeTouches(plan, runs, noise);
    o.held_out_ids = screened.heldOutIds();
    const SpaceframeDiagnosis d = diagnoseSpaceframe(plan, runs, o);
    if (!d.baseline.converged)
      throw InputError(r.results.front().path, 0, "spaceframe diagnosis: a model fit did not converge");
    CycleDocuments out = documents(spaceframeDiagnosisJson(d, plan), spaceframeDiagnosisText(d) + screened.text() + "\n");
    out.doc["outliers"] = screened.json();
    if (!screened.screen.excluded.empty() || screened.screen.too_many) out.warnings.push_back(screened.text());
    return out;
  }
};

}  // namespace

const Cycle& spaceframeCycle() { return singleton<Spaceframe>(); }

}  // namespace rotacal
