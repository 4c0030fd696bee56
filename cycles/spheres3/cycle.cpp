// spheres3 (001): the 4 location and 6 component errors of the C axis from three spheres.
#include "cycles/spheres3/plan.hpp"
#include "cycles/spheres3/diagnose.hpp"
#include "cycles/spheres3/analyze.hpp"
#include "cycles/spheres3/budget.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "postproc/probe_program.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "core/errors.hpp"
#include "core/units.hpp"
#include "core/singleton.hpp"

namespace rotacal {
namespace {

/// The declared noise; two declarations of the probe's repeatability that disagree are the
/// contributors file's error (its path leads the message).
Spheres3Noise spheres3NoiseOrFail(const ProbePlan& plan, const ContributorSet* declared) {
  try {
    return spheres3DeclaredNoise(plan, declared);
  } catch (const std::invalid_argument& e) {
    throw InputError(declared && !declared->file.empty() ? declared->file : "MACHINE.json contributors", 0, e.what());
  }
}

class Spheres3 final : public Cycle {
 public:
  Spheres3() : Cycle({"spheres3", "001: the 4 location and 6 component errors of the C axis from three spheres",
                       {"examples/machines/ac_trunnion.json", {}, "examples/truth/table4_mean.json"},
                       7001,  // 7000 + its source document (001)
                       makeSpheres3Plan, probeProgram, spheres3PlanRules(),
                       "spheres3 identifies component errors as functions of C: they need the controller's rotary "
                       "compensation table, which no dialect writes yet"}) {}

