#include "cycles/touch154/identification.hpp"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/simulation.hpp"
#include "core/least_squares.hpp"
#include "core/units.hpp"

namespace rotacal {

std::string_view methodName(Method m) {
  switch (m) {
    case Method::ClosedForm: return "closed_form";
    case Method::LeastSquaresRigidSetup: return "lsq_rigid_setup";
    case Method::LeastSquaresPerPoint: return "lsq_per_point";
  }
  return "?";
}

Method methodFromName(std::string_view name) {
  if (name == "closed_form") return Method::ClosedForm;
  if (name == "lsq_rigid_setup") return Method::LeastSquaresRigidSetup;
  if (name == "lsq_per_point" || name == "lsq") return Method::LeastSquaresPerPoint;
  throw std::invalid_argument("unknown method '" + std::string(name) +
                              "' (expected closed_form, lsq_rigid_setup, lsq_per_point)");
}

bool IdentificationOptions::validate(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(step_tolerance > 0)) return fail("step_tolerance must be > 0");
  if (!(rank_tolerance > 0 && rank_tolerance < 1)) return fail("rank_tolerance must be in (0, 1)");
  if (!(prior_sigma_um >= 0)) return fail("prior_sigma_um must be >= 0");
  return true;
}

double observationTime_s(const ProbePlan& plan, int run, const ProbePoint& point, const TriggerPoint& trigger) {
  if (std::isfinite(trigger.t_s)) return trigger.t_s;
  const double cycle = plan.points.empty() ? 0.0 : plan.points.back().t_s + 60.0;
  return point.t_s + run * cycle;
}

namespace {

struct Observation {
  int run;
  const ProbePoint* point;
  double s_mm;  // measured, along the approach from the nominal trigger
  Eigen::Vector3d measured_m;
  double t_h = 0.0;
  bool held_out = false;

  ObservationContext context() const { return ObservationContext{point, run, t_h}; }
};

std::vector<Observation> collect(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                 const IdentificationOptions& options, std::string* why) {
  std::vector<Observation> obs;
  double t_sum = 0.0;
  int t_n = 0;
  for (size_t r = 0; r < runs.size(); ++r) {
    for (const auto& t : runs[r].points) {
      const ProbePoint* p = plan.findPoint(t.point_id);
      if (!p) {
        *why = fmt::format("{}: point {} is not in the plan", runs[r].source, t.point_id);
        return {};
      }
      Observation o{static_cast<int>(r), p, alongApproach(*p, t), t.position_m_mm};
      o.t_h = observationTime_s(plan, static_cast<int>(r), *p, t) / 3600.0;
      o.held_out = options.hold_out && options.hold_out(static_cast<int>(r), *p);
      if (!o.held_out) {
        t_sum += o.t_h;
        ++t_n;
      }
      obs.push_back(o);
    }
  }
  const double t_mean = t_n ? t_sum / t_n : 0.0;
  for (auto& o : obs) o.t_h -= t_mean;
  return obs;
}

/// Parameter layout and model of the least-squares problem.
class LsqModel {
 public:
  LsqModel(const ProbePlan& plan, const std::vector<Observation>& obs, Method method,
           const std::vector<ExtensionPtr>& extensions)
      : plan_(plan), obs_(obs), method_(method), r_(plan.machine.probe.ball_radius_mm()), ext_(extensions) {
    for (const auto& x : ext_) {
      ext_offset_.push_back(n_ext_);
      for (const auto& prm : x->parameters()) ext_params_.push_back(prm);
      n_ext_ += static_cast<int>(x->parameters().size());
    }
    nuis0_ = kNumLocationErrors + n_ext_;
    if (method == Method::LeastSquaresRigidSetup) {
      nuisance_ = 6;
    } else {
      for (const auto& o : obs) {
        if (!target_index_.count(o.point->target)) {
          const int idx = static_cast<int>(target_index_.size());
          target_index_[o.point->target] = idx;
        }
      }
      nuisance_ = static_cast<int>(target_index_.size());
      for (Face f : kAllFaces) normal_[static_cast<size_t>(f)] = faceNormal_w(f);
      reference_pose_ = plan.points.front().pose_name;
    }
  }

