// tooltip (004): angular positioning error and pivot length of a head's axis from a fixed-tool-tip
// program. The laser writes its own file whatever the controller; no offsets.
#include <cmath>

#include "core/contributor_draw.hpp"

#include <fmt/format.h>

#include "core/errors.hpp"
#include "core/report_envelope.hpp"
#include "cycles/tooltip/plan.hpp"
#include "cycles/tooltip/analyze.hpp"
#include "cycles/tooltip/budget.hpp"
#include "cycles/tooltip/diagnose.hpp"
#include "cycles/tooltip/noise.hpp"
#include "cycles/tooltip/screen.hpp"
#include "cycles/cycle.hpp"
#include "cycles/tooltip/program.hpp"
#include "core/require_valid.hpp"
#include "core/singleton.hpp"

namespace rotacal {
namespace {

/// Every run of every results file, in order (a file holds the runs of one program); `file_of`
/// (optional): the index in `results` of each run's file.
std::vector<TooltipRun> readRuns(const ProbePlan& plan, const std::vector<InputFile>& results,
                                 std::vector<size_t>* file_of = nullptr) {
  std::vector<TooltipRun> runs;
  for (size_t f = 0; f < results.size(); ++f)
    for (TooltipRun& run : parseTooltipResults(results[f].text, results[f].path, plan)) {
      runs.push_back(std::move(run));
      if (file_of) file_of->push_back(f);
    }
  return runs;
}

/// A plan's `planned` runs not all read: the text says what the missing ones would have seen.
std::string fewerRunsThanPlanned(int planned, size_t read) {
  if (read >= static_cast<size_t>(planned)) return {};
  return fmt::format("{} run{} read where the plan repeats {}: {}", read, read == 1 ? "" : "s", planned,
                     read < static_cast<size_t>(kTooltipRepeats)
                         ? fmt::format("a gross reading along the tool tip's circle is seen from {} runs on", kTooltipRepeats)
                         : std::string("the values are those of the runs read"));
}

/// The cycle writes no offsets; its values go into the machine's kinematics tables by hand. When
/// they must not, REPORT.json, the text and the warnings say why (and `--offsets` gives it).
void holdBack(CycleDocuments* out, const std::string& why) {
  if (why.empty() || !out->offsets_refused.empty()) return;
  out->offsets_refused = why;
  out->warnings.push_back(why);
  out->doc["corrections_held_back"] = why;
  out->text += "corrections held back: " + why + "\n";
}

class Tooltip final : public Cycle {
 public:
  Tooltip() : Cycle({"tooltip",
                      "004: angular positioning error and pivot length of a head's axis from a fixed-tool-tip program",
                      {"examples/machines/head_ab.json", {}, "examples/truth/tooltip_dr.json"},
                      7004,  // 7000 + its source document (004)
                      makeTooltipPlan, tooltipProgram, tooltipPlanRules(),
                      "the tooltip cycle writes no offsets (a head's pivot length and angular errors go into the "
                      "machine's kinematics tables by hand)",
                      "tool-tip poses"}) {}

  // Every run but the last ends with the move back to the next run's start.
  double machineSeconds(const ProbePlan& plan) const override {
    const int runs = tooltipOptionsFrom(plan.options, plan.machine).repeats;
    return runs * tooltipRunSeconds(plan) - (plan.points.empty() ? 0.0 : 60.0);
  }

