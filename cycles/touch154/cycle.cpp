// touch154 (000): the 8 location errors of an A/C table from 154 touches on a square column.
// Plans written by `rotacal design` (cycle "touch_designed") are analyzed the same way.
#include <fmt/format.h>

#include <optional>
#include <stdexcept>

#include "core/errors.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/outliers.hpp"
#include "cycles/touch154/point_deviations.hpp"
#include "core/units.hpp"
#include "cycles/touch154/budget.hpp"
#include "cycles/touch154/closed_form.hpp"
#include "cycles/touch154/declared.hpp"
#include "cycles/touch154/commands.hpp"
#include "cycles/touch154/diagnose.hpp"
#include "cycles/touch154/figures.hpp"
#include "cycles/touch154/report.hpp"
#include "cycles/touch154/plan.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "postproc/probe_program.hpp"
#include "core/singleton.hpp"

namespace rotacal {
namespace {

/// The declared noise; two declarations of the probe's repeatability that disagree are the
/// contributors file's error (its path leads the message).
Touch154Noise declaredNoiseOrFail(const ProbePlan& plan, const ContributorSet* declared) {
  try {
    return touch154DeclaredNoise(plan, declared);
  } catch (const std::invalid_argument& e) {
    throw InputError(declared && !declared->file.empty() ? declared->file : "MACHINE.json contributors", 0, e.what());
  }
}

class Touch154 final : public Cycle {
 public:
  Touch154() : Cycle({"touch154", "000: the 8 location errors of an A/C table from 154 touches",
                       {"examples/machines/ac_trunnion.json", {}, "examples/truth/table4_mean.json"},
                       7154,  // the 154 touches of 000; the others are 7000 + their source document
                       makeTouch154Plan, probeProgram, touch154PlanRules()}) {}
  std::vector<std::string> aliases() const override { return {"touch_designed"}; }


