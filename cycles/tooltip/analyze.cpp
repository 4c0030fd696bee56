#include "cycles/tooltip/analyze.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <functional>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "core/least_squares.hpp"
#include "core/require_valid.hpp"
#include "core/units.hpp"
#include "core/report_envelope.hpp"

namespace rotacal {
namespace {

Eigen::Matrix3d skewX() {
  Eigen::Matrix3d g;
  g << 0, 0, 0, 0, 0, -1, 0, 1, 0;
  return g;
}
Eigen::Matrix3d skewY() {
  Eigen::Matrix3d g;
  g << 0, 0, 1, 0, 0, 0, -1, 0, 0;
  return g;
}

/// The problem: observations and the parameter layout x = [e_0 .. e_{J-1} (rad), dR (mm)].
struct Problem {
  TooltipOptions o;
  std::vector<double> angles_deg;  // distinct, ascending
  struct Obs {
    double theta = 0, theta_ref = 0, other = 0;  // rad
    int j = 0, j_ref = 0;                       // angle indices
    double t_um = 0, z_um = 0;
    int reading = 0;                            // index in the concatenated runs
    int run = 0, k = 0;                         // run, and plan point in it
    int k_ref = 0;                              // the plan point of its sweep's zero reading
  };
  std::vector<Obs> obs;
  int readings = 0;

  int J() const { return static_cast<int>(angles_deg.size()); }
  int ti() const { return o.axis == 'A' ? 1 : 0; }

  Eigen::Vector3d F(double phi, double other, double r) const {
    return o.axis == 'A' ? tipOffset_m(phi, other, r) : tipOffset_m(other, phi, r);
  }
  Eigen::Vector3d dFdphi(double phi, double other, double r) const {
    if (o.axis == 'A') return skewX() * tipOffset_m(phi, other, r);
    // F = Rx(other) Ry(phi) v: d/dphi = Rx(other) Gy Ry(phi) v.
    return rxTimes(other, skewY() * tipOffset_m(0.0, phi, r));
  }
  static Eigen::Vector3d rxTimes(double a, const Eigen::Vector3d& w) {
    return {w.x(), std::cos(a) * w.y() - std::sin(a) * w.z(), std::sin(a) * w.y() + std::cos(a) * w.z()};
  }

