#pragma once
// The diagnosis contract's fields (contract.md) that the cycles derive from the judge's summary
// (core/judge.hpp): one form for every cycle that writes them.
#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include <functional>
#include <utility>
#include <string>

#include "core/json_io.hpp"
#include "core/judge.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// What every probing cycle's diagnosis options must hold: valid judge options and a declared
/// probe repeatability > 0 (the judge weighs the residuals by it). False with `why` otherwise.
inline bool validJudgeAndProbe(const JudgeOptions& judge, double sigma_um, std::string* why) {
  if (!judge.validate(why)) return false;
  if (!(sigma_um > 0)) {
    if (why) *why = "the declared probe repeatability must be > 0 um";
    return false;
  }
  return true;
}

/// The contract's format and cycle of a diagnosis document.
inline void stampDiagnosis(Json& j, const std::string& cycle) {
  j["format"] = "rotacal-diagnosis/1";
  j["cycle"] = cycle;
}

/// The judge's verdict, its message and whether the final model explains the data, for a cycle
/// that does not write the whole summary (judgeToJson writes them too).
inline void verdictJson(Json& j, const JudgeSummary& s) {
  j["verdict"] = judgeVerdictName(s.verdict);
  j["message"] = s.message;
  j["explains_data"] = s.explainsData();
}

/// The contract's fields of a finding that the judge's summary holds: its parameters (u null
/// where not identifiable), the final model's residual, the finding's held-out residual and its
/// gain against the model before it (percent), its separability and confidence.
inline Json contractFindingJson(const JudgeSummary& s, const JudgeFinding& f) {
  Json params = Json::object();
  for (const auto& p : f.parameters)
    params[p.name] = {{"value", p.value}, {"unit", p.unit}, {"u", p.identifiable ? Json(p.u) : Json(nullptr)}};
  return {{"parameters", params},
          {"residual_rms_um", s.final_model.rms_residual},
          {"holdout_rms_um", f.holdout_rms_cause},
          {"gain_pct", f.holdout_rms_model > 0 ? 100.0 * (1.0 - f.holdout_rms_cause / f.holdout_rms_model) : 0.0},
          {"separability", f.separability},
          {"confidence", f.confidence}};
}

/// The contract's `findings`: each finding's fields (contractFindingJson), its cause and a one-line
/// summary in the cycle's words; `extra` adds to an entry what only the cycle knows (may be empty).
inline Json contractFindingsJson(const JudgeSummary& s, const std::function<std::string(const JudgeFinding&)>& summary,
                                 const std::function<void(const JudgeFinding&, Json&)>& extra = {}) {
  Json out = Json::array();
  for (const auto& f : s.findings) {
    Json e = contractFindingJson(s, f);
    e["cause"] = f.cause;
    e["summary"] = summary(f);
    if (extra) extra(f, e);
    out.push_back(e);
  }
  return out;
}

/// "name = value +- u unit" of each of a finding's parameters, comma-separated.
inline std::string findingParametersText(const JudgeFinding& f) {
  std::string params;
  for (const auto& p : f.parameters)
    params += (params.empty() ? "" : ", ") + fmt::format("{} = {:.3g} +- {:.2g} {}", p.name, p.value, p.u, p.unit);
  return params;
}

/// How far a finding lowers the held-out residual below the baseline's, percent (0 without a
/// baseline residual).
inline double holdoutGainPct(const JudgeSummary& s, const JudgeFinding& f) {
  return s.baseline_holdout_rms > 0 ? 100.0 * (1.0 - f.holdout_rms_cause / s.baseline_holdout_rms) : 0.0;
}

/// The contract's baseline of a cycle that writes the judge's adequacy test itself: `model` in
/// words, its residual and held-out rms, chi2, dof, p and whether it is within the declared noise.
inline Json contractBaselineJson(const JudgeSummary& s, const std::string& model) {
  return {{"model", model},
          {"residual_rms_um", s.baseline.rms_residual},
          {"holdout_rms_um", s.baseline_holdout_rms},
          {"chi2", s.baseline.chi2},
          {"dof", s.baseline.dof},
          {"p_value", s.baseline.p_value},
          {"within_declared_noise", s.baseline.passes}};
}

/// thermal_drift of a sphere cycle: the sphere moving by v (t - t_mid) in the machine frame, v
/// in um/h along X, Y, Z; a touch reads it along its normal n_j (its residual falls by
/// n_j . v dt), times its row weight w_j (1 when empty).
inline JudgeCause sphereDriftCause(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& t_s,
                                   const std::vector<double>& weights = {}) {
  double t_lo = 1e300, t_hi = -1e300;
  for (double t : t_s) t_lo = std::min(t_lo, t), t_hi = std::max(t_hi, t);
  const double t_mid = 0.5 * (t_lo + t_hi);
  const auto n = static_cast<Eigen::Index>(normals.size());
  JudgeCause drift{"thermal_drift", "the sphere drifting linearly in time in X, Y, Z (thermal growth over the cycle)",
                   Eigen::MatrixXd(n, 3), {{"vX", "um/h"}, {"vY", "um/h"}, {"vZ", "um/h"}}};
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto js = static_cast<size_t>(j);
    drift.J.row(j) = -(weights.empty() ? 1.0 : weights[js]) * normals[js].transpose() * (t_s[js] - t_mid) / 3600.0;
  }
  return drift;
}

/// The observations' time (s) as a factor of the problem, when they span any.
inline void addTimeFactor(JudgeProblem& p, const std::vector<double>& t_s) {
  if (t_s.empty() || *std::max_element(t_s.begin(), t_s.end()) <= *std::min_element(t_s.begin(), t_s.end())) return;
  p.factors.push_back({"time", {}, t_s, "s"});
}

/// The diagnosis of a cycle whose baseline is one fit judged as a whole: the judge's summary
/// over how many repeats, the baseline in words (`model`) and what would tell a confounded cause
/// apart (`separate_with`).
struct JudgedFit {
  JudgeSummary summary;
  int runs = 0;
  std::string model;
  std::function<std::string(const JudgeConfounded&)> separate_with;
};

/// The tail such a diagnosis shares: the observations' time as a factor, then the judge.
inline JudgedFit judgeWithTime(JudgeProblem& p, const std::vector<double>& t_s, size_t runs, const JudgeOptions& o,
                               std::string model, std::function<std::string(const JudgeConfounded&)> separate_with) {
  addTimeFactor(p, t_s);
  return {judge(p, o), static_cast<int>(runs), std::move(model), std::move(separate_with)};
}

/// The DIAGNOSIS.json of such a diagnosis: the contract's fields.
inline Json judgedDiagnosisJson(const std::string& cycle, const ProbePlan& plan, const JudgedFit& d) {
  const JudgeSummary& s = d.summary;
  const int runs = d.runs;
  const std::string& model = d.model;
  const auto& separate_with = d.separate_with;
  Json j;
  stampDiagnosis(j, cycle);
  j["machine"] = plan.machine.name;
  j["repeats"] = runs;
  j["declared_sigma_um"] = s.declared_sigma_rms;
  j["baseline"] = contractBaselineJson(s, model);
  j["baseline"]["holdout"] = fmt::format("leave one {} out", s.group_name);
  verdictJson(j, s);
  j["findings"] = contractFindingsJson(
      s, [](const JudgeFinding& f) { return f.description + ": " + findingParametersText(f); });
  writeConfounded(j, s, separate_with);
  j["judge"] = judgeToJson(s);
  return j;
}

}  // namespace rotacal
