// spaceframe (003): length errors of a 7-sphere frame against U = +-(A + K L), and what explains them.
#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/errors.hpp"
#include "core/report_envelope.hpp"
#include "core/simulation.hpp"
#include "core/transforms.hpp"
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
                         {"examples/machines/ac_trunnion.json", {{"phi_list", "-90,-45,0"}}, "examples/truth/table4_mean.json"},
                         7003,  // 7000 + its source document (003)
                         makeSpaceframePlan, probeProgram, {},
                         "a spaceframe analysis is a performance test: it writes no offsets (calibrate with touch154 "
                         "and use its offsets)"}) {}

  // --contributors: a whole machine drawn as every probing cycle draws it (drawMachine: the
  // probe's pretravel, the linear axes of 000 Eqs. (22)-(23), the per-touch scatter as the noise),
  // with the set-up acting where this cycle has one: the frame on the table, turned about its
  // origin and shifted, as FrameModel's set-up (the test piece it was drawn for is not on the
  // table). Its spheres have no faces: a declared form_error is named as left out.
  Simulated simulate(const SimulateRequest& r) const override {
    if (!r.contributors) return simulateProbing(r);
    const ProbePlan& plan = *r.plan;
    const JsonDoc doc = parseJsonText(r.truth.text, r.truth.path);
    Truth truth = truthFromJson(doc, plan.machine);
    Json truth_json = doc.value;
    const DrawnMachine m = onTruthFile(r.truth, [&] { return drawMachine(plan, *r.contributors, r.machine_seed, &truth); });
    const SpaceframeLayout l = SpaceframeLayout::fromOptions(plan.options);
    const Eigen::Vector3d& t = truth.artefact.setup.translation_mm;
    const Eigen::Vector3d& w = truth.artefact.setup.rotation_rad;
    const Eigen::Isometry3d S = Eigen::Translation3d(t + l.origin_w_mm) * Da(w.x()) * Db(w.y()) * Dc(w.z()) *
                                Eigen::Translation3d(-l.origin_w_mm);
    for (int s = 1; s <= 7; ++s) {
      const Eigen::Vector3d p = l.origin_w_mm + l.frame.spheres_mm[static_cast<size_t>(s - 1)];
      const auto it = truth.sphere_center_error_w_mm.find(s);  // Eigen leaves a new entry unset
      const Eigen::Vector3d e = it == truth.sphere_center_error_w_mm.end() ? Eigen::Vector3d::Zero() : it->second;
      truth.sphere_center_error_w_mm[s] = S * (p + e) - p;
    }
    truth.artefact.setup = {};
    Json rec = m.record;
    rec["setup"]["applied_to"] = "the frame on the table: rotation about the frame's origin, then translation";
    rec.erase("form");
    if (r.contributors->find("form_error")) {
      Json left = rec.value("left_out", Json::array());
      left.push_back("form_error (the frame's spheres have no faces)");
      rec["left_out"] = left;
    }
    truth_json["drawn"] = rec;
    if (r.noise_um) truth.noise_um = *r.noise_um;
    if (r.start_s) truth.start_time_s = *r.start_s;
    truth_json["noise_um"] = truth.noise_um;
    const MeasurementRun run = onTruthFile(r.truth, [&] { return rotacal::simulate(plan, truth, {r.seed}); });
    Simulated s{r.dialect->write_results(plan, run),
            fmt::format("simulated {} triggers (noise {:.3f} um, seed {}, a machine drawn from {} (machine seed {})) as {} "
                        "results",
                        run.points.size(), truth.noise_um, r.seed,
                        r.contributors->file.empty() ? std::string("the machine's contributors") : r.contributors->file,
                        r.machine_seed, r.dialect->name),
            truth_json};
    if (locationErrorsAreConstant(truth)) s.injected["location_errors"] = locationErrorValues(truth.errors);
    return s;
  }

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
    // What analyze signs: u_A from the data, u_B from the declared contributors and
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
    if (!a.summary.usable())
      out.warnings.push_back("spaceframe identification " + std::string(terminationName(a.summary.termination)));
    out.doc["outliers"] = screened.json();
    out.text += screened.text() + "\n" + screened.screen.reachLine();
    if (!screened.screen.excluded.empty()) out.warnings.push_back(screened.text());
    if (screened.screen.too_many) holdBack(&out, screened.text());
    // The centres against what the machine's contributors declare (the budget's own model):
    // beyond it, the model does not explain this machine.
    const SpaceframeCentreProblem cp = spaceframeCentreProblem(plan, a, noise);
    const DeclaredNoiseTest test = testAgainstDeclared(cp.residual_um, cp.J, cp.covariance_um2, cp.null_draws_um);
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