  Simulated simulate(const SimulateRequest& r) const override {
    Simulated s = simulateProbing(r);
    // What the report states of them: the C axis's average line at z = 0 (Oxc Oyc Sxc Syc), from
    // the papers' chains at tilt 0 to first order (000 Eq. (1) on an A/C table, 002 Eq. (2) on a
    // B/C table; the second order is below 1 nm for errors of tens of um and mdeg).
    const Kinematics k = r.plan->machine.kinematics;
    // Their 001 form exists for a tilt axis carrying a C table.
    if (k != Kinematics::TableAC && k != Kinematics::TableBC) s.injected.erase("location_errors");
    if (s.injected.contains("location_errors")) {
      const Json e = s.injected["location_errors"];
      const bool ac = k == Kinematics::TableAC;
      auto at = [&e](const char* name) { return e.value(name, 0.0); };
      s.injected["location_errors"] = {
          {"Oxc", ac ? at("dx_AY") : at("dx_BY") + at("dx_CB")},
          {"Oyc", ac ? at("dy_AY") + at("dy_CA") : at("dy_CB")},
          {"Sxc", ac ? at("a_AY") : at("a_BY") + at("a_CB")},
          {"Syc", ac ? at("b_AY") + at("b_CA") : at("b_BY")}};
    }
    return s;
  }

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    Spheres3Options opt;
    opt.prior_sigma_um = plan.machine.probe.repeatability_um;
    const std::vector<MeasurementRun> runs = readProbeRuns(plan, r.results, *r.dialect);
    // Touches that hit a chip: found against the declared noise (the machine's contributors, the
    // linear axes' shared errors included) before the radius check, left out with the reason;
    // the radius check then reads the spheres without them.
    const Spheres3Noise noise = spheres3NoiseOrFail(plan, r.contributors);
    const Spheres3Screen screened = screenSpheres3Touches(plan, runs, noise, opt);
    const OutlierScreen& screen = screened.screen;
    if (!screened.refused.empty()) throw InputError(r.results.front().path, 0, screened.refused);
    if (!screened.kept_beyond.empty()) throw InputError(r.results.front().path, 0, screened.keptBeyondText());
    opt.hold_out_touch = screen.holdOut();
    const Spheres3Result res = identifySpheres3(plan, runs, opt);
    CycleDocuments out;
    out.doc = spheres3ReportJson(plan, res, pathsOf(r.results));
    out.doc["outliers"] = outlierScreenJson(screen, screened.options);
    // Touches left out as one of several the data cannot tell apart carry that reason.
    Json ambiguous = Json::array();
    for (const auto& a : screened.ambiguous) {
      ambiguous.push_back({{"run", a.run + 1}, {"sphere", a.sphere}, {"c_deg", a.c_deg}, {"points", a.point_ids},
                           {"left_out", a.left_out.empty() ? a.point_ids : a.left_out}, {"reason", a.text()}});
      for (auto& e : out.doc["outliers"]["excluded"])
        if (e.value("run", 0) == a.run + 1 &&
            std::find(a.point_ids.begin(), a.point_ids.end(), e.value("point", 0)) != a.point_ids.end())
          e["reason"] = a.text();
      out.warnings.push_back("outlier screen: " + a.text());
    }
    out.doc["outliers"]["ambiguous"] = ambiguous;
    const Spheres3TouchProblem tp = spheres3TouchProblem(runs, res, noise);
    const Eigen::MatrixXd null_draws = tp.nu.asDiagonal() * noise.trigger.nullDraws(tp.readings, kDeclaredNullSeed + 2);
    out.doc["declared_noise"] =
        declaredNoiseJson(noise.trigger, testAgainstDeclared(tp.residual_um, tp.J, tp.covariance_um2, null_draws));
    if (!screen.excluded.empty() || screen.too_many) out.warnings.push_back(screen.text());
    // What analyze signs: u_A from the data, u_B from the declared contributors by
    // Monte Carlo through the same estimator (cycles/spheres3/budget.hpp, docs/uncertainty.md).
    std::vector<Spheres3Result> per_run;
    if (runs.size() >= 2)
      for (size_t k = 0; k < runs.size(); ++k) {
        Spheres3Options o = opt;
        if (opt.hold_out_touch)
          o.hold_out_touch = [&opt, k](int, const ProbePoint& p) { return opt.hold_out_touch(static_cast<int>(k), p); };
        per_run.push_back(identifySpheres3(plan, {runs[k]}, o));
      }
    Spheres3BudgetOptions bo;
    bo.runs = r.mc_runs;
    bo.seed = r.mc_seed;
    const Spheres3Budget b = spheres3Budget(plan, res, per_run, r.contributors, bo);
    addSpheres3Budget(&out.doc, b);
    out.text = spheres3Text(res, &b.location) + screen.lines();
    Eigen::VectorXd values(4);
    for (int i = 0; i < 4; ++i) values[i] = i < 2 ? mmToUm(res.location[i]) : radToMdeg(res.location[i]);
    out.text += "\n" + budgetText(b.location, values);
    if (b.component_u_c.size() > 0)
      out.text += fmt::format("component errors: U ({:.2f} %) at most {:.3f} um (EXC EYC EZC), {:.3f} mdeg (EAC EBC ECC) "
                              "over the sampled angles (REPORT.json component_errors: u (= u_c) u_a u_b u_c U k)\n",
                              100.0 * kCoverageProbability, b.componentExpanded().leftCols(3).maxCoeff(),
                              b.componentExpanded().rightCols(3).maxCoeff());
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    Spheres3DiagnosisOptions o;
    o.judge.alpha = r.alpha;
    o.sigma_um = plan.machine.probe.repeatability_um;  // the declared noise, never the fit's own
    const Spheres3Noise noise = spheres3NoiseOrFail(plan, r.contributors);
    o.noise = &noise;
    const Spheres3Diagnosis d = diagnoseSpheres3(plan, readProbeRuns(plan, r.results, *r.dialect), o);
    return documents(spheres3DiagnosisJson(d), spheres3DiagnosisText(d));
  }
};

}  // namespace

const Cycle& spheres3Cycle() { return singleton<Spheres3>(); }

}  // namespace rotacal
