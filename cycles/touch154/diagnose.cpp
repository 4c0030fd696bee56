#include "cycles/touch154/diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/report_envelope.hpp"
#include "core/units.hpp"
#include "cycles/judge_contract.hpp"
#include "cycles/touch154/causes.hpp"
#include "core/require_valid.hpp"

namespace rotacal {

bool Touch154DiagnosisOptions::validate(std::string* why) const { return validJudgeAndProbe(judge, sigma_um, why); }

namespace {

std::string directionName(const Eigen::Vector3d& u) {
  int axis = 0;
  u.cwiseAbs().maxCoeff(&axis);
  return fmt::format("{}{}", u[axis] > 0 ? '+' : '-', "XYZ"[axis]);
}

/// Judge names must be unique: a cause with two variants (thermal drift) names the second.
std::vector<std::string> judgeNames(const std::vector<ExtensionPtr>& cands) {
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (const auto& c : cands) {
    std::string n = c->cause();
    if (!seen.insert(n).second) n += "_" + c->variant();
    names.push_back(n);
  }
  return names;
}

}  // namespace

JudgeProblem touch154JudgeProblem(const ProbePlan& plan, const Linearisation& lin,
                                  const std::vector<ExtensionPtr>& candidates, double sigma_um,
                                  const Touch154Noise* noise) {
  JudgeProblem p;
  const Eigen::Index n = lin.residual_um.size();
  p.y = lin.residual_um;
  if (noise && noise->noise.structured_um2.size()) {
    std::vector<std::pair<int, int>> kept;
    for (const auto& o : lin.observations) kept.emplace_back(o.run, noise->index_of_id.at(o.point->id));
    p.covariance = noise->noise.covariance(kept);
    p.null_draws = noise->noise.nullDraws(kept, kTouch154NullSeed);
  } else {
    p.sigma = Eigen::VectorXd::Constant(n, noise ? std::sqrt(noise->noise.white_um2) : sigma_um);
  }
  p.declaration = noise ? noise->noise.declaration
                        : fmt::format("declared: repeatability only ({:.3f} um, MACHINE.json probe.repeatability_um)", sigma_um);
  p.unit = "um";
  p.J0 = lin.J0;
  for (size_t k = 0; k < lin.J0_names.size(); ++k) p.baseline_parameters.push_back({lin.J0_names[k], lin.J0_units[k]});
  const auto names = judgeNames(candidates);
  for (size_t c = 0; c < candidates.size(); ++c) {
    JudgeCause jc;
    jc.name = names[c];
    jc.description = candidates[c]->describe();
    jc.J = lin.extension_J[c];
    for (const auto& prm : candidates[c]->parameters()) jc.parameters.push_back({prm.name, prm.unit});
    p.causes.push_back(jc);
  }
  // Leave one pose out (all its repeats): a pose is what the plan adds or drops.
  std::map<std::string, int> pose_id;
  for (const auto& pp : plan.poses) pose_id.emplace(pp.name, static_cast<int>(pose_id.size()));
  p.group_name = "pose";
  JudgeFactor time{"time", {}, {}, "h"}, pose{"pose", {}, {}, ""}, approach{"approach", {}, {}, ""},
      face{"face", {}, {}, ""}, repeat{"repeat", {}, {}, ""};
  JudgeFactor xyz[3] = {{"X", {}, {}, "mm"}, {"Y", {}, {}, "mm"}, {"Z", {}, {}, "mm"}};
  int runs = 0;
  for (const auto& o : lin.observations) {
    const auto it = pose_id.emplace(o.point->pose_name, static_cast<int>(pose_id.size())).first;
    p.groups.push_back(it->second);
    time.values.push_back(o.t_h);
    pose.levels.push_back(o.point->pose_name);
    approach.levels.push_back(directionName(o.point->approach_m));
    face.levels.emplace_back(faceName(o.point->face));
    repeat.levels.push_back(std::to_string(o.run + 1));
    for (int a = 0; a < 3; ++a) xyz[a].values.push_back(o.point->trigger_m_mm[a]);
    runs = std::max(runs, o.run + 1);
  }
  p.factors = {time, pose, approach, face};
  if (runs > 1) p.factors.push_back(repeat);
  for (auto& f : xyz) p.factors.push_back(f);
  return p;
}

Touch154Diagnosis diagnoseTouch154(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                   const Touch154DiagnosisOptions& options) {
  requireValid(options, "diagnosis options");
  Touch154Diagnosis d;
  d.candidates = options.candidates.empty() ? catalogFor(plan, static_cast<int>(runs.size())) : options.candidates;
  d.judge_names = judgeNames(d.candidates);
  IdentificationOptions io;
  io.method = Method::LeastSquaresPerPoint;
  io.prior_sigma_um = options.sigma_um;
  d.lin = lineariseAtBaseline(plan, runs, io, d.candidates);
  if (!d.lin.ok) return d;
  d.judged = judge(touch154JudgeProblem(plan, d.lin, d.candidates, options.sigma_um, options.noise), options.judge);
  // Each accepted cause refitted with the exact model (with the ones accepted before it): the
  // location errors it re-estimates and the residuals the figures draw.
  std::vector<ExtensionPtr> accepted;
  for (const auto& f : d.judged.findings) {
    const auto it = std::find(d.judge_names.begin(), d.judge_names.end(), f.cause);
    if (it == d.judge_names.end()) continue;
    Touch154Finding tf;
    tf.extension = d.candidates[static_cast<size_t>(it - d.judge_names.begin())];
    tf.judge_name = f.cause;
    accepted.push_back(tf.extension);
    IdentificationOptions ext = io;
    ext.extensions = accepted;
    tf.fit = identify(plan, runs, ext);
    d.findings.push_back(tf);
  }
  return d;
}

namespace {

/// What separates a confounded entry's causes, named by the contract's cause of the extension.
std::function<std::string(const JudgeConfounded&)> separateWith(const Touch154Diagnosis& d) {
  return [&d](const JudgeConfounded& c) {
    const auto it = std::find(d.judge_names.begin(), d.judge_names.end(), c.cause);
    const std::string cause =
        it == d.judge_names.end() ? c.cause : d.candidates[static_cast<size_t>(it - d.judge_names.begin())]->cause();
    return separationHint(cause, c.with);
  };
}

}  // namespace

Json touch154DiagnosisJson(const Touch154Diagnosis& d, const ProbePlan& plan) {
  const JudgeSummary& s = d.judged;
  Json j = judgeToJson(s);
  stampDiagnosis(j, plan.cycle);
  // The contract's fields (docs/../contract.md), beside the judge's own.
  Json& b = j["baseline"];
  b["model"] = "location errors + one surface offset per target point (lsq_per_point)";
  b["residual_rms_um"] = d.lin.baseline.summary.residual_rms_um;
  b["holdout_rms_um"] = s.baseline_holdout_rms;
  b["location_errors"] = locationErrorsJson(d.lin.baseline.estimate, d.lin.baseline.u);
  j["holdout"] = "leave one pose out (every repeat of it), exact for the linearised model";
  j["sigma_um"] = s.declared_sigma_rms;  // the declared noise the tests use
  for (size_t k = 0; k < d.findings.size() && k < j["findings"].size(); ++k) {
    Json& f = j["findings"][k];
    const auto& tf = d.findings[k];
    const JudgeFinding& jf = s.findings[k];
    f["cause"] = tf.extension->cause();
    f["variant"] = tf.extension->variant();
    const std::string params = findingParametersText(jf);
    const double gain = holdoutGainPct(s, jf);
    f["summary"] = fmt::format("{}: {}; held-out residual {:.3f} -> {:.3f} um ({:+.0f} %)", tf.extension->describe(), params,
                               s.baseline_holdout_rms, jf.holdout_rms_cause, -gain);
    f["location_errors"] = locationErrorsJson(tf.fit.estimate, tf.fit.u);
    f["residual_rms_um"] = tf.fit.summary.residual_rms_um;
    f["holdout_rms_um"] = jf.holdout_rms_cause;
    f["gain_pct"] = gain;
  }
  writeConfounded(j, s, separateWith(d));
  return j;
}

std::string touch154DiagnosisText(const Touch154Diagnosis& d) {
  std::string s = fmt::format(
      "baseline (location errors + per-point offsets): residual rms {:.3f} um, held-out rms {:.3f} um (leave one pose out)\n",
      d.lin.baseline.summary.residual_rms_um, d.judged.baseline_holdout_rms);
  s += fmt::format("declared noise: {:.3f} um rms {} ({})\n", d.judged.declared_sigma_rms,
                   d.judged.correlated ? "left in the baseline's residual" : "per touch", d.judged.declaration);
  s += judgeText(d.judged, separateWith(d));
  for (const auto& f : d.findings) {
    const auto& params = locationParameters(f.fit.estimate.kinematics);
    s += fmt::format("location errors with {} (exact refit):\n  {:<8} {:>10} {:>10}\n", f.extension->cause(), "error",
                     "baseline", "extended");
    for (int i = 0; i < kNumLocationErrors; ++i)
      s += fmt::format("  {:<8} {:>10.3f} {:>10.3f} {}\n", params[i].name, d.lin.baseline.estimate.reportValue(i),
                       f.fit.estimate.reportValue(i), reportUnit(params[i].kind));
  }
  return s;
}

}  // namespace rotacal