  int size() const { return nuis0_ + nuisance_; }
  int extensionCount() const { return n_ext_; }
  const std::vector<ExtensionParameter>& extensionParameters() const { return ext_params_; }
  bool knowsTarget(int target) const { return method_ == Method::LeastSquaresRigidSetup || target_index_.count(target) > 0; }

  Eigen::VectorXd extensionBlock(const Eigen::VectorXd& theta, size_t i) const {
    return theta.segment(kNumLocationErrors + ext_offset_[i], static_cast<long>(ext_[i]->parameters().size()));
  }

  LocationErrors errors(const Eigen::VectorXd& theta) const {
    LocationErrors e;
    e.kinematics = plan_.machine.kinematics;
    e.values = theta.head<kNumLocationErrors>();
    return e;
  }

  /// Face orientation from the reference pose (second-order effect only; see header).
  void updateNormals(const Eigen::VectorXd& theta) {
    if (method_ != Method::LeastSquaresPerPoint) return;
    const LocationErrors e = errors(theta);
    for (Face f : kAllFaces) {
      std::vector<Eigen::Vector3d> pts;
      for (const auto& o : obs_) {
        if (o.point->face != f || o.point->pose_name != reference_pose_) continue;
        pts.push_back(T_m_w(e, o.point->pose).inverse() * o.measured_m);
      }
      const Eigen::Vector3d n0 = faceNormal_w(f);
      const auto axes = faceAxes_w(f);
      std::vector<Eigen::Vector3d> used_axes;
      for (const auto& ax : axes) {
        double lo = 1e300, hi = -1e300;
        for (const auto& p : pts) { lo = std::min(lo, ax.dot(p)); hi = std::max(hi, ax.dot(p)); }
        if (!pts.empty() && hi - lo > 1.0) used_axes.push_back(ax);
      }
      if (pts.size() < used_axes.size() + 2 || used_axes.empty()) { normal_[static_cast<size_t>(f)] = n0; continue; }
      Eigen::MatrixXd M(pts.size(), used_axes.size() + 1);
      Eigen::VectorXd h(pts.size());
      for (size_t i = 0; i < pts.size(); ++i) {
        M(static_cast<long>(i), 0) = 1.0;
        for (size_t a = 0; a < used_axes.size(); ++a) M(static_cast<long>(i), static_cast<long>(a + 1)) = used_axes[a].dot(pts[i]);
        h[static_cast<long>(i)] = n0.dot(pts[i]);
      }
      const Eigen::VectorXd c = M.colPivHouseholderQr().solve(h);
      Eigen::Vector3d n = n0;
      for (size_t a = 0; a < used_axes.size(); ++a) n -= c[static_cast<long>(a + 1)] * used_axes[a];
      normal_[static_cast<size_t>(f)] = n.normalized();
    }
  }

  Plane plane_w(const Eigen::VectorXd& theta, const ProbePoint& p) const {
    if (method_ == Method::LeastSquaresRigidSetup) {
      ArtefactTruth a;
      a.setup.translation_mm = theta.segment<3>(nuis0_);
      a.setup.rotation_rad = theta.segment<3>(nuis0_ + 3);
      return a.face(*plan_.machine.artefact, p.face);
    }
    const Eigen::Vector3d& n = normal_[static_cast<size_t>(p.face)];
    const double s = theta[nuis0_ + target_index_.at(p.target)];
    return Plane{p.contact_w_mm + s * n, n};
  }

  /// Location errors in force at an observation (extensions such as drift change them).
  LocationErrors errorsAt(const Eigen::VectorXd& theta, const Observation& o) const {
    LocationErrors e = errors(theta);
    for (size_t i = 0; i < ext_.size(); ++i) e = ext_[i]->errorsAt(extensionBlock(theta, i), o.context(), e);
    return e;
  }