  /// Model (um) of one observation: transverse and Z.
  Eigen::Vector2d model(const Obs& b, const Eigen::VectorXd& x) const {
    const double r = o.radius_mm, rt = r + x[J()];
    const Eigen::Vector3d d = F(b.theta + x[b.j], b.other, rt) - F(b.theta, b.other, r) -
                              F(b.theta_ref + x[b.j_ref], b.other, rt) + F(b.theta_ref, b.other, r);
    return mmToUm(1.0) * Eigen::Vector2d(d[ti()], d.z());
  }
  /// d model / d x (um per rad, um per mm), 2 x (J + 1).
  Eigen::Matrix<double, 2, Eigen::Dynamic> jacobian(const Obs& b, const Eigen::VectorXd& x) const {
    Eigen::Matrix<double, 2, Eigen::Dynamic> jac = Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, J() + 1);
    const double rt = o.radius_mm + x[J()];
    auto put = [&](int col, const Eigen::Vector3d& v, double s) {
      jac(0, col) += s * mmToUm(1.0) * v[ti()];
      jac(1, col) += s * mmToUm(1.0) * v.z();
    };
    put(b.j, dFdphi(b.theta + x[b.j], b.other, rt), 1.0);
    put(b.j_ref, dFdphi(b.theta_ref + x[b.j_ref], b.other, rt), -1.0);
    put(J(), F(b.theta + x[b.j], b.other, rt) / rt, 1.0);
    put(J(), F(b.theta_ref + x[b.j_ref], b.other, rt) / rt, -1.0);
    return jac;
  }
};

Problem makeProblem(const ProbePlan& plan, const std::vector<TooltipRun>& runs) {
  Problem p;
  p.o = tooltipOptionsFrom(plan.options, plan.machine);
  if (runs.empty()) throw std::invalid_argument("tooltip analysis: no results");
  for (const auto& pt : plan.points) {
    const double a = p.o.axis == 'A' ? pt.pose.A : pt.pose.B;
    if (std::none_of(p.angles_deg.begin(), p.angles_deg.end(), [&](double v) { return std::abs(v - a) < 1e-9; }))
      p.angles_deg.push_back(a);
  }
  std::sort(p.angles_deg.begin(), p.angles_deg.end());
  auto index = [&](double a) {
    for (int j = 0; j < p.J(); ++j)
      if (std::abs(p.angles_deg[j] - a) < 1e-9) return j;
    throw std::logic_error("tooltip: angle not in the plan");
  };
  const std::vector<int> refs = tooltipReferences(plan);
  int reading = 0;
  for (const auto& run : runs) {
    if (run.size() != plan.points.size()) throw std::invalid_argument("tooltip analysis: a run does not match the plan");
    for (size_t k = 0; k < run.size(); ++k, ++reading) {
      if (refs[k] == static_cast<int>(k)) continue;  // the zero reading: 0 by construction
      const Pose& pose = plan.points[k].pose;
      const Pose& ref = plan.points[refs[k]].pose;
      Problem::Obs b;
      const double th = p.o.axis == 'A' ? pose.A : pose.B;
      const double th_ref = p.o.axis == 'A' ? ref.A : ref.B;
      b.theta = degToRad(th);
      b.theta_ref = degToRad(th_ref);
      b.other = degToRad(p.o.axis == 'A' ? pose.B : pose.A);
      b.j = index(th);
      b.j_ref = index(th_ref);
      b.t_um = run[k].t_um;
      b.z_um = run[k].z_um;
      b.reading = reading;
      b.run = static_cast<int>(&run - runs.data());
      b.k = static_cast<int>(k);
      b.k_ref = refs[k];
      p.obs.push_back(b);
    }
  }
  p.readings = reading;
  return p;
}

struct GnResult {
  Eigen::VectorXd x;
  Eigen::MatrixXd cov_unit;  // (J^T J)^-1 plus the laser zeros' A Z A^T over the active parameters, in full layout (0 elsewhere)
  double rss = 0;
  int iterations = 0;
  bool converged = false;
  double last_step = 0;
  int used = 0;  // observations (components)
  int active = 0;
  // At the solution, over the values read (finite): the residual, the Jacobian of the active
  // parameters, and each value's (run, 2 k + c).
  Eigen::VectorXd kept_residual;
  Eigen::MatrixXd kept_J;
  std::vector<std::pair<int, int>> kept;
};

/// The least squares over the active parameters, on the observations `use` accepts, by the
/// shared engine (core/least_squares): r = reading - model in um, unweighted (the noise is one
/// per reading; its size scales the covariance afterwards).
GnResult gaussNewton(const Problem& p, const Eigen::VectorXd& x0, const std::vector<bool>& active,
                     const std::function<bool(const Problem::Obs&)>& use, const TooltipFitOptions& opt) {
  std::vector<int> cols;
  for (int i = 0; i < static_cast<int>(active.size()); ++i)
    if (active[i]) cols.push_back(i);
  std::vector<const Problem::Obs*> obs;
  for (const auto& b : p.obs)
    if (use(b)) obs.push_back(&b);
  const int m = 2 * static_cast<int>(obs.size()), n = static_cast<int>(cols.size());
  GnResult g;
  // A reading of the transverse direction alone has no Z row, and a value the screen of gross
  // readings left out is NaN: its row stays zero and uncounted.
  g.used = 0;
  for (const auto* b : obs) g.used += (std::isfinite(b->t_um) ? 1 : 0) + (std::isfinite(b->z_um) ? 1 : 0);
  g.active = n;
  const auto full = [&](const Eigen::VectorXd& xa) {
    Eigen::VectorXd x = x0;
    for (int c = 0; c < n; ++c) x[cols[static_cast<size_t>(c)]] = xa[c];
    return x;
  };
  // r = reading - model; J_r_x = -d model / dx over the active columns.
  const ResidualFunction residuals = [&](const Eigen::VectorXd& xa, Eigen::VectorXd& res, Eigen::MatrixXd* jac) {
    const Eigen::VectorXd x = full(xa);
    res.resize(m);
    if (jac) jac->resize(m, n);
    for (size_t i = 0; i < obs.size(); ++i) {
      const Eigen::Vector2d mdl = p.model(*obs[i], x);
      const bool t = std::isfinite(obs[i]->t_um), z = std::isfinite(obs[i]->z_um);
      res(2 * i) = t ? obs[i]->t_um - mdl[0] : 0.0;
      res(2 * i + 1) = z ? obs[i]->z_um - mdl[1] : 0.0;
      if (!jac) continue;
      const auto d = p.jacobian(*obs[i], x);
      for (int c = 0; c < n; ++c) {
        (*jac)(2 * i, c) = t ? -d(0, cols[static_cast<size_t>(c)]) : 0.0;
        (*jac)(2 * i + 1, c) = z ? -d(1, cols[static_cast<size_t>(c)]) : 0.0;
      }
    }
  };
  Eigen::VectorXd xa0(n);
  for (int c = 0; c < n; ++c) xa0[c] = x0[cols[static_cast<size_t>(c)]];
  {
    // A parameter no reading sees is the caller's mistake, not a direction to hold: say so.
    Eigen::VectorXd r;
    Eigen::MatrixXd J;
    residuals(xa0, r, &J);
    for (int c = 0; c < n; ++c)
      if (!(J.col(c).norm() > 0)) throw std::invalid_argument("tooltip fit: a parameter has no data (singular)");
  }
  LeastSquaresOptions lo;
  lo.max_iterations = opt.max_iterations;
  lo.step_tolerance = opt.step_tol;
  const LeastSquaresResult fit = solveLeastSquares(residuals, xa0, lo);
  if (fit.summary.termination == Termination::InvalidInput)
    throw std::invalid_argument("tooltip fit: " + fit.summary.message);
  if (fit.summary.rank < n) throw std::invalid_argument("tooltip fit: the parameters are not identifiable from these readings");
  g.converged = fit.summary.usable();
  g.iterations = fit.summary.iterations;
  Eigen::VectorXd res;
  Eigen::MatrixXd jac;
  residuals(fit.x, res, &jac);
  // What one more Gauss-Newton step would move (mm, rad): the linearisation's check at the end.
  g.last_step = n > 0 ? (jac.completeOrthogonalDecomposition().solve(-res)).cwiseAbs().maxCoeff() : 0.0;
  g.x = full(fit.x);
  g.rss = res.squaredNorm();
  std::vector<int> rows;
  for (size_t i = 0; i < obs.size(); ++i)
    for (int c = 0; c < 2; ++c)
      if (std::isfinite(c == 0 ? obs[i]->t_um : obs[i]->z_um)) {
        rows.push_back(2 * static_cast<int>(i) + c);
        g.kept.emplace_back(obs[i]->run, 2 * obs[i]->k + c);
      }
  g.kept_residual = res(rows);
  g.kept_J = -jac(rows, Eigen::all);  // d model / dx, as the judge and the budget read it
  // Per um^2 of reading variance: each reading's own through the fit, (J^T J)^-1, and its
  // sweep's laser zero's, which every value of that sweep and direction in its run is read less
  // (A Z A^T, A = (J^T J)^-1 J^T the fit's map, Z = 1 between the values of one zero).
  Eigen::MatrixXd cov(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) cov(a, b) = fit.covariance(a, b);
  const Eigen::MatrixXd A = cov * jac.transpose();  // n x m: zero columns where a value is not read
  std::map<std::tuple<int, int, int>, Eigen::VectorXd> per_zero;
  for (size_t i = 0; i < obs.size(); ++i)
    for (int c = 0; c < 2; ++c) {
      if (!std::isfinite(c == 0 ? obs[i]->t_um : obs[i]->z_um)) continue;
      auto [it, fresh] = per_zero.try_emplace({obs[i]->run, obs[i]->k_ref, c}, Eigen::VectorXd::Zero(n));
      it->second -= A.col(2 * static_cast<Eigen::Index>(i) + c);  // d x / d(reading) = -(J_r^T J_r)^-1 J_r^T
    }
  Eigen::MatrixXd with_zero = cov;
  for (const auto& [key, a_z] : per_zero) with_zero += a_z * a_z.transpose();
  g.cov_unit = Eigen::MatrixXd::Zero(x0.size(), x0.size());
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) g.cov_unit(cols[static_cast<size_t>(a)], cols[static_cast<size_t>(b)]) = with_zero(a, b);
  return g;
}

