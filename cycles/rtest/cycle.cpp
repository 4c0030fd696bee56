// rtest (002): the position-dependent errors of the tilt axis with an R-test, and their thermal
// drift. The R-test logger writes its own CSV whatever the controller; no offsets (the errors
// depend on position and time).
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "core/errors.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/rtest/diagnose.hpp"
#include "cycles/rtest/analyze.hpp"
#include "cycles/rtest/budget.hpp"
#include "core/report_envelope.hpp"
#include "core/require_valid.hpp"
#include "core/units.hpp"
#include "core/simulation.hpp"
#include "cycles/cycle.hpp"
#include "cycles/rtest/program.hpp"
#include "core/singleton.hpp"

namespace rotacal {
namespace {

std::vector<RtestCycle> readCycles(const ProbePlan& plan, const std::vector<InputFile>& results,
                                   std::vector<std::string>* warnings = nullptr) {
  std::vector<RtestCycle> cycles;
  for (const auto& f : results) {
    const RtestSeries s = parseRtestResults(f.text, f.path, plan);
    size_t unchecked = 0;
    for (const auto& cy : s.cycles) unchecked += cy.reset ? 0 : 1;
    if (warnings && unchecked > 0)
      warnings->push_back(fmt::format("{}: {} of {} cycle(s) have no reset / re-read rows (pose 0, written before the "
                                      "reset was read in every cycle): the reset could not be checked for a sensor step "
                                      "or a lost count, and those cycles are read against the first cycle's reset",
                                      f.path, unchecked, s.cycles.size()));
    for (const auto& cy : s.cycles) {
      if (!cycles.empty() && cy.readings.front().t_s < cycles.back().readings.back().t_s)
        throw InputError(f.path, 0, "cycles must be in time order across the results files");
      cycles.push_back(cy);
    }
  }
  return cycles;
}

double sensorSigma(const ProbePlan& plan) { return rtestSensorNoiseUm(plan); }

class Rtest final : public Cycle {
 public:
  Rtest() : Cycle({"rtest", "002: the position-dependent errors of the tilt axis with an R-test, and their thermal drift",
                    {"examples/machines/bc_trunnion.json", {}, "examples/truth/bc_location.json"},
                    7002,  // 7000 + its source document (002)
                    makeRtestPlan, rtestProgram, rtestPlanRules(),
                    "the R-test cycle reports position-dependent errors and their drift; it writes no offsets (use "
                    "touch154 for the location errors)",
                    "R-test poses"}) {}