  /// The exact model of one trigger (mm along the approach from the nominal trigger).
  double predict(const Eigen::VectorXd& theta, const Observation& o) const {
    const ProbePoint& p = *o.point;
    const Plane w = plane_w(theta, p);
    const Eigen::Isometry3d T = T_m_w(errorsAt(theta, o), p.pose);
    const Plane pm{T * w.point, T.linear() * w.normal};
    double s = ballPlaneContact(p.trigger_m_mm, p.approach_m, r_, pm);
    bool positional = false;
    for (const auto& x : ext_) positional = positional || x->hasPositionError();
    if (positional) {
      for (int it = 0; it < 50; ++it) {
        const Eigen::Vector3d c = p.trigger_m_mm + s * p.approach_m;
        Eigen::Vector3d E = Eigen::Vector3d::Zero();
        for (size_t i = 0; i < ext_.size(); ++i)
          if (ext_[i]->hasPositionError()) E += ext_[i]->positionError(extensionBlock(theta, i), c);
        const double next = ballPlaneContact(p.trigger_m_mm + E, p.approach_m, r_, pm);
        const bool done = std::abs(next - s) < 1e-13;
        s = next;
        if (done) break;
      }
    }
    for (size_t i = 0; i < ext_.size(); ++i) s += ext_[i]->triggerOffset(extensionBlock(theta, i), o.context());
    return s;
  }

  /// Residuals (measured - model) and the Jacobian of the model, J_s_theta.
  void evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd* res, Eigen::MatrixXd* J) const {
    const long m = static_cast<long>(obs_.size());
    res->resize(m);
    J->setZero(m, size());
    for (long i = 0; i < m; ++i) {
      const Observation& o = obs_[static_cast<size_t>(i)];
      const ProbePoint& p = *o.point;
      const LocationErrors e = errorsAt(theta, o);
      const Plane w = plane_w(theta, p);
      const Eigen::Isometry3d T = T_m_w(e, p.pose);
      const Plane pm{T * w.point, T.linear() * w.normal};
      const double s = n_ext_ > 0 ? predict(theta, o) : ballPlaneContact(p.trigger_m_mm, p.approach_m, r_, pm);
      (*res)[i] = o.s_mm - s;
      const double nu = pm.normal.dot(p.approach_m);
      // J_s_e: the plane moves with the table: dx = J(x) de, dn = (J(x + n) - J(x)) de.
      const auto Jx = J_pm_e(e, p.pose, w.point);
      const auto Jxn = J_pm_e(e, p.pose, w.point + w.normal);
      for (int j = 0; j < kNumLocationErrors; ++j) {
        const Eigen::Vector3d dx = Jx.col(j);
        const Eigen::Vector3d dn = Jxn.col(j) - dx;
        (*J)(i, j) = (-dn.dot(p.trigger_m_mm - pm.point) + pm.normal.dot(dx)) / nu - s * dn.dot(p.approach_m) / nu;
      }
      // Extensions: central differences of the exact model (few parameters).
      for (int j = 0; j < n_ext_; ++j) {
        const double h = ext_params_[static_cast<size_t>(j)].fd_step;
        Eigen::VectorXd tp = theta, tm = theta;
        tp[kNumLocationErrors + j] += h;
        tm[kNumLocationErrors + j] -= h;
        (*J)(i, kNumLocationErrors + j) = (predict(tp, o) - predict(tm, o)) / (2 * h);
      }
      if (method_ == Method::LeastSquaresPerPoint) {
        (*J)(i, nuis0_ + target_index_.at(p.target)) = 1.0 / nu;
      } else {
        for (int j = 0; j < 6; ++j) {
          const double h = j < 3 ? 1e-6 : 1e-8;
          Eigen::VectorXd tp = theta, tm = theta;
          tp[nuis0_ + j] += h;
          tm[nuis0_ + j] -= h;
          (*J)(i, nuis0_ + j) = (predict(tp, o) - predict(tm, o)) / (2 * h);
        }
      }
    }
  }

