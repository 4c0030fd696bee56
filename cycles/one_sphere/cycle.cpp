// one_sphere: both rotary axes' ISO 230-7 location errors from one calibration sphere,
// touched at a grid of tilt and C angles (the KinematicsOpt / CYCLE996 / AxiSet class).
#include <fmt/format.h>

#include "core/errors.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "cycles/one_sphere/analyze.hpp"
#include "cycles/one_sphere/budget.hpp"
#include "cycles/one_sphere/diagnose.hpp"
#include "cycles/one_sphere/plan.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {
namespace {

/// The declared noise; two declarations of the probe's repeatability that disagree are the
/// contributors file's error (its path leads the message).
DeclaredNoise sphereNoiseOrFail(const ProbePlan& plan, const ContributorSet* declared) {
  try {
    return sphereDeclaredNoise(plan, declared);
  } catch (const std::invalid_argument& e) {
    throw InputError(declared && !declared->file.empty() ? declared->file : "MACHINE.json contributors", 0, e.what());
  }
}

class Sphere final : public Cycle {
 public:
  Sphere() : Cycle({"one_sphere", "rotacal's own: both rotary axes' ISO 230-7 location errors and the probe's radius from one sphere",
                     {"examples/machines/ac_trunnion.json", {}, "examples/truth/table4_mean.json"},
                     7019,  // O7019: its own slot in the control's memory
                     makeSpherePlan, probeProgram, spherePlanRules()}) {}

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    // Touches that hit a chip: found against the declared noise (the machine's contributors,
    // the linear axes' shared errors included), left out of the fit with the reason.
    const DeclaredNoise noise = sphereNoiseOrFail(plan, r.contributors);
    const SphereScreen screened = screenSphereTouches(plan, readProbeRuns(plan, r.results, *r.dialect), noise);
    const OutlierScreen& screen = screened.screen;
    const SphereCycleResult& res = screened.fit;
    BudgetOptions bo;
    bo.runs = r.mc_runs;
    bo.seed = r.mc_seed;
    const UncertaintyBudget b = sphereBudget(plan, res, r.contributors, bo);
    const std::vector<std::string> files = pathsOf(r.results);
    CycleDocuments out;
    out.doc = sphereReportJson(plan, res, b, files);
    out.text = sphereText(res, b) + screen.lines();
    out.doc["outliers"] = outlierScreenJson(screen, screened.options);
    const SphereFittedProblem f = sphereFittedProblem(noise, res);
    const DeclaredNoiseTest test =
        testAgainstDeclared(f.residual_um, f.J, f.covariance_um2, noise.nullDraws(f.readings, kDeclaredNullSeed + 2));
    out.doc["declared_noise"] = declaredNoiseJson(noise, test);
    out.doc["figures"] = sphereFiguresJson(plan, res, std::sqrt(noise.white_um2));
    if (!screen.excluded.empty() || screen.too_many) out.warnings.push_back(screen.text());
    if (plan.machine.kinematics == Kinematics::HeadAB) {
      // No writer takes the A/B head's kinematics: controllers.md has no verified form of them.
      out.offsets_refused = fmt::format(
          "a {} machine's kinematic parameters go into the control's kinematics description (Heidenhain's kinematics "
          "table, Siemens' $TC_CARR, Fanuc's TCP parameters), which rotacal does not write yet: none of these forms is "
          "confirmed in rotacal's sources (docs/dialects.md); enter REPORT.json's kinematic_parameters by hand",
          kinematicsName(plan.machine.kinematics));
      return out;
    }
    if (!hasPapersLocationErrors(plan.machine.kinematics)) {
      // A head machine: the model's own parameters reach the dialect, which writes what its
      // control can hold of them (LinuxCNC's maxkins, 5axiskins) or refuses with the reason.
      out.offsets = headCorrection(res, b);
      finishOffsets(screen, noise, test, &out);
      return out;
    }
    LocationCorrection c;
    c.identified = res.location;
    const Eigen::VectorXd uc = b.uC();
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const auto& q = res.names[static_cast<size_t>(res.location_index_in_x[static_cast<size_t>(i)])];
      for (int k = 0; k < b.size(); ++k)
        if (b.names[static_cast<size_t>(k)] == q.name)
          c.u[i] = q.kind == ParamKind::Length ? umToMm(uc[k]) : mdegToRad(uc[k]);
    }
    out.offsets = c;
    finishOffsets(screen, noise, test, &out);
    return out;
  }

  // More than a few chips: nothing was left out, and data this far from the declared noise
  // sign no offsets.
  static void finishOffsets(const OutlierScreen& screen, const DeclaredNoise& noise, const DeclaredNoiseTest& test,
                            CycleDocuments* out) {
    if (screen.too_many) out->offsets_refused = screen.text();
    const std::string held = offsetsHeldBack(noise, test);
    if (!held.empty() && out->offsets_refused.empty()) {
      out->offsets_refused = held;
      out->warnings.push_back(held);
    }
  }

  // Every fitted parameter with its u_c (mm / rad), the held ones marked.
  static LocationCorrection headCorrection(const SphereCycleResult& res, const UncertaintyBudget& b) {
    LocationCorrection c;
    c.identified.kinematics = res.location.kinematics;
    const Eigen::VectorXd uc = b.uC();
    for (size_t i = 0; i < res.names.size(); ++i) {
      const auto& q = res.names[i];
      ParameterEstimate p;
      p.name = q.name;
      p.kind = q.kind;
      p.value = res.x[static_cast<Eigen::Index>(i)];
      p.held = res.identifiability.held[i];
      for (int k = 0; k < b.size(); ++k)
        if (b.names[static_cast<size_t>(k)] == q.name) p.u = q.kind == ParamKind::Length ? umToMm(uc[k]) : mdegToRad(uc[k]);
      c.parameters.push_back(p);
    }
    return c;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    JudgeOptions o;
    o.alpha = r.alpha;
    sphereNoiseOrFail(plan, r.contributors);  // a contradictory declaration names its file
    const SphereDiagnosis d = diagnoseSphere(plan, readProbeRuns(plan, r.results, *r.dialect), o, r.contributors);
    return documents(judgedDiagnosisJson(std::string(name()), plan, d), judgeText(d.summary, d.separate_with));
  }
};

}  // namespace

const Cycle& one_sphereCycle() { return singleton<Sphere>(); }

}  // namespace rotacal