  Simulated simulate(const SimulateRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    const JsonDoc doc = parseJsonText(r.truth.text, r.truth.path);
    Truth truth = truthFromJson(doc, plan.machine.kinematics);
    RtestTruthExtras extras;
    rtestTruthFromJson(doc, plan.machine.kinematics, truth, extras);
    RtestSimOptions o;
    o.seed = r.seed;
    o.noise_um = truth.noise_um;
    // --contributors: a machine drawn from them on top of the truth file, as the budget draws it
    // (drawRtest, run 0 of the machine seed: the sensors' gain and cross-talk, the sphere offset,
    // the drift within a cycle, the linear axes), and the declared per-reading scatter (sensors
    // and sphere form) as the noise, replacing the truth file's (one declaration, not two).
    Json truth_json;
    std::string drawn;
    if (r.contributors) {
      RtestDraw draw;
      onTruthFile(r.truth, [&] {
        drawRtest(plan, *r.contributors, r.machine_seed, 0, -1, &draw);
        return 0;
      });
      applyRtestDraw(plan, draw, &truth, &extras);
      o.noise_um = std::sqrt(rtestDeclaredNoise(plan, r.contributors).white_um2);
      const std::string from = r.contributors->file.empty() ? std::string("the machine's contributors") : r.contributors->file;
      std::vector<std::string> left_out;
      for (const Contributor& c : r.contributors->items)
        if (!rtestTypeA(*c.info) && !rtestActsAsTypeB(*c.info)) left_out.emplace_back(c.info->id);
      truth_json = doc.value;
      Json rec = rtestDrawJson(draw);
      rec["seed"] = r.machine_seed;
      rec["contributors"] = from;
      rec["per_reading_um"] = std::round(o.noise_um * 1e6) / 1e6;
      if (!left_out.empty()) rec["left_out"] = left_out;
      truth_json["drawn"] = rec;
      drawn = fmt::format(", a machine drawn from {} (machine seed {})", from, r.machine_seed);
    }
    // Both are >= 0: the truth file's reader and --noise-um's check refuse a negative noise.
    if (r.noise_um) o.noise_um = *r.noise_um;
    if (!truth_json.is_null()) truth_json["noise_um"] = o.noise_um;
    o.start_s = r.start_s.value_or(0.0);
    const RtestSeries s = onTruthFile(r.truth, [&] { return simulateRtest(plan, truth, extras, o); });
    Simulated out{rtestResultsCsv(plan, s),
                  fmt::format("simulated {} R-test cycle(s) of {} readings (sensor noise {:.3f} um, seed {}{})",
                              s.cycles.size(), plan.points.size(), o.noise_um, r.seed, drawn),
                  truth_json};
    if (locationErrorsAreConstant(truth)) out.injected["location_errors"] = locationErrorValues(truth.errors);
    return out;
  }


  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    CycleDocuments out;
    const std::vector<RtestCycle> cycles = readCycles(plan, r.results, &out.warnings);
    RtestFitOptions o;
    o.sensor_sigma_um = sensorSigma(plan);
    // The structured part (the sensors' gain and cross-talk, the sphere offset, the linear axes)
    // taken about the first cycle's readings: the sensors scale what they read.
    const DeclaredNoise noise = rtestDeclaredNoise(plan, r.contributors, cycles.empty() ? nullptr : &cycles.front());
    o.reading_sigma_um = std::sqrt(noise.white_um2);
    o.declaration = noise.declaration;
    o.structured_um2 = noise.structured_um2;
    o.structured_draws_um = noise.structured_draws_um;
    const RtestAnalysis a = analyzeRtest(plan, cycles, o);
    const std::vector<std::string> files = pathsOf(r.results);
    out.doc = rtestReportJson(plan, cycles, a, files);
    if (!a.screen.screen.excluded.empty() || a.screen.screen.too_many) out.warnings.push_back(rtestScreenText(plan, a.screen));
    out.doc["warnings"] = out.warnings;
    for (size_t c = 0; c < a.cycles.size(); ++c)
      if (a.cycles[c].sensor_step)
        out.warnings.push_back(fmt::format("cycle {}: the reset pose re-read differs from its reading before the first "
                                           "pose beyond the declared sensor noise (p = {:.2g}): a sensor step",
                                           c + 1, a.cycles[c].reset_p));
    // The eight ISO 230-7 location errors separated by the constant-error fit; what
    // the R-test measures at each tilt is per_tilt_errors.
    out.doc["errors_heading"] = "ISO 230-7 location errors (constant over the tilt, first cycle)";
    // What analyze signs: u_A from the data, u_B from the declared contributors by
    // Monte Carlo through the same fit (cycles/rtest/budget.hpp, docs/uncertainty.md).
    // The text prints what REPORT.json signs (u = u_c): written once every budget is known.
    RtestSignedU signed_u;
    std::string budget_text;
    std::optional<UncertaintyBudget> location_budget;
    if (a.location.identifiable) {
      RtestBudgetOptions bo;
      bo.runs = r.mc_runs;
      bo.seed = r.mc_seed;
      location_budget = rtestBudget(plan, cycles.front(), a.location, o.sensor_sigma_um, r.contributors, bo);
      const UncertaintyBudget& b = *location_budget;
      addBudgetFields(&out.doc["location_errors"], b);
      out.doc["uncertainty"] = budgetJson(b);
      Eigen::VectorXd values(kNumLocationErrors);
      const auto& params = locationParameters(plan.machine.kinematics);
      for (int i = 0; i < kNumLocationErrors; ++i)
        values[i] = params[static_cast<size_t>(i)].kind == ParamKind::Length ? mmToUm(a.location.value[i])
                                                                             : radToMdeg(a.location.value[i]);
      budget_text += "\n" + budgetText(b, values);
      signed_u.location = &*location_budget;
    }
    const RtestDriftBudget db = rtestDriftBudget(plan, cycles, a, o, r.contributors);
    addRtestDriftBudget(&out.doc, plan, db);
    if (db.u_a.size() > 0) signed_u.drift_u_c = db.uC();
    // The per-tilt errors, what the R-test measures at each tilt, with the same contributors.
    {
      RtestBudgetOptions bo;
      bo.runs = r.mc_runs;
      bo.seed = r.mc_seed;
      const RtestTiltBudget tb = rtestTiltBudget(plan, cycles.front(), a, o, r.contributors, bo);
      addRtestTiltBudget(&out.doc, plan, tb);
      signed_u.tilt_u_c = tb.uC();
      signed_u.tilt_u_b = tb.uB();
      const Eigen::MatrixXd U = tb.expanded();
      budget_text += fmt::format("per-tilt errors of the first cycle: U ({:.2f} %) at most {:.3f} um (translations), {:.3f} "
                                 "mdeg (rotations) over the {} tilts; u_B {} (REPORT.json cycles[*].errors: u (= u_c) u_a "
                                 "u_b u_c U k)\n",
                                 100.0 * kCoverageProbability, U.topRows(3).maxCoeff(), U.bottomRows(3).maxCoeff(), tb.tilts,
                                 tb.budget.type_b_evaluated ? "from the declared contributors" : "not evaluated (none declared)");
    }
    out.text = rtestReportText(plan, a, signed_u) + rtestScreenText(plan, a.screen) + "\n" + a.screen.screen.reachLine("values") + budget_text;
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    CycleDocuments out;
    const std::vector<RtestCycle> cycles = readCycles(plan, r.results, &out.warnings);
    RtestDiagnosisOptions o;
    o.judge.alpha = r.alpha;
    o.sensor_sigma_um = sensorSigma(plan);  // the sensors (plan option, default 002's 0.2 um): the re-read check
    // The judge tests every reading against what one reading is declared to scatter by: the
    // sensors and the sphere's form, the per-reading part analyze's uncertainty budget reads too.
    // The structured part (the sensors' gain and cross-talk, the sphere offset, the linear axes)
    // taken about the first cycle's readings: the sensors scale what they read.
    const DeclaredNoise noise = rtestDeclaredNoise(plan, r.contributors, cycles.empty() ? nullptr : &cycles.front());
    o.reading_sigma_um = std::sqrt(noise.white_um2);
    o.declaration = noise.declaration;
    o.structured_um2 = noise.structured_um2;
    o.structured_draws_um = noise.structured_draws_um;
    requireValid(o, "rtest diagnosis");
    const RtestDiagnosis d = diagnoseRtest(plan, cycles, o);
    out.text = rtestDiagnosisText(plan, d);
    out.doc = rtestDiagnosisJson(plan, d);
    if (!d.analysis.screen.screen.excluded.empty() || d.analysis.screen.screen.too_many)
      out.warnings.push_back(rtestScreenText(plan, d.analysis.screen));
    return out;
  }
};

}  // namespace

const Cycle& rtestCycle() { return singleton<Rtest>(); }

}  // namespace rotacal
