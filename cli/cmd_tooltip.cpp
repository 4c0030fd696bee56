#include "cli/cmd_tooltip.hpp"
#include "cli/output.hpp"

#include <fmt/format.h>

#include "core/json_io.hpp"
#include "core/tooltip.hpp"
#include "core/tooltip_fit.hpp"

namespace rotacal {
namespace {

std::vector<TooltipRun> readRuns(const ProbePlan& plan, const std::vector<std::string>& results) {
  std::vector<TooltipRun> runs;
  const std::vector<std::string> texts = readResultsFiles(results);
  for (size_t i = 0; i < results.size(); ++i) runs.push_back(parseTooltipResults(texts[i], results[i], plan));
  return runs;
}

}  // namespace

int simulateTooltipCmd(const Common& c, const ProbePlan& plan, const std::string& truth_file, double noise_um,
                       bool noise_given, std::uint64_t seed, const std::string& out) {
  const JsonDoc doc = readJsonFile(truth_file);
  TooltipTruth truth = tooltipTruthFrom(doc, doc.value);
  if (noise_given) truth.noise_um = noise_um;
  TooltipRun run;
  try {
    run = simulateTooltip(plan, truth, seed);
  } catch (const std::invalid_argument& e) {
    failFile(truth_file, e.what());
  }
  OutputSet outputs;
  outputs.add("-o", out, tooltipResultsText(plan, run));
  outputs.commit();
  if (out != "-")
    say(c, fmt::format("simulated {} tool-tip readings (dR {:.3f} um, noise {:.3f} um, seed {}) -> {}\n", run.size(),
                       truth.dR_um, truth.noise_um, seed, out));
  return 0;
}

int analyzeTooltipCmd(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results,
                      const std::string& json_out, const std::string& text_out, const std::string& html_out) {
  const std::vector<TooltipRun> runs = readRuns(plan, results);
  TooltipAnalysis a;
  try {
    a = analyzeTooltip(plan, runs);
  } catch (const std::invalid_argument& e) {
    failFile(results.front(), e.what());
  }
  a.result_files = results;
  const std::string text = tooltipReportText(plan, a);
  writeDocuments(c, tooltipReportJson(plan, runs, a), text, json_out, text_out, html_out);
  return 0;
}

int diagnoseTooltipCmd(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results, double alpha,
                       const std::string& json_out, const std::string& text_out, const std::string& html_out) {
  const std::vector<TooltipRun> runs = readRuns(plan, results);
  TooltipDiagnosisOptions o;
  o.alpha = alpha;
  std::string why;
  if (!o.validate(&why)) throw CLI::ValidationError("--alpha", why);
  TooltipDiagnosis d;
  try {
    d = diagnoseTooltip(plan, runs, o);
  } catch (const std::invalid_argument& e) {
    failFile(results.front(), e.what());
  }
  const std::string text = tooltipDiagnosisText(d);
  writeDocuments(c, tooltipDiagnosisJson(d), text, json_out, text_out, html_out);
  return 0;
}

}  // namespace rotacal