  std::vector<std::string> methods() const override {
    return {std::string(methodName(Method::LeastSquaresPerPoint)), std::string(methodName(Method::LeastSquaresRigidSetup)),
            std::string(methodName(Method::ClosedForm))};
  }

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    const Method method = methodFromName(r.method.empty() ? methods().front() : r.method);
    const std::vector<MeasurementRun> runs = readProbeRuns(plan, r.results, *r.dialect);
    IdentificationOptions opt;
    opt.method = method;
    opt.prior_sigma_um = plan.machine.probe.repeatability_um;
    // Touches that hit a chip: found by the least squares' residuals against the declared noise
    // (the machine's contributors, shared errors included), left out with the reason.
    const Touch154Noise noise = declaredNoiseOrFail(plan, r.contributors);
    OutlierOptions oo;
    oo.sigma_um = std::sqrt(noise.noise.white_um2);
    oo.declaration = noise.noise.declaration;
    if (noise.basis.size())
    {
      oo.statistic = [&noise](const ScreenedFit& fit) { return touch154OutlierStatistic(noise, fit); };
      oo.null_maxima = [&noise](const ScreenedFit& fit) {
        const FittedReadings f = fittedProblem(noise, fit.residuals);
        if (f.null_draws_um.cols() == 0) return Eigen::VectorXd();
        return screenNullMaxima(deletionStatisticsColumns(f.null_draws_um, f.J, f.covariance_um2));
      };
      oo.sensitivity = [&noise](const ScreenedFit& fit) {
        const FittedReadings f = fittedProblem(noise, fit.residuals);
        return deletionSensitivity(f.J, f.covariance_um2);
      };
    }
    const OutlierScreen screen = screenOutliers(
        [&](const std::function<bool(int, const ProbePoint&)>& hold) {
          IdentificationOptions o = opt;
          o.method = Method::LeastSquaresPerPoint;
          o.hold_out = hold;
          return identify(plan, runs, o);
        },
        oo);
    opt.hold_out = screen.holdOut();
    Analysis a;
    a.plan = &plan;
    a.result_files = pathsOf(r.results);
    a.main = identifyTouch154(plan, runs, opt);
    if (a.main.summary.termination == Termination::RankDeficient || a.main.summary.termination == Termination::InvalidInput)
      throw InputError(r.results.front().path, 0, a.main.summary.message);
    if (runs.size() > 1)
      for (size_t k = 0; k < runs.size(); ++k) {
        IdentificationOptions o = opt;
        if (opt.hold_out) o.hold_out = [&opt, k](int, const ProbePoint& p) { return opt.hold_out(static_cast<int>(k), p); };
        a.per_run.push_back(identifyTouch154(plan, {runs[k]}, o));
      }
    for (Method other : {Method::LeastSquaresPerPoint, Method::LeastSquaresRigidSetup, Method::ClosedForm}) {
      if (other == method) continue;
      IdentificationOptions o = opt;
      o.method = other;
      a.other_methods.push_back(identifyTouch154(plan, runs, o));
    }
    if (plan.cycle == name()) {
      try {
        a.patterns = touch154Patterns(plan, runs.front());
      } catch (const std::invalid_argument&) {
        // a reduced plan has no complete pattern set; the least squares still runs
      }
    }
    Touch154BudgetOptions bo;
    bo.runs = r.mc_runs;
    bo.seed = r.mc_seed;
    a.budget = touch154Budget(plan, a.main, a.per_run, r.contributors, bo);
    CycleDocuments out;
    out.text = analysisText(a) + screen.lines();
    out.doc = analysisToJson(a);
    out.doc["outliers"] = outlierScreenJson(screen, oo);
    // What the screen and the adequacy test read, and how the data compare with it.
    if (noise.basis.size()) {
      const IdentificationResult* lp = a.main.method == Method::LeastSquaresPerPoint ? &a.main : nullptr;
      for (const auto& other : a.other_methods)
        if (!lp && other.method == Method::LeastSquaresPerPoint) lp = &other;
      if (lp) {
        const FittedReadings f = fittedProblem(noise, lp->residuals);
        const DeclaredNoiseTest test = testAgainstDeclared(f.residual_um, f.J, f.covariance_um2, f.null_draws_um);
        out.doc["declared_noise"] = declaredNoiseJson(noise.noise, test);
        const std::string held = offsetsHeldBack(noise.noise, test);
        if (!held.empty() && out.offsets_refused.empty()) {
          out.offsets_refused = held;
          out.warnings.push_back(held);
        }
      }
    }
    if (!screen.excluded.empty() || screen.too_many) out.warnings.push_back(screen.text());
    if (screen.too_many) out.offsets_refused = screen.text();
    if (!screen.excluded.empty() && method == Method::ClosedForm)
      out.offsets_refused = "the closed form uses every touch, the outlier screen's excluded ones too (" + screen.text() +
                            "): analyze with --method lsq_per_point";
    if (!screen.excluded.empty() && method == Method::ClosedForm)
      out.warnings.push_back("the closed form uses every touch, the excluded ones too: its estimate carries them "
                             "(--method lsq_per_point leaves them out)");
    out.doc["points"] = pointDeviationsJson(plan, runs, a.main);  // the HTML report's deviation views
    if (plan.cycle == name())  // the poses of 000 Fig. 5: the report's views are the paper's figures
      out.doc["figure_titles"] = {{"fig7", "Probed positions at A = 0 (000 Fig. 7)"},
                                  {"fig8", "Relative displacements at A = 0 (000 Fig. 8, Eq. (21))"},
                                  {"fig9", "Relative displacements at A = -90 deg (000 Fig. 9)"}};
    // The offsets carry the combined uncertainty: what the report signs, not the data's scatter alone.
    ErrorVector u_c;
    const Eigen::VectorXd uc = a.budget.uC();
    const auto& params = locationParameters(plan.machine.kinematics);
    for (int i = 0; i < kNumLocationErrors; ++i)
      u_c[i] = params[i].kind == ParamKind::Length ? umToMm(uc[i]) : mdegToRad(uc[i]);
    out.offsets = LocationCorrection{a.main.estimate, u_c, {}};
    if (a.main.summary.termination != Termination::Converged) out.warnings.push_back(a.main.summary.message);
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    const std::vector<MeasurementRun> runs = readProbeRuns(plan, r.results, *r.dialect);
    Touch154DiagnosisOptions o;
    o.judge.alpha = r.alpha;
    o.sigma_um = plan.machine.probe.repeatability_um;  // declared, never the fit's own
    const Touch154Noise noise = declaredNoiseOrFail(plan, r.contributors);
    o.noise = &noise;
    std::string why;
    if (!o.validate(&why)) throw std::invalid_argument(why);
    if (r.progress) r.progress(0, 1);
    const Touch154Diagnosis dg = diagnoseTouch154(plan, runs, o);
    if (r.progress) r.progress(1, 1);
    if (!dg.lin.ok)
      throw InputError(r.results.front().path, 0, "baseline fit failed: " + dg.lin.baseline.summary.message);
    CycleDocuments out;
    out.text = touch154DiagnosisText(dg);
    out.doc = touch154DiagnosisJson(dg, plan);
    out.doc["figures"] = touch154DiagnosisFigures(dg, plan);  // drawn by the HTML report
    return out;
  }

  bool hasUncertainty() const override { return true; }
  CycleDocuments uncertainty(const UncertaintyRequest& r) const override { return touch154Uncertainty(r); }

  bool hasDesign() const override { return true; }
  DesignedPlan design(const DesignRequest& r) const override {
    std::optional<ProbePlan> full;
    try {
      full = plan(*r.machine, {});
    } catch (const std::invalid_argument&) {
      // no full plan on this machine: the design is compared with nothing
    }
    return touch154Design(r, full ? &*full : nullptr);
  }
};

}  // namespace

const Cycle& touch154Cycle() { return singleton<Touch154>(); }

}  // namespace rotacal
