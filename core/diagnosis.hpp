#pragma once
// What the model gets wrong (issue 6): residual analysis after the baseline fit, a search over
// the catalog of physical causes (core/causes.hpp), and a model selection that cannot fool
// itself: a cause is reported only when (1) it lowers the residual by more than noise of the
// known probe repeatability can (chi-square test, Bonferroni over the candidates), and (2) it
// predicts held-out data (leave one pose out) better by a margin the sampling of that
// held-out residual cannot explain. Causes the plan cannot tell from the location errors (or
// from each other) are listed as confounded, with how to separate them.
#include <functional>
#include <string>
#include <vector>

#include "core/identification.hpp"
#include "core/json_io.hpp"
#include "core/model_extension.hpp"
#include "core/statistics.hpp"  // chiSquareSurvival, once declared here

namespace rotacal {

struct DiagnosisOptions {
  double alpha = 1e-3;          // family-wise false-alarm rate of the chi-square test
  double min_holdout_gain = 0.02;  // held-out rms must drop by at least this fraction ...
  double holdout_sigmas = 2.0;  // ... and by this many standard errors of the rms estimate
  int max_causes = 2;
  double max_correlation = 0.95;  // above this a cause is reported as confounded with a location error
  double prior_sigma_um = 0.7;  // the probe's repeatability (MACHINE.json)
  std::vector<ExtensionPtr> candidates;  // empty: the catalog for the plan
  /// Called before each candidate fit with (fits done, fits at most); may be empty.
  std::function<void(int done, int total)> progress;

  bool validate(std::string* why) const;
};

struct FactorStatistic {
  std::string factor;        // "time", "pose", "approach", "face", "repeat", "X", "Y", "Z"
  std::string detail;        // e.g. the largest group mean, or the slope with its unit
  double chi2 = 0.0;
  int dof = 0;
  double p_value = 1.0;
  bool structured = false;   // p below alpha / number of factors
};

struct CandidateScore {
  std::string cause;
  std::string variant;
  int parameters = 0;
  double residual_rms_um = 0.0;
  double holdout_rms_um = 0.0;
  double chi2 = 0.0;   // (RSS_baseline - RSS_candidate) / sigma^2
  double p_value = 1.0;
  double bic = 0.0;
  std::string verdict;  // "accepted", or why not
};

struct Finding {
  std::string cause;
  std::string variant;
  std::string summary;
  struct Param {
    std::string name, unit;
    double value = 0.0, u = 0.0;
  };
  std::vector<Param> parameters;
  IdentificationResult fit;
  double residual_rms_um = 0.0;
  double holdout_rms_um = 0.0;
  double gain_pct = 0.0;
  /// Location errors in force at each repeat's mean time (drift findings).
  std::vector<std::pair<double, LocationErrors>> per_repeat;
};

struct Confounded {
  std::vector<std::string> causes;
  std::string why;
  std::string separate_with;
};

struct Diagnosis {
  IdentificationResult baseline;
  double baseline_holdout_rms_um = 0.0;
  std::string holdout_scheme;
  double sigma_um = 0.0;  // noise used by the tests: max(probe repeatability, fit's own)
  std::vector<FactorStatistic> residual_analysis;
  std::vector<CandidateScore> candidates;
  std::vector<Finding> findings;  // in order of acceptance
  std::vector<Confounded> confounded;
  std::vector<double> repeat_times_h;  // mean time of each repeat, relative to the data's mean
  bool effectFound() const { return !findings.empty(); }
};

Diagnosis diagnose(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const DiagnosisOptions& options);

Json diagnosisToJson(const Diagnosis& d);
std::string diagnosisText(const Diagnosis& d);

}  // namespace rotacal
