#include "cycles/probe_qual/diagnose.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "cycles/judge_contract.hpp"
#include "cycles/probe_qual/analyze.hpp"
#include "cycles/probe_qual/plan.hpp"

namespace rotacal {

namespace {

constexpr const char* kDrift = "thermal_drift";

std::string separateWith(const JudgeConfounded&) {
  return "repeat the qualification with the directions in another order (a drift follows the clock, a lobe the "
         "direction)";
}

}  // namespace

ProbeQualDiagnosis diagnoseProbeQual(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const JudgeOptions& options) {
  const ProbeQualification q = qualifyProbe(plan, runs);
  const auto touches = probeQualLayoutOf(plan).touches();
  const auto n = static_cast<Eigen::Index>(q.residuals_um.size());
  JudgeProblem p;
  p.y = Eigen::Map<const Eigen::VectorXd>(q.residuals_um.data(), n);
  p.sigma = Eigen::VectorXd::Constant(n, plan.machine.probe.repeatability_um);  // declared, never the data's
  p.unit = "um";
  // The baseline at its solution: the sphere's centre and the pretravel per approach (um along
  // the approach per um).
  p.J0 = q.J_weighted;
  for (const auto& name : q.parameter_names) p.baseline_parameters.push_back({name, "um"});
  double t_lo = 1e300, t_hi = -1e300;
  for (double t : q.t_s) t_lo = std::min(t_lo, t), t_hi = std::max(t_hi, t);
  const double t_mid = 0.5 * (t_lo + t_hi);
  JudgeCause drift{kDrift, "the sphere drifting linearly in time in X, Y, Z (thermal growth over the cycle)",
                   Eigen::MatrixXd(n, 3), {{"vX", "um/h"}, {"vY", "um/h"}, {"vZ", "um/h"}}};
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto js = static_cast<size_t>(j);
    const Eigen::Vector3d& u = plan.points[js % plan.points.size()].approach_m;
    const double w = 1.0 / std::max(1e-6, std::abs(q.normals[js].dot(u)));
    drift.J.row(j) = -w * q.normals[js].transpose() * (q.t_s[js] - t_mid) / 3600.0;
  }
  p.causes.push_back(drift);
  p.group_name = "repeat";
  p.groups = q.repeat_of;
  JudgeFactor direction{"touch", {}, {}, ""}, repeat{"repeat", {}, {}, ""}, time{"time", {}, {}, "s"};
  for (Eigen::Index j = 0; j < n; ++j) {
    direction.levels.push_back(touches[static_cast<size_t>(q.touch_of[static_cast<size_t>(j)])].name);
    repeat.levels.push_back(std::to_string(q.repeat_of[static_cast<size_t>(j)] + 1));
    time.values.push_back(q.t_s[static_cast<size_t>(j)]);
  }
  p.factors = {direction, repeat};
  if (t_hi > t_lo) p.factors.push_back(time);
  ProbeQualDiagnosis d;
  d.runs = static_cast<int>(runs.size());
  d.summary = judge(p, options);
  return d;
}

Json probeQualDiagnosisJson(const ProbeQualDiagnosis& d, const ProbePlan& plan) {
  const JudgeSummary& s = d.summary;
  Json j;
  stampDiagnosis(j, "probe_qual");
  j["machine"] = plan.machine.name;
  j["repeats"] = d.runs;
  j["declared_sigma_um"] = s.declared_sigma_rms;
  j["baseline"] = contractBaselineJson(s, "the sphere's centre and the probe's pretravel per approach direction (its "
                                          "mean and harmonics from the second on)");
  j["baseline"]["holdout"] = fmt::format("leave one {} out", s.group_name);
  verdictJson(j, s);
  j["findings"] = contractFindingsJson(
      s, [](const JudgeFinding& f) { return f.description + ": " + findingParametersText(f); });
  j["confounded"] = confoundedJson(s, separateWith);
  j["judge"] = judgeToJson(s);
  return j;
}

}  // namespace rotacal