// No Z reading at all: the transverse reading alone.
bool noZ(const Problem& p) {
  for (const auto& b : p.obs)
    if (std::isfinite(b.z_um)) return false;
  return true;
}

std::vector<bool> activeFor(const Problem& p, bool pivot, int excluded) {
  std::vector<bool> active(p.J() + 1, false);
  // An angle whose every reading the screen of gross readings left out (NaN) has no data.
  for (const auto& b : p.obs)
    if (b.j != excluded && (std::isfinite(b.t_um) || std::isfinite(b.z_um))) active[b.j] = active[b.j_ref] = true;
  // From the transverse reading alone, e at the zero pose and e_j = e_0 cos(0) / cos(theta_j)
  // leave every reading unchanged: the zero pose is the reference, its error 0 by definition
  // (the laser is zeroed there, 004).
  if (noZ(p)) {
    for (const auto& b : p.obs) active[b.j_ref] = false;
    // Where the tip moves along the beam (A = +-90 deg: d(dy)/de = R cos A = 0) the transverse
    // reading does not see the angle to first order: not identifiable there, never a number
    // from a near-singular column (it came out as 1e17 mdeg).
    std::vector<double> sens(static_cast<size_t>(p.J()), 0.0);
    double largest = 0.0;
    const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(p.J() + 1);
    for (const auto& b : p.obs) {
      const double d = std::abs(p.jacobian(b, x0)(0, b.j));
      sens[static_cast<size_t>(b.j)] = std::max(sens[static_cast<size_t>(b.j)], d);
      largest = std::max(largest, d);
    }
    for (int j = 0; j < p.J(); ++j)
      if (sens[static_cast<size_t>(j)] <= 1e-9 * largest) active[static_cast<size_t>(j)] = false;
  }
  active[p.J()] = pivot;
  return active;
}

