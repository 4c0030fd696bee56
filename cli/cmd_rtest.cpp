#include "cli/cmd_rtest.hpp"
#include "cli/output.hpp"

#include <fmt/format.h>

#include "core/json_io.hpp"
#include "core/rtest.hpp"
#include "core/rtest_diagnosis.hpp"
#include "core/rtest_fit.hpp"
#include "core/simulation.hpp"

namespace rotacal {

int rtestSimulate(const Common& c, const ProbePlan& plan, const std::string& truth_file, double noise_um, bool noise_given,
                  std::uint64_t seed, double start_s, const std::string& out) {
  const JsonDoc doc = readJsonFile(truth_file);
  Truth truth = truthFromJson(doc, plan.machine.kinematics);
  RtestTruthExtras extras;
  rtestTruthFromJson(doc, plan.machine.kinematics, truth, extras);
  RtestSimOptions o;
  o.seed = seed;
  o.noise_um = noise_given ? noise_um : truth.noise_um;
  o.start_s = start_s;
  RtestSeries s;
  try {
    s = simulateRtest(plan, truth, extras, o);
  } catch (const std::invalid_argument& e) {
    failFile(truth_file, e.what());
  }
  OutputSet outputs;
  outputs.add("-o", out, rtestResultsCsv(plan, s));
  outputs.commit();
  if (out != "-")
    say(c, fmt::format("simulated {} R-test cycle(s) of {} readings (sensor noise {:.3f} um, seed {}) -> {}\n",
                       s.cycles.size(), plan.points.size(), o.noise_um, seed, out));
  return 0;
}

namespace {

std::vector<RtestCycle> readCycles(const ProbePlan& plan, const std::vector<std::string>& results) {
  std::vector<RtestCycle> cycles;
  const std::vector<std::string> texts = readResultsFiles(results);
  for (size_t i = 0; i < results.size(); ++i) {
    const std::string& f = results[i];
    const RtestSeries s = parseRtestResults(texts[i], f, plan);
    for (const auto& cy : s.cycles) {
      if (!cycles.empty() && cy.readings.front().t_s < cycles.back().readings.back().t_s)
        failFile(f, "cycles must be in time order across the results files");
      cycles.push_back(cy);
    }
  }
  return cycles;
}

double sensorSigma(const ProbePlan& plan) {
  return parseNumber("sensor_noise_um",
                     plan.options.count("sensor_noise_um") ? plan.options.at("sensor_noise_um") : std::string("0.2"));
}

}  // namespace

int rtestDiagnose(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results,
                  const std::string& json_out, const std::string& text_out, double alpha, const std::string& html_out) {
  const std::vector<RtestCycle> cycles = readCycles(plan, results);
  RtestDiagnosisOptions o;
  o.alpha = alpha;
  o.sensor_sigma_um = sensorSigma(plan);
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--alpha", e.what());
  }
  RtestDiagnosis d;
  try {
    d = diagnoseRtest(plan, cycles, o);
  } catch (const std::invalid_argument& e) {
    failFile(results.front(), e.what());
  }
  const std::string text = rtestDiagnosisText(plan, d);
  writeDocuments(c, rtestDiagnosisJson(plan, d), text, json_out, text_out, html_out);
  return 0;
}

int rtestAnalyze(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results,
                 const std::string& json_out, const std::string& text_out, const std::string& offsets_out, const std::string& html_out) {
  if (!offsets_out.empty())
    throw CLI::ValidationError("--offsets", "the R-test cycle reports position-dependent errors and their drift; it "
                                            "writes no offsets (use touch154 for the location errors)");
  const std::vector<RtestCycle> cycles = readCycles(plan, results);
  RtestFitOptions o;
  o.sensor_sigma_um = sensorSigma(plan);
  RtestAnalysis a;
  try {
    a = analyzeRtest(plan, cycles, o);
  } catch (const std::invalid_argument& e) {
    failFile(results.front(), e.what());
  }
  const std::string text = rtestReportText(plan, a);
  writeDocuments(c, rtestReportJson(plan, cycles, a, results), text, json_out, text_out, html_out);
  return 0;
}

}  // namespace rotacal
