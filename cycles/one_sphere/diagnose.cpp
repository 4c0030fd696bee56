#include "cycles/one_sphere/diagnose.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "core/declared_noise.hpp"
#include "core/units.hpp"
#include "cycles/judge_contract.hpp"
#include "cycles/one_sphere/analyze.hpp"
#include "cycles/one_sphere/plan.hpp"

namespace rotacal {

namespace {

constexpr const char* kDrift = "thermal_drift";
constexpr const char* kPretravel = "pretravel_by_direction";

// The baseline the judge starts from, in words.
constexpr const char* kBaseline =
    "both rotary axes' ISO 230-7 location errors (core/kinematic_model.hpp), the sphere's set-up and the probe's "
    "effective radius";

std::string separateWith(const JudgeConfounded& c) {
  if (c.cause == kDrift)
    return "repeat the cycle with the poses in another order (a drift follows the clock, a location error the pose)";
  return "touch each pose from more directions (both sides of every axis where the stem allows)";
}

}  // namespace

SphereDiagnosis diagnoseSphere(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const JudgeOptions& options,
                               const ContributorSet* declared) {
  const SphereCycleResult fit = identifySphereCycle(plan, runs);
  const auto n = static_cast<Eigen::Index>(fit.residuals_um.size());
  JudgeProblem p;
  p.y = Eigen::Map<const Eigen::VectorXd>(fit.residuals_um.data(), n);
  // The declared covariance of the touches, never the fit's own scatter: the linear axes' shared
  // errors are part of the declared machine, not a misfit.
  const DeclaredNoise noise = sphereDeclaredNoise(plan, declared);
  const SphereFittedProblem declared_fit = sphereFittedProblem(noise, fit);
  p.covariance = declared_fit.covariance_um2;
  // The null from draws of the declared machine (its node spacing one per machine: a scale
  // mixture, heavier-tailed than a normal of the same covariance), the draws analyze's adequacy
  // test reads: one data set, one null.
  p.null_draws = noise.nullDraws(declared_fit.readings, kDeclaredNullSeed + 2);
  p.declaration = noise.declaration;
  p.unit = "um";
  // The baseline at its solution: the columns of the parameters the fit frees, in um per report
  // unit. The held ones (the plan's unseen directions, analyze's `unseparable`) stay out: their
  // columns add nothing to the span, but with them a cause confounded with the model was read as
  // a minimum-norm mix along the unseen directions (pretravel +-Y as S_yz = -33 mdeg with
  // A0B = +33 mdeg under a head), and at the measured triggers a nearly unseen direction could
  // count in the judge's rank when the fit held it.
  for (size_t i = 0; i < fit.names.size(); ++i) {
    if (fit.identifiability.held[i]) continue;
    const double per = fit.names[i].kind == ParamKind::Length ? 1.0 : kUmPerMm / kMdegPerRad;  // um per um, um per mdeg
    p.J0.conservativeResize(n, p.J0.cols() + 1);
    p.J0.col(p.J0.cols() - 1) = fit.J_r_x.col(static_cast<Eigen::Index>(i)) * per;
    p.baseline_parameters.push_back({fit.names[i].name, std::string(reportUnit(fit.names[i].kind))});
  }
  // Drift: the sphere moving linearly in time in the machine frame.
  p.causes.push_back(sphereDriftCause(fit.normals, fit.t_s));
  // Pretravel by direction: one trigger distance per approach beyond the first (the mean is the
  // model's dR); a direction no pose used has no column.
  // A touch is classed by the nearest of the five approaches: a head leaning diagonally turns its
  // sides off the axes (plan.cpp), and a class per turned direction would leave one touch each.
  const auto& approaches = sphereApproaches();
  const char* dir_names[] = {"-X", "-Y", "+X", "+Y", "-Z"};
  std::vector<int> class_of(static_cast<size_t>(n));
  for (Eigen::Index j = 0; j < n; ++j) {
    const Eigen::Vector3d& u = plan.points[static_cast<size_t>(fit.point_index[static_cast<size_t>(j)])].approach_m;
    size_t best = 0;
    for (size_t c = 1; c < approaches.size(); ++c)
      if (approaches[c].dot(u) > approaches[best].dot(u) + 1e-9) best = c;
    class_of[static_cast<size_t>(j)] = static_cast<int>(best);
  }
  JudgeCause pre{kPretravel, "the probe's trigger distance differing by approach direction (lobing)", Eigen::MatrixXd(n, 0), {}};
  for (size_t a = 1; a < approaches.size(); ++a) {
    Eigen::VectorXd col = Eigen::VectorXd::Zero(n);
    for (Eigen::Index j = 0; j < n; ++j)
      if (class_of[static_cast<size_t>(j)] == static_cast<int>(a)) col[j] = -1.0;
    if (col.cwiseAbs().sum() == 0) continue;
    pre.J.conservativeResize(n, pre.J.cols() + 1);
    pre.J.col(pre.J.cols() - 1) = col;
    pre.parameters.push_back({fmt::format("pretravel_{}", dir_names[a]), "um"});
  }
  if (pre.J.cols() > 0) p.causes.push_back(pre);
  p.group_name = "pose";
  JudgeFactor pose{"pose", {}, {}, ""}, approach{"approach", {}, {}, ""};
  for (Eigen::Index j = 0; j < n; ++j) {
    const ProbePoint& pt = plan.points[static_cast<size_t>(fit.point_index[static_cast<size_t>(j)])];
    pose.levels.push_back(pt.pose_name);
    approach.levels.push_back(dir_names[class_of[static_cast<size_t>(j)]]);
  }
  // Leave one pose out: the group is the pose's index among the plan's poses.
  for (Eigen::Index j = 0; j < n; ++j) {
    const std::string& name = pose.levels[static_cast<size_t>(j)];
    int g = 0;
    for (size_t k = 0; k < plan.poses.size(); ++k)
      if (plan.poses[k].name == name) g = static_cast<int>(k);
    p.groups.push_back(g);
  }
  p.factors = {pose, approach};
  return judgeWithTime(p, fit.t_s, runs.size(), options, kBaseline, separateWith);
}

}  // namespace rotacal