double r6(double v) { return std::isfinite(v) ? std::round(v * 1e6) / 1e6 : v; }
Json num(double v) { return std::isfinite(v) ? Json(r6(v)) : Json(nullptr); }

}  // namespace

TooltipModelEval evaluateTooltipModel(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const Eigen::VectorXd& x) {
  const Problem p = makeProblem(plan, runs);
  if (x.size() != p.J() + 1) throw std::invalid_argument("tooltip model: x must hold one angle per distinct angle and dR");
  TooltipModelEval e;
  e.angles = p.J();
  const int m = 2 * static_cast<int>(p.obs.size());
  e.model_um.resize(m);
  e.J_model_x.resize(m, p.J() + 1);
  for (size_t i = 0; i < p.obs.size(); ++i) {
    e.model_um.segment<2>(2 * static_cast<int>(i)) = p.model(p.obs[i], x);
    e.J_model_x.middleRows(2 * static_cast<int>(i), 2) = p.jacobian(p.obs[i], x);
  }
  return e;
}

bool TooltipFitOptions::validate(std::string* why) const {
  if (max_iterations < 1) return invalidBecause(why, "max_iterations must be at least 1");
  if (!(step_tol > 0)) return invalidBecause(why, "step_tol must be positive");
  if (!(sigma_floor_um >= 0)) return invalidBecause(why, "sigma_floor_um must not be negative");
  return true;
}

