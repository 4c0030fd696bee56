#include "cycles/probe_qual/diagnose.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/contributor_draw.hpp"
#include "core/declared_noise.hpp"
#include "core/units.hpp"
#include "cycles/judge_contract.hpp"
#include "cycles/probe_qual/analyze.hpp"
#include "cycles/probe_qual/plan.hpp"

namespace rotacal {

namespace {

// The baseline the judge starts from, in words.
constexpr const char* kBaseline =
    "the sphere's centre and the probe's pretravel per approach direction (its mean and harmonics from the second on)";

std::string separateWith(const JudgeConfounded&) {
  return "repeat the qualification with the directions in another order (a drift follows the clock, a lobe the "
         "direction)";
}

}  // namespace

ProbeQualDiagnosis diagnoseProbeQual(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const JudgeOptions& options, const ContributorSet* declared) {
  const ProbeQualification q = qualifyProbe(plan, runs);
  const ProbeQualLayout layout = probeQualLayoutOf(plan);
  const auto touches = layout.touches();
  const auto n = static_cast<Eigen::Index>(q.residuals_um.size());
  JudgeProblem p;
  p.y = Eigen::Map<const Eigen::VectorXd>(q.residuals_um.data(), n);
  p.unit = "um";
  // The declared noise, never the data's: a row reads its trigger's displacement ds along the
  // approach as sign(m . u) ds (rows weighted by 1 / |m . u|).
  DeclaredNoise noise = perTouchDeclaration(declared, plan.machine.probe.repeatability_um);
  if (declared) {
    std::vector<Eigen::Vector3d> t, u;
    for (const auto& pt : plan.points) t.push_back(pt.trigger_m_mm), u.push_back(pt.approach_m);
    addProbeAxesPart(*declared, t, u, Eigen::VectorXd(), &noise);
  }
  std::vector<std::pair<int, int>> kept;
  Eigen::VectorXd sign(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto js = static_cast<size_t>(j);
    kept.emplace_back(q.repeat_of[js] / layout.repeats, q.point_index[js]);
    sign[j] = q.normals[js].dot(plan.points[static_cast<size_t>(q.point_index[js])].approach_m) < 0 ? -1.0 : 1.0;
  }
  p.covariance = sign.asDiagonal() * noise.covariance(kept) * sign.asDiagonal();
  p.declaration = noise.declaration;
  // The baseline at its solution: the sphere's centre and the pretravel per approach (um along
  // the approach per um).
  p.J0 = q.J_weighted;
  for (const auto& name : q.parameter_names) p.baseline_parameters.push_back({name, "um"});
  std::vector<double> weights;  // the rows read along the approach
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto js = static_cast<size_t>(j);
    weights.push_back(
        1.0 / std::max(1e-6, std::abs(q.normals[js].dot(plan.points[static_cast<size_t>(q.point_index[js])].approach_m))));
  }
  p.causes.push_back(sphereDriftCause(q.normals, q.t_s, weights));
  p.group_name = "repeat";
  p.groups = q.repeat_of;
  JudgeFactor touch{"touch", {}, {}, ""}, repeat{"repeat", {}, {}, ""};
  for (Eigen::Index j = 0; j < n; ++j) {
    touch.levels.push_back(touches[static_cast<size_t>(q.touch_of[static_cast<size_t>(j)])].name);
    repeat.levels.push_back(std::to_string(q.repeat_of[static_cast<size_t>(j)] + 1));
  }
  p.factors = {touch, repeat};
  return judgeWithTime(p, q.t_s, runs.size(), options, kBaseline, separateWith);
}

}  // namespace rotacal
