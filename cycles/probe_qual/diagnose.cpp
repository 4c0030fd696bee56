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
  // The declared noise, never the data's, in the rows' unit (um along the approach, rows weighted
  // by w = 1 / |m . u|). The probe scatters along the approach: its repeatability reads 1:1. The
  // surface and the machine's axes move the contact itself: a roughness height h along the normal
  // reads w h, the axes' error e reads -w m . e (above the equator a horizontal approach reads
  // tan(latitude) of the vertical error too; analyze's u_B reads them the same way).
  DeclaredNoise noise = perTouchDeclaration(declared, plan.machine.probe.repeatability_um);
  std::vector<double> w_of_point(plan.points.size(), 1.0);
  std::vector<Eigen::Vector3d> t, reads;
  for (const auto& pt : plan.points) {
    const Eigen::Vector3d& m = touches[static_cast<size_t>(pt.target - 1)].n;
    w_of_point[t.size()] = 1.0 / std::max(1e-6, std::abs(m.dot(pt.approach_m)));
    t.push_back(pt.trigger_m_mm);
    reads.push_back(w_of_point[t.size() - 1] * m);
  }
  if (declared) addProbeAxesPart(*declared, t, reads, Eigen::VectorXd(), &noise);
  const Contributor* rough = declared ? declared->find("surface_roughness") : nullptr;
  // (perTouchDeclaration counts it only beside a declared probe_repeatability.)
  const double rough_um2 = rough && declared->find("probe_repeatability") ? std::pow(mmToUm(rough->u[0]), 2) : 0.0;
  std::vector<std::pair<int, int>> kept;
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto js = static_cast<size_t>(j);
    kept.emplace_back(q.repeat_of[js] / layout.repeats, q.point_index[js]);
  }
  p.covariance = noise.covariance(kept);
  // perTouchDeclaration counts the roughness once per touch; a touch above the equator reads w^2 of it.
  for (Eigen::Index j = 0; j < n; ++j) {
    const double w = w_of_point[static_cast<size_t>(q.point_index[static_cast<size_t>(j)])];
    p.covariance(j, j) += rough_um2 * (w * w - 1.0);
  }
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