TooltipFit fitTooltip(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipFitOptions& options) {
  requireValid(options, "tooltip fit options");
  const Problem p = makeProblem(plan, runs);
  const std::vector<bool> active = activeFor(p, options.fit_pivot_length, -1);
  const GnResult g = gaussNewton(p, Eigen::VectorXd::Zero(p.J() + 1), active, [](const Problem::Obs&) { return true; },
                                 options);
  TooltipFit f;
  f.model = options.fit_pivot_length ? "angular+pivot" : "angular";
  f.converged = g.converged;
  f.iterations = g.iterations;
  f.observations = g.used;
  f.dof = g.used - g.active;
  f.rss_um2 = g.rss;
  f.residual_rms_um = g.used > 0 ? std::sqrt(g.rss / g.used) : 0.0;
  const double s_data = f.dof > 0 ? std::sqrt(g.rss / f.dof) : 0.0;
  f.sigma_um = std::max(s_data, options.sigma_floor_um);
  f.last_step_um = g.last_step;
  f.angles_deg = p.angles_deg;
  const bool reference_fixed = noZ(p);
  for (int j = 0; j < p.J(); ++j) {
    bool is_ref = false;
    for (const auto& b : p.obs) is_ref = is_ref || (reference_fixed && b.j_ref == j);
    f.e_mdeg.push_back(active[j] ? radToMdeg(g.x[j]) : is_ref ? 0.0 : std::numeric_limits<double>::quiet_NaN());
    f.u_e_mdeg.push_back(active[j]  ? radToMdeg(f.sigma_um * std::sqrt(g.cov_unit(j, j)))
                         : is_ref ? 0.0
                                  : std::numeric_limits<double>::quiet_NaN());
  }
  if (options.fit_pivot_length) {
    f.dR_um = mmToUm(g.x[p.J()]);
    f.u_dR_um = mmToUm(f.sigma_um * std::sqrt(g.cov_unit(p.J(), p.J())));
  }
  f.kept_values = g.kept;
  f.kept_residual_um = g.kept_residual;
  f.kept_J = g.kept_J;
  f.res_t_um.assign(p.readings, 0.0);
  f.res_z_um.assign(p.readings, 0.0);
  f.model_t_um.assign(p.readings, 0.0);
  f.model_z_um.assign(p.readings, 0.0);
  for (const auto& b : p.obs) {
    const Eigen::Vector2d mdl = p.model(b, g.x);
    f.model_t_um[b.reading] = mdl[0];
    f.model_z_um[b.reading] = mdl[1];
    f.res_t_um[b.reading] = b.t_um - mdl[0];
    f.res_z_um[b.reading] = b.z_um - mdl[1];
  }
  return f;
}

double tooltipHoldoutRms(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipFitOptions& options) {
  const Problem p = makeProblem(plan, runs);
  double ss = 0;
  int n = 0;
  for (int j = 0; j < p.J(); ++j) {
    if (std::abs(p.angles_deg[j]) < 1e-9) continue;  // the zero reading is in every observation
    const std::vector<bool> active = activeFor(p, options.fit_pivot_length, j);
    const GnResult train = gaussNewton(p, Eigen::VectorXd::Zero(p.J() + 1), active,
                                       [j](const Problem::Obs& b) { return b.j != j; }, options);
    std::vector<bool> only(p.J() + 1, false);
    only[j] = true;
    const GnResult test =
        gaussNewton(p, train.x, only, [j](const Problem::Obs& b) { return b.j == j; }, options);
    ss += test.rss;
    n += test.used;
  }
  return n > 0 ? std::sqrt(ss / n) : 0.0;
}

std::vector<double> angularError004Mdeg(const ProbePlan& plan, const TooltipRun& run) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  std::vector<double> out;
  for (const auto& r : run) {
    const double c = std::cos(degToRad(r.angle_deg));
    // 004: dA = -dYp / (R cos A), dYp = -dy. cos 90 deg in double is 6e-17, not 0: treat
    // |cos| < 1e-12 as the division by zero it is.
    out.push_back(std::abs(c) < 1e-12 ? std::numeric_limits<double>::quiet_NaN()
                                      : radToMdeg(umToMm(r.t_um) / (o.radius_mm * c)));
  }
  return out;
}