 private:
  const ProbePlan& plan_;
  const std::vector<Observation>& obs_;
  Method method_;
  double r_;
  int nuisance_ = 0;
  std::map<int, int> target_index_;
  std::array<Eigen::Vector3d, 5> normal_;
  std::string reference_pose_;
  std::vector<ExtensionPtr> ext_;
  std::vector<int> ext_offset_;
  std::vector<ExtensionParameter> ext_params_;
  int n_ext_ = 0;
  int nuis0_ = kNumLocationErrors;
};

IdentificationResult leastSquares(const ProbePlan& plan, const std::vector<Observation>& all_obs,
                                  const IdentificationOptions& options, Eigen::VectorXd* theta_out = nullptr) {
  IdentificationResult out;
  out.method = options.method;
  out.estimate.kinematics = plan.machine.kinematics;
  std::vector<Observation> obs, held;
  for (const auto& o : all_obs) (o.held_out ? held : obs).push_back(o);
  if (obs.empty()) {
    out.summary.message = "every observation is held out";
    return out;
  }
  LsqModel model(plan, obs, options.method, options.extensions);
  const int n = model.size();
  const long m = static_cast<long>(obs.size());
  out.summary.observations = static_cast<int>(m);
  out.summary.parameters = n;
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd res;
  Eigen::MatrixXd J;
  Eigen::VectorXd scale;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd;
  // The column-scaled SVD of J at theta: its rank and condition, as the summary states them.
  const auto decompose = [&]() {
    model.updateNormals(theta);
    model.evaluate(theta, &res, &J);
    scale = J.colwise().norm().transpose();
    for (int j = 0; j < n; ++j) scale[j] = scale[j] > 0 ? 1.0 / scale[j] : 1.0;
    svd.compute(J * scale.asDiagonal(), Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto& sv = svd.singularValues();
    const double tol = options.rank_tolerance * sv[0];
    int rank = 0;
    for (long i = 0; i < sv.size(); ++i)
      if (sv[i] > tol) ++rank;
    out.summary.rank = rank;
    out.summary.condition = rank > 0 ? sv[0] / sv[rank - 1] : INFINITY;
    return rank;
  };
  if (const int rank = decompose(); rank < n || m < n) {
    // Name the location errors that take part in the null space.
    std::set<std::string> names;
    const auto& V = svd.matrixV();
    const auto& params = locationParameters(plan.machine.kinematics);
    for (long c = rank; c < V.cols(); ++c) {
      for (int j = 0; j < kNumLocationErrors; ++j)
        if (std::abs(V(j, c)) > 0.05) names.insert(std::string(params[j].name));
      for (int j = 0; j < model.extensionCount(); ++j)
        if (std::abs(V(kNumLocationErrors + j, c)) > 0.05) names.insert(model.extensionParameters()[static_cast<size_t>(j)].name);
    }
    out.unidentifiable.assign(names.begin(), names.end());
    out.summary.termination = Termination::RankDeficient;
    std::string list;
    for (const auto& s : out.unidentifiable) list += (list.empty() ? "" : ", ") + s;
    out.summary.message = names.empty()
                              ? fmt::format("the plan leaves {} nuisance combination(s) unidentifiable", n - rank)
                              : "the plan cannot identify " + list + " (they move no trigger independently)";
    return out;
  }
  // The shared engine (core/least_squares), r = predicted - measured (mm), the contact normals
  // updated at every evaluation. Converged when a step changes no predicted trigger by more than
  // step_tolerance (mm), the step's effect through the Jacobian it was taken with; the engine's
  // own tolerances are off.
  Eigen::MatrixXd J_step, J_now;  // the Jacobian at the x a step starts from, and at the latest x
  LeastSquaresOptions lo;
  lo.max_iterations = options.max_iterations;
  lo.rank_tolerance = options.rank_tolerance;
  lo.step_tolerance = std::numeric_limits<double>::min();
  lo.function_tolerance = 0.0;
  lo.converged = [&](const Eigen::VectorXd& before, const Eigen::VectorXd& after) {
    return (J_step * (after - before)).cwiseAbs().maxCoeff() < options.step_tolerance;
  };
  const LeastSquaresResult solved = solveLeastSquares(
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* Jr) {
        Eigen::VectorXd measured_minus_predicted;
        Eigen::MatrixXd Jx;
        model.updateNormals(x);
        model.evaluate(x, &measured_minus_predicted, &Jx);
        r = -measured_minus_predicted;
        if (Jr) {
          J_step = std::move(J_now);  // the previous evaluation's: the one the next step is judged by
          J_now = Jx;
          *Jr = std::move(Jx);
        }
      },
      theta, lo);
  theta = solved.x;
  out.summary.iterations = solved.summary.iterations;
  out.summary.termination = solved.summary.usable() ? Termination::Converged : Termination::MaxIterations;
  decompose();
  const double rss = res.squaredNorm();
  out.summary.cost = 0.5 * rss;
  out.summary.dof = static_cast<int>(m) - n;
  out.summary.residual_rms_um = mmToUm(std::sqrt(rss / static_cast<double>(m)));
  out.summary.sigma_um = out.summary.dof > 0 ? mmToUm(std::sqrt(rss / out.summary.dof)) : options.prior_sigma_um;
  const double sigma_mm = umToMm(out.summary.sigma_um);
  const Eigen::VectorXd inv_sv = svd.singularValues().cwiseInverse();
  const Eigen::MatrixXd Vs = scale.asDiagonal() * svd.matrixV();
  const Eigen::MatrixXd cov = sigma_mm * sigma_mm * Vs * inv_sv.cwiseAbs2().asDiagonal() * Vs.transpose();
  out.covariance = cov.topLeftCorner<kNumLocationErrors, kNumLocationErrors>();
  out.u = out.covariance.diagonal().cwiseSqrt();
  out.estimate = model.errors(theta);
  if (model.extensionCount() > 0) {
    out.extension_values = theta.segment(kNumLocationErrors, model.extensionCount());
    out.extension_u = cov.diagonal().segment(kNumLocationErrors, model.extensionCount()).cwiseSqrt();
    out.extension_correlation.resize(model.extensionCount(), kNumLocationErrors);
    for (int a = 0; a < model.extensionCount(); ++a)
      for (int b = 0; b < kNumLocationErrors; ++b)
        out.extension_correlation(a, b) =
            cov(kNumLocationErrors + a, b) / std::sqrt(cov(kNumLocationErrors + a, kNumLocationErrors + a) * cov(b, b));
  }
  for (long i = 0; i < m; ++i)
    out.residuals.push_back({obs[static_cast<size_t>(i)].run, obs[static_cast<size_t>(i)].point->id, mmToUm(res[i]),
                             obs[static_cast<size_t>(i)].t_h, false});
  double held_ss = 0.0;
  for (const auto& o : held) {
    if (!model.knowsTarget(o.point->target)) continue;  // no offset for a point never fitted
    const double r_um = mmToUm(o.s_mm - model.predict(theta, o));
    out.residuals.push_back({o.run, o.point->id, r_um, o.t_h, true});
    held_ss += r_um * r_um;
    ++out.holdout_points;
  }
  out.holdout_rms_um = out.holdout_points ? std::sqrt(held_ss / out.holdout_points) : 0.0;
  if (theta_out) *theta_out = theta;
  if (out.summary.termination == Termination::Converged)
    out.summary.message = fmt::format("converged in {} iterations", out.summary.iterations);
  else
    out.summary.message = fmt::format("stopped after {} iterations without meeting the step tolerance", out.summary.iterations);
  return out;
}

}  // namespace