  Simulated simulate(const SimulateRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    const JsonDoc doc = parseJsonText(r.truth.text, r.truth.path);
    TooltipTruth truth = tooltipTruthFrom(doc, doc.value);
    // --contributors: a machine drawn from them on top of the truth file, as the budget draws
    // it (drawTooltip, run 0 of the machine seed: the linear axes carrying the pivot, the beams'
    // alignment), and the declared per-reading scatter as the noise, replacing the truth file's
    // (one declaration, not two).
    TooltipMachine machine;
    Json truth_json;
    std::string drawn;
    if (r.contributors) {
      const ContributorSplit split = splitContributors(*r.contributors, tooltipTypeA, tooltipTypeB);
      TooltipDraw draw;
      onTruthFile(r.truth, [&] {
        drawTooltip(plan, split.type_b, r.machine_seed, 0, -1, &draw);
        return 0;
      });
      machine = tooltipMachineOf(plan, draw);
      truth.noise_um = std::sqrt(tooltipDeclaredNoise(plan, r.contributors).white_um2);
      const std::string from = r.contributors->file.empty() ? std::string("the machine's contributors") : r.contributors->file;
      truth_json = doc.value;
      Json rec = tooltipDrawJson(draw);
      rec["seed"] = r.machine_seed;
      rec["contributors"] = from;
      rec["per_reading_um"] = std::round(truth.noise_um * 1e6) / 1e6;
      if (!split.left_out.empty()) rec["left_out"] = split.left_out;
      truth_json["drawn"] = rec;
      drawn = fmt::format(", a machine drawn from {} (machine seed {})", from, r.machine_seed);
    }
    // Both are >= 0: the truth file's reader and --noise-um's check refuse a negative noise.
    if (r.noise_um) truth.noise_um = *r.noise_um;
    if (!truth_json.is_null()) truth_json["noise_um"] = truth.noise_um;
    const std::vector<TooltipRun> runs =
        onTruthFile(r.truth, [&] { return simulateTooltipRepeats(plan, truth, r.seed, machine, r.start_s.value_or(0.0)); });
    Simulated s{tooltipResultsText(plan, runs),
                fmt::format("simulated {} tool-tip readings{} (dR {:.3f} um, noise {:.3f} um, seed {}{})",
                            runs.size() * plan.points.size(),
                            runs.size() > 1 ? fmt::format(" in {} runs", runs.size()) : std::string(), truth.dR_um,
                            truth.noise_um, r.seed, drawn),
                truth_json};
    s.injected["location_errors"] = {{"dR", truth.dR_um}};
    return s;
  }

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    const std::vector<TooltipRun> read = readRuns(plan, r.results);
    // Gross readings (a laser glitch, a chip): found against what the machine's contributors
    // declare, left out of every fit below with the reason; too many: nothing left out, and the
    // values are held back.
    const DeclaredNoise noise = tooltipDeclaredNoise(plan, r.contributors, &read.front());
    const TooltipScreen screen = screenTooltipReadings(plan, read, noise);
    const std::vector<TooltipRun> runs = withoutScreened(read, screen);
    TooltipAnalysis a = analyzeTooltip(plan, runs);
    a.result_files = pathsOf(r.results);
    CycleDocuments out;
    out.doc = tooltipReportJson(plan, runs, a);
    const TooltipOptions to = tooltipOptionsFrom(plan.options, plan.machine);
    const std::string fewer = fewerRunsThanPlanned(to.repeats, read.size());
    if (!fewer.empty()) {
      out.warnings.push_back(fewer);
      out.doc["runs_read"] = {{"read", read.size()}, {"planned", to.repeats}, {"note", fewer}};
    }
    out.doc["errors_heading"] = "Identified errors";  // a pivot length and angular errors, not location errors in ISO 230-7's sense
    // What analyze signs: u_A from the data, u_B from the declared contributors by
    // Monte Carlo through the same fit (cycles/tooltip/budget.hpp, docs/uncertainty.md).
    TooltipBudgetOptions bo;
    bo.runs = r.mc_runs;
    bo.seed = r.mc_seed;
    const UncertaintyBudget b = tooltipBudget(plan, runs, a, to.noise_um, r.contributors, bo);
    addBudgetFields(&out.doc["location_errors"], b);
    // The angular errors are an array by angle: each entry gets the same fields, u = u_c.
    const Eigen::VectorXd ua = b.uA(), ub = b.uB(), k = b.coverageFactors();
    for (auto& e : out.doc["angular_error"])
      for (int i = 0; i < b.size(); ++i)
        if (b.names[static_cast<size_t>(i)] == fmt::format("e_{}{:g}", to.axis, e["angle_deg"].get<double>()))
          setUncertaintyFields(&e, ua[i], ub[i], k[i]);
    const Eigen::VectorXd values = tooltipBudgetValues(a, b);
    out.doc["uncertainty"] = budgetJson(b, values);
    out.text = tooltipReportText(plan, a, &b) + "\n" + budgetText(b, values);
    if (!fewer.empty()) out.text += fewer + "\n";
    out.doc["outliers"] = tooltipScreenJson(plan, screen);
    out.text += tooltipScreenText(plan, screen) + "\n" + screen.screen.reachLine("values");
    if (!screen.screen.excluded.empty()) out.warnings.push_back(tooltipScreenText(plan, screen));
    if (screen.screen.too_many) holdBack(&out, tooltipScreenText(plan, screen));
    // The data against what the machine's contributors declare (the budget's own model): beyond
    // it, the model does not explain this machine, and its values go into no kinematics table.
    const DeclaredNoiseTest test =
        testAgainstDeclared(a.joint.kept_residual_um, a.joint.kept_J, noise.covariance(a.joint.kept_values));
    out.doc["declared_noise"] = declaredNoiseJson(noise, test);
    out.text += "declared noise: " + out.doc["declared_noise"]["summary"].get<std::string>() + " (" + noise.declaration + ")\n";
    holdBack(&out, offsetsHeldBack(noise, test));
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    std::vector<size_t> file_of;
    const std::vector<TooltipRun> runs = readRuns(plan, r.results, &file_of);
    for (size_t k = 0; k < runs.size(); ++k)
      for (const auto& reading : runs[k])
        if (!std::isfinite(reading.z_um))
          throw InputError(r.results[file_of[k]].path, 1,
                           "diagnose needs both directions of the reading (dz too): its causes (pivot length, scale, "
                           "drift) differ only in how they split between the two; analyze reads one direction");
    TooltipDiagnosisOptions o;
    o.judge.alpha = r.alpha;
    o.contributors = r.contributors;  // the declared noise; none: the plan's laser_noise_um alone
    requireValid(o, "tooltip diagnosis");
    // The judge sees the readings the screen keeps (all of them when it found too many).
    const TooltipScreen screen = screenTooltipReadings(plan, runs, tooltipDeclaredNoise(plan, r.contributors, &runs.front()));
    const TooltipDiagnosis d = diagnoseTooltip({{&plan, withoutScreened(runs, screen)}}, o);
    CycleDocuments out = documents(tooltipDiagnosisJson(d), tooltipDiagnosisText(d) + tooltipScreenText(plan, screen) + "\n");
    out.doc["outliers"] = tooltipScreenJson(plan, screen);
    if (!screen.screen.excluded.empty() || screen.screen.too_many) out.warnings.push_back(tooltipScreenText(plan, screen));
    return out;
  }
};

}  // namespace

const Cycle& tooltipCycle() { return singleton<Tooltip>(); }

}  // namespace rotacal