bool transverseOnly(const std::vector<TooltipRun>& runs) {
  for (const auto& run : runs)
    for (const auto& r : run)
      if (std::isfinite(r.z_um)) return false;
  return true;
}

TooltipAnalysis analyzeTooltip(const ProbePlan& plan, const std::vector<TooltipRun>& runs) {
  TooltipAnalysis a;
  TooltipFitOptions o;
  // One reading per angle of one direction: each angle's angular error absorbs the pivot-length
  // term (dy = dR sin A + R e(A) cos A, e free per angle): dR is not identifiable, and the angular
  // errors are 004's model (dR = 0), with a pivot-length error read as e = dR tan A / R.
  a.transverse_only = transverseOnly(runs);
  o.fit_pivot_length = !a.transverse_only;
  a.joint = fitTooltip(plan, runs, o);
  o.fit_pivot_length = false;
  a.angular = fitTooltip(plan, runs, o);
  a.da004_mdeg = angularError004Mdeg(plan, runs.front());
  return a;
}

Json tooltipReportJson(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipAnalysis& a) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const std::string t = o.axis == 'A' ? "dy" : "dx";
  Json j = documentEnvelope("rotacal-report/1", plan, a.result_files);
  j["axis"] = std::string(1, o.axis);
  j["radius_mm"] = o.radius_mm;
  j["model"] = a.joint.model;
  if (a.transverse_only) {
    j["location_errors"] = Json::object();
    j["not_identified"] = {{"dR", "the transverse reading alone (" + t + " without dz): each angle's angular error absorbs "
                                  "the pivot-length term dR sin A, so dR is not identifiable and the angular errors "
                                  "assume dR = 0 (a pivot-length error dR reads as e = dR tan A / R); read dz too, or "
                                  "sweep with two tool lengths"}};
  } else {
    j["location_errors"] = {{"dR", {{"value", r6(a.joint.dR_um)}, {"unit", "um"}, {"u", r6(a.joint.u_dR_um)},
                                    {"iso", "pivot length (tool-tip distance) error"}}}};
  }
  Json ang = Json::array();
  for (size_t k = 0; k < a.joint.angles_deg.size(); ++k)
    ang.push_back({{"angle_deg", a.joint.angles_deg[k]},
                   {"value", num(a.joint.e_mdeg[k])},
                   {"u", num(a.joint.u_e_mdeg[k])},
                   {"unit", "mdeg"},
                   {"value_004_model", num(a.angular.e_mdeg[k])}});
  j["angular_error"] = ang;
  j["residual_rms_um"] = r6(a.joint.residual_rms_um);
  j["points_used"] = a.transverse_only ? a.joint.observations : a.joint.observations / 2;
  j["summary"] = {{"converged", a.joint.converged},   {"iterations", a.joint.iterations},
                  {"observations", a.joint.observations}, {"dof", a.joint.dof},
                  {"sigma_um", r6(a.joint.sigma_um)},   {"last_step", a.joint.last_step_um}};
  j["model_004"] = {{"model", "angular (004: dR = 0)"},
                    {"residual_rms_um", r6(a.angular.residual_rms_um)},
                    {"dof", a.angular.dof}};
  // Figures (shared schema, /work/briefs/figures.md).
  const TooltipRun& run = runs.front();
  std::vector<double> x, dt, dz, mt, mz, x004, y004;
  for (size_t k = 0; k < run.size(); ++k) {
    x.push_back(run[k].angle_deg);
    dt.push_back(r6(run[k].t_um));
    dz.push_back(r6(run[k].z_um));
    mt.push_back(r6(run[k].t_um - a.joint.res_t_um[k]));
    mz.push_back(r6(run[k].z_um - a.joint.res_z_um[k]));
    if (std::isfinite(a.da004_mdeg[k])) {
      x004.push_back(run[k].angle_deg);
      y004.push_back(r6(a.da004_mdeg[k]));
    }
  }
  Json figs = Json::array();
  figs.push_back({{"id", "tooltip_deviation"},
                  {"title", "Tool-tip deviation vs angle (004 Fig. 3), first results file"},
                  {"x", {{"label", std::string(1, o.axis)}, {"unit", "deg"}}},
                  {"y", {{"label", "deviation"}, {"unit", "um"}}},
                  {"series", Json::array({{{"name", t + " measured"}, {"style", "points"}, {"x", x}, {"y", dt}},
                                          {{"name", "dz measured"}, {"style", "points"}, {"x", x}, {"y", dz}},
                                          {{"name", t + " model (angular+pivot)"}, {"style", "line"}, {"x", x}, {"y", mt}},
                                          {{"name", "dz model (angular+pivot)"}, {"style", "line"}, {"x", x}, {"y", mz}}})},
                  {"note", "dz carries the pivot-length error that 004's formula never looks at"}});
  std::vector<double> ea, ee, eu, e4;
  for (size_t k = 0; k < a.joint.angles_deg.size(); ++k) {
    ea.push_back(a.joint.angles_deg[k]);
    ee.push_back(r6(a.joint.e_mdeg[k]));
    eu.push_back(r6(a.joint.u_e_mdeg[k]));
    e4.push_back(r6(a.angular.e_mdeg[k]));
  }
  figs.push_back({{"id", "tooltip_angular_error"},
                  {"title", "Angular positioning error vs angle (004 Fig. 4)"},
                  {"x", {{"label", std::string(1, o.axis)}, {"unit", "deg"}}},
                  {"y", {{"label", "angular error"}, {"unit", "mdeg"}}},
                  {"series", Json::array({{{"name", "004 dA = dy / (R cos A)"}, {"style", "points"}, {"x", x004}, {"y", y004}},
                                          {{"name", "fit: angular + pivot length"}, {"style", "line"}, {"x", ea}, {"y", ee}, {"u", eu}},
                                          {{"name", "fit: angular only (004 model)"}, {"style", "line"}, {"x", ea}, {"y", e4}}})},
                  {"note", fmt::format("004's formula has no value at 90 deg and reads dR = {:.1f} um as dR tan A / R",
                                       a.joint.dR_um)}});
  j["figures"] = figs;
  return j;
}