Linearisation lineariseAtBaseline(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                  const IdentificationOptions& options, const std::vector<ExtensionPtr>& candidates) {
  Linearisation lin;
  IdentificationOptions base = options;
  base.extensions.clear();
  base.hold_out = nullptr;
  lin.baseline = identify(plan, runs, base);
  if (lin.baseline.summary.termination != Termination::Converged) return lin;
  std::string why;
  const auto obs = collect(plan, runs, base, &why);
  Eigen::VectorXd theta0;
  leastSquares(plan, obs, base, &theta0);  // deterministic: the same solution as lin.baseline
  LsqModel model(plan, obs, base.method, candidates);
  const int p0 = static_cast<int>(theta0.size());
  const int nuis = p0 - kNumLocationErrors;
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(model.size());
  theta.head<kNumLocationErrors>() = theta0.head<kNumLocationErrors>();
  theta.tail(nuis) = theta0.tail(nuis);
  model.updateNormals(theta);
  Eigen::VectorXd res;
  Eigen::MatrixXd J;
  model.evaluate(theta, &res, &J);
  lin.residual_um = mmToUm(1.0) * res;
  const auto& params = locationParameters(plan.machine.kinematics);
  lin.J0.resize(J.rows(), p0);
  for (int j = 0; j < kNumLocationErrors; ++j) {
    const bool angle = params[static_cast<size_t>(j)].kind == ParamKind::Angle;
    // um of trigger per report unit: mm -> um (x1000) per um (x1e-3), or per mdeg.
    const double per_report = angle ? mmToUm(1.0) * degToRad(1e-3) : 1.0;
    lin.J0.col(j) = J.col(j) * per_report;
    lin.J0_names.emplace_back(params[static_cast<size_t>(j)].name);
    lin.J0_units.emplace_back(reportUnit(params[static_cast<size_t>(j)].kind));
  }
  lin.J0.rightCols(nuis) = J.rightCols(nuis);  // mm per mm = um per um
  // The per-point offsets in LsqModel's order (first appearance of each target), named by target.
  std::vector<int> targets;
  for (const auto& o : obs)
    if (std::find(targets.begin(), targets.end(), o.point->target) == targets.end()) targets.push_back(o.point->target);
  for (int k = 0; k < nuis; ++k) {
    lin.J0_names.push_back(k < static_cast<int>(targets.size()) ? fmt::format("offset_target{}", targets[static_cast<size_t>(k)])
                                                                : fmt::format("nuisance_{}", k + 1));
    lin.J0_units.emplace_back("um");
  }
  int col = kNumLocationErrors;
  for (const auto& x : candidates) {
    const auto ps = x->parameters();
    Eigen::MatrixXd Jx(J.rows(), static_cast<Eigen::Index>(ps.size()));
    for (size_t k = 0; k < ps.size(); ++k)
      Jx.col(static_cast<Eigen::Index>(k)) = J.col(col + static_cast<int>(k)) * mmToUm(1.0) / ps[k].to_report;
    col += static_cast<int>(ps.size());
    lin.extension_J.push_back(Jx);
  }
  for (const auto& o : obs) lin.observations.push_back({o.run, o.point, o.t_h});
  lin.ok = true;
  return lin;
}

IdentificationResult identify(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                              const IdentificationOptions& options) {
  IdentificationResult bad;
  bad.method = options.method;
  bad.estimate.kinematics = plan.machine.kinematics;
  std::string why;
  if (!options.validate(&why)) {
    bad.summary.message = "invalid options: " + why;
    return bad;
  }
  if (runs.empty()) {
    bad.summary.message = "no results to identify from";
    return bad;
  }
  if (!plan.machine.artefact) {
    bad.summary.message = "the plan has no artefact";
    return bad;
  }
  if (options.method == Method::ClosedForm) {
    // The closed form is one cycle's own estimator (its equations hold for its plan alone): the
    // cycle runs it and hands everything else to this engine.
    bad.summary.message = "closed_form is not a least-squares method: the cycle whose plan it solves runs it";
    return bad;
  }
  const auto obs = collect(plan, runs, options, &why);
  if (obs.empty()) {
    bad.summary.message = why.empty() ? "no observations" : why;
    return bad;
  }
  return leastSquares(plan, obs, options);
}

}  // namespace rotacal