std::string tooltipReportText(const ProbePlan& plan, const TooltipAnalysis& a, const UncertaintyBudget* budget) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const auto uOf = [&](const std::string& name, double fit) { return budget ? budget->uCOr(name, fit) : fit; };
  const char* u_name = budget ? "u_c" : "u (the fit's)";
  std::string s = a.transverse_only
                      ? fmt::format("tooltip ({} axis, R = {:.3f} mm): the transverse reading alone: the pivot-length "
                                    "error dR is not identifiable (each angle's angular error absorbs dR sin A); the "
                                    "angular errors below assume dR = 0\n",
                                    o.axis, o.radius_mm)
                      : fmt::format("tooltip ({} axis, R = {:.3f} mm): pivot-length error dR = {:.2f} um ({} {:.2f} um, "
                                    "k = 1)\n",
                                    o.axis, o.radius_mm, a.joint.dR_um, u_name, uOf("dR", a.joint.u_dR_um));
  s += fmt::format("residual rms {:.3f} um (angular+pivot) vs {:.3f} um (004's angular model)\n", a.joint.residual_rms_um,
                   a.angular.residual_rms_um);
  s += fmt::format("angle_deg  e_mdeg  {}  e_004model_mdeg\n", budget ? "uc_mdeg" : "u_mdeg (fit)");
  for (size_t k = 0; k < a.joint.angles_deg.size(); ++k)
    s += fmt::format("{:9.3f} {:7.3f} {:7.3f} {:9.3f}\n", a.joint.angles_deg[k], a.joint.e_mdeg[k],
                     uOf(fmt::format("e_{}{:g}", o.axis, a.joint.angles_deg[k]), a.joint.u_e_mdeg[k]), a.angular.e_mdeg[k]);
  return s;
}

}  // namespace rotacal
