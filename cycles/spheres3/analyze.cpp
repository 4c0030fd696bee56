#include "cycles/spheres3/analyze.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/transforms.hpp"
#include "core/report_envelope.hpp"
#include "core/least_squares.hpp"
#include "core/units.hpp"
#include "cycles/spheres3/diagnose.hpp"
#include "core/require_valid.hpp"

namespace rotacal {

// ---- Stage 2 model ------------------------------------------------------------------------

const std::array<const char*, kNumComponentErrors>& componentNames() {
  static const std::array<const char*, kNumComponentErrors> n = {"EXC", "EYC", "EZC", "EAC", "EBC", "ECC"};
  return n;
}
const std::array<const char*, 4>& spheres3LocationNames() {
  static const std::array<const char*, 4> n = {"Oxc", "Oyc", "Sxc", "Syc"};
  return n;
}
const std::array<const char*, 4>& spheres3LocationIso() {
  static const std::array<const char*, 4> n = {"X0C", "Y0C", "A0C", "B0C"};
  return n;
}

namespace {
bool isAngle(int component) { return component >= 3; }
double toReport(int component, double v) { return isAngle(component) ? radToMdeg(v) : mmToUm(v); }
const char* reportUnitOf(int component) { return isAngle(component) ? "mdeg" : "um"; }
}  // namespace

std::string ComponentTerm::name() const {
  switch (kind) {
    case Kind::Cos: return fmt::format("{}_cos{}C", componentNames()[component], k);
    case Kind::Sin: return fmt::format("{}_sin{}C", componentNames()[component], k);
    case Kind::CounterCos:
      return fmt::format("{}+{}_counter{}_cos", componentNames()[component], componentNames()[component + 1], k);
    case Kind::CounterSin:
      return fmt::format("{}+{}_counter{}_sin", componentNames()[component], componentNames()[component + 1], k);
  }
  return "";
}

ComponentVector ComponentTerm::value(double c) const {
  ComponentVector v = ComponentVector::Zero();
  switch (kind) {
    case Kind::Cos: v[component] = std::cos(k * c); break;
    case Kind::Sin: v[component] = std::sin(k * c); break;
    // The table turns at -C (p_m = Dc(-C) p_w): a vector fixed on the table is
    // (g cos C, -g sin C); its counterpart turning at +C is what the spheres cannot absorb.
    case Kind::CounterCos:
      v[component] = std::cos(k * c);
      v[component + 1] = std::sin(k * c);
      break;
    case Kind::CounterSin:
      v[component] = -std::sin(k * c);
      v[component + 1] = std::cos(k * c);
      break;
  }
  return v;
}

std::vector<ComponentTerm> componentTerms(ComponentModel model, int n) {
  using K = ComponentTerm::Kind;
  std::vector<ComponentTerm> t;
  if (model == ComponentModel::None) return t;
  if (model == ComponentModel::SecondOrderRadial) {
    for (int comp : {0, 1})
      for (K kind : {K::Cos, K::Sin}) t.push_back({kind, comp, 2});
    return t;
  }
  const bool even = n % 2 == 0;
  const int kmax = even ? n / 2 - 1 : (n - 1) / 2;  // full cos + sin pairs
  for (int pair : {0, 3}) {
    t.push_back({K::CounterCos, pair, 1});
    t.push_back({K::CounterSin, pair, 1});
    for (int comp : {pair, pair + 1}) {
      for (int k = 2; k <= kmax; ++k) {
        t.push_back({K::Cos, comp, k});
        t.push_back({K::Sin, comp, k});
      }
      if (even && n / 2 >= 2) t.push_back({K::Cos, comp, n / 2});
    }
  }
  for (int comp : {2, 5}) {
    for (int k = 1; k <= kmax; ++k) {
      t.push_back({K::Cos, comp, k});
      t.push_back({K::Sin, comp, k});
    }
    if (even) t.push_back({K::Cos, comp, n / 2});
  }
  return t;
}

bool Spheres3Options::validate(std::string* why) const {
  auto fail = [&](const char* w) {
    if (why) *why = w;
    return false;
  };
  if (!(prior_sigma_um > 0)) return fail("prior_sigma_um must be positive");
  if (!(radius_tolerance_um > 0)) return fail("radius_tolerance_um must be positive");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (!(step_tolerance_mm > 0)) return fail("step_tolerance_mm must be positive");
  return true;
}

Eigen::Isometry3d spheres3Table_m_w(const Eigen::Vector4d& L, const ComponentVector& e, double c) {
  return Dx(L[0]) * Dy(L[1]) * Da(L[2]) * Db(L[3]) * Dx(e[0]) * Dy(e[1]) * Dz(e[2]) * Da(e[3]) * Db(e[4]) * Dc(e[5]) *
         Dc(-c);
}

ComponentVector Spheres3Result::componentAt(double c_deg_value) const {
  ComponentVector v = ComponentVector::Zero();
  for (size_t t = 0; t < terms.size(); ++t) v += h[static_cast<Eigen::Index>(t)] * terms[t].value(degToRad(c_deg_value));
  return v;
}

namespace {

// Parameter vector: [Oxc Oyc Sxc Syc | s_1 s_2 s_3 (mm, table frame) | h].
struct Model {
  std::vector<ComponentTerm> terms;
  int size() const { return 13 + static_cast<int>(terms.size()); }
  Eigen::Vector4d location(const Eigen::VectorXd& th) const { return th.head<4>(); }
  Eigen::Vector3d sphere(const Eigen::VectorXd& th, int i) const { return th.segment<3>(4 + 3 * i); }
  ComponentVector component(const Eigen::VectorXd& th, double c) const {
    ComponentVector v = ComponentVector::Zero();
    for (size_t t = 0; t < terms.size(); ++t) v += th[13 + static_cast<Eigen::Index>(t)] * terms[t].value(c);
    return v;
  }
  Eigen::Vector3d predict(const Eigen::VectorXd& th, int i, double c) const {
    return spheres3Table_m_w(location(th), component(th, c), c) * sphere(th, i);
  }
  // Typical size of each parameter (column scaling, finite-difference step): 1 um, 10 urad.
  double scale(int p) const {
    if (p < 2) return 1e-3;
    if (p < 4) return 1e-5;
    if (p < 13) return 1e-3;
    return isAngle(terms[static_cast<size_t>(p - 13)].component) ? 1e-5 : 1e-3;
  }
};

// The centre's information per unit touch variance from the touches' unit normals (centre to
// touch), the radius eliminated: N^T (I - 1 1^T / k) N.
Eigen::Matrix3d centreInformation(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& c) {
  Eigen::Matrix3d nn = Eigen::Matrix3d::Zero();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& t : pts) {
    const Eigen::Vector3d n = (t - c).normalized();
    nn += n * n.transpose();
    sum += n;
  }
  return nn - sum * sum.transpose() / static_cast<double>(pts.size());
}

// A sphere whose touches do not fix its whole centre (one left out by the screen): Gauss-Newton
// on |t_j - c| - rho over the radius and the centre's coordinates the touches fix (the directions
// of centreInformation at or above kSpheres3MeasuredFloor); the rest stays at `start`, which the
// touches' distances do not depend on to first order. Returns the fit, the measured directions'
// information and the projector onto the unmeasured ones.
SphereFit fitPartialSphere(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& start, double rho0,
                           Eigen::Matrix3d* information, Eigen::Matrix3d* unmeasured, int* measured) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(centreInformation(pts, start));
  std::vector<int> keep;
  for (int i = 0; i < 3; ++i)
    if (eig.eigenvalues()[i] >= kSpheres3MeasuredFloor) keep.push_back(i);
  const int d = static_cast<int>(keep.size());
  const int k = static_cast<int>(pts.size());
  if (d < 2 || k < d + 1)
    throw std::invalid_argument(fmt::format("{} touches fix {} coordinate{} of the centre (at least 2 needed)", k, d,
                                            d == 1 ? "" : "s"));
  Eigen::MatrixXd V(3, d);
  for (int i = 0; i < d; ++i) V.col(i) = eig.eigenvectors().col(keep[static_cast<size_t>(i)]);
  SphereFit f;
  // The shared engine over (the measured coordinates, the radius); converged when a step moves
  // them by less than 1e-12 mm, the engine's own tolerances off.
  const auto centre = [&](const Eigen::VectorXd& x) { return Eigen::Vector3d(start + V * x.head(d)); };
  LeastSquaresOptions lo;
  lo.max_iterations = 50;
  lo.step_tolerance = std::numeric_limits<double>::min();
  lo.function_tolerance = 0.0;
  lo.converged = [](const Eigen::VectorXd& before, const Eigen::VectorXd& after) { return (after - before).norm() < 1e-12; };
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(d + 1);
  x0[d] = rho0;
  const LeastSquaresResult solved = solveLeastSquares(
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
        const Eigen::Vector3d cx = centre(x);
        r.resize(k);
        if (J) J->resize(k, d + 1);
        for (int j = 0; j < k; ++j) {
          const Eigen::Vector3d n = (pts[static_cast<size_t>(j)] - cx).normalized();
          r[j] = (pts[static_cast<size_t>(j)] - cx).norm() - x[d];
          if (!J) continue;
          J->row(j).head(d) = -(n.transpose() * V);
          (*J)(j, d) = -1.0;
        }
      },
      x0, lo);
  f.iterations = solved.summary.iterations;
  f.converged = solved.summary.usable();
  const Eigen::Vector3d c = centre(solved.x);
  const double rho = solved.x[d];
  Eigen::VectorXd res(k);
  for (int j = 0; j < k; ++j) res[j] = (pts[static_cast<size_t>(j)] - c).norm() - rho;
  f.centre_mm = c;
  f.rho_mm = rho;
  f.radius_fitted = true;
  f.triggers = k;
  f.dof = k - d - 1;
  f.rss_mm2 = res.squaredNorm();
  f.residual_rms_um = mmToUm(std::sqrt(f.rss_mm2 / k));
  const Eigen::MatrixXd A = V.transpose() * centreInformation(pts, c) * V;  // d x d
  *information = V * A * V.transpose();
  f.cov_centre_per_sigma2 = V * A.inverse() * V.transpose();
  *unmeasured = Eigen::Matrix3d::Identity() - V * V.transpose();
  *measured = d;
  return f;
}

// Observation key (run, angle, sphere) -> where stage 2 put the sphere: the start of the
// coordinates a partial sphere does not measure.
using CentreStarts = std::map<std::tuple<int, int, int>, Eigen::Vector3d>;

Spheres3Result identifyOnce(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const Spheres3Options& opt,
                            const CentreStarts* starts);

}  // namespace

Spheres3Result identifySpheres3(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                const Spheres3Options& opt) {
  Spheres3Result r = identifyOnce(plan, runs, opt, nullptr);
  // A sphere measuring only part of its centre started the rest at the nominal pose; the touches'
  // distances depend on it only through their small offsets from the sphere's equator and pole
  // (0.1 mm off there moves a distance by up to 0.4 um), so once more from where stage 2 puts it.
  CentreStarts starts;
  for (const auto& o : r.observations)
    if (o.measured < 3) starts[{o.run, o.angle, o.sphere}] = o.fit.centre_mm - o.residual_mm;
  if (starts.empty()) return r;
  return identifyOnce(plan, runs, opt, &starts);
}

namespace {

Spheres3Result identifyOnce(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const Spheres3Options& opt,
                            const CentreStarts* starts) {
  requireValid(opt, "spheres3 options");
  if (plan.cycle != "spheres3") throw std::invalid_argument("plan is not a spheres3 plan (cycle '" + plan.cycle + "')");
  if (runs.empty()) throw std::invalid_argument("no results");
  Spheres3Result r;
  r.model = opt.model;
  const double ball = plan.machine.probe.ball_radius_mm();

  // Group the plan's points: angle (pose order) x sphere.
  std::map<std::string, int> angle_of;
  for (const auto& p : plan.poses) {
    angle_of[p.name] = static_cast<int>(r.c_deg.size());
    r.c_deg.push_back(p.pose.C);
  }
  const int n_angles = static_cast<int>(r.c_deg.size());
  std::vector<std::vector<int>> group(static_cast<size_t>(n_angles * 3));
  for (const auto& p : plan.points) {
    if (!p.sphere || p.sphere->id < 1 || p.sphere->id > 3)
      throw std::invalid_argument(fmt::format("point {} is not a touch on sphere 1, 2 or 3", p.id));
    const auto a = angle_of.find(p.pose_name);
    if (a == angle_of.end()) throw std::invalid_argument(fmt::format("point {}: unknown pose '{}'", p.id, p.pose_name));
    group[static_cast<size_t>(a->second * 3 + p.sphere->id - 1)].push_back(p.id);
    r.nominal_w_mm[static_cast<size_t>(p.sphere->id - 1)] = p.sphere->center_w_mm;
    r.nominal_radius_mm = p.sphere->radius_mm;
  }
  if (opt.hold_out_angle >= n_angles) throw std::invalid_argument("hold_out_angle beyond the plan's angles");
  // Every angle must see every sphere, or stage 1 has nothing to fit (and stage 2 an angle
  // without data): refuse the plan rather than guess.
  for (int a = 0; a < n_angles; ++a)
    for (int s = 0; s < 3; ++s)
      if (group[static_cast<size_t>(a * 3 + s)].size() < 4)
        throw std::invalid_argument(fmt::format(
            "plan pose {} (C = {:g} deg) has {} touches of sphere {}; a spheres3 plan needs at least 4 per sphere at "
            "every pose",
            plan.poses[static_cast<size_t>(a)].name, r.c_deg[static_cast<size_t>(a)],
            group[static_cast<size_t>(a * 3 + s)].size(), s + 1));

  // Stage 1.
  double rss_touch = 0.0;
  int dof_touch = 0;
  for (size_t run = 0; run < runs.size(); ++run) {
    std::map<int, const TriggerPoint*> by_id;
    for (const auto& t : runs[run].points) by_id[t.point_id] = &t;
    for (int a = 0; a < n_angles; ++a)
      for (int s = 0; s < 3; ++s) {
        const auto& all_ids = group[static_cast<size_t>(a * 3 + s)];
        std::vector<int> ids, held;
        std::vector<Eigen::Vector3d> pts;
        for (int id : all_ids) {
          const auto it = by_id.find(id);
          if (it == by_id.end())
            throw std::invalid_argument(fmt::format("{}: no trigger for point {}", runs[run].source, id));
          if (opt.hold_out_touch && opt.hold_out_touch(static_cast<int>(run), *plan.findPoint(id))) {
            held.push_back(id);
            continue;
          }
          ids.push_back(id);
          pts.push_back(it->second->position_m_mm);
        }
        if (ids.size() < 2)
          throw std::invalid_argument(fmt::format("{}: sphere {} at C = {:g} deg (points {}..{}): {} touches left",
                                                  runs[run].source, s + 1, r.c_deg[static_cast<size_t>(a)],
                                                  all_ids.front(), all_ids.back(), ids.size()));
        Eigen::Vector3d guess = T_m_w_nominal(plan.machine.kinematics, plan.findPoint(ids.front())->pose) *
                                r.nominal_w_mm[static_cast<size_t>(s)];
        if (starts) {
          const auto st = starts->find({static_cast<int>(run), a, s});
          if (st != starts->end()) guess = st->second;
        }
        Spheres3Observation o;
        o.run = static_cast<int>(run);
        o.angle = a;
        o.sphere = s;
        o.point_ids = ids;
        o.held_point_ids = held;
        try {
          // Only a held-out touch can leave a sphere short of a centre (the plan's five fix it).
          const bool partial = !held.empty() && (pts.size() < 4 || Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(
                                                                         centreInformation(pts, guess))
                                                                             .eigenvalues()
                                                                             .minCoeff() < kSpheres3MeasuredFloor);
          if (partial) {
            o.fit = fitPartialSphere(pts, guess, r.nominal_radius_mm + ball, &o.information_per_sigma2, &o.unmeasured,
                                     &o.measured);
          } else {
            o.fit = fitSphereCentre(pts, guess, {r.nominal_radius_mm + ball, true, 50});
            o.information_per_sigma2 = o.fit.cov_centre_per_sigma2.inverse();
          }
        } catch (const std::invalid_argument& e) {
          throw std::invalid_argument(fmt::format("{}: sphere {} at C = {:g} deg (points {}..{}): {}", runs[run].source,
                                                  s + 1, r.c_deg[static_cast<size_t>(a)], all_ids.front(), all_ids.back(),
                                                  e.what()));
        }
        const double dev_um = mmToUm(o.fit.rho_mm - ball - r.nominal_radius_mm);
        r.max_radius_dev_um = std::max(r.max_radius_dev_um, std::abs(dev_um));
        if (std::abs(dev_um) > opt.radius_tolerance_um)
          throw std::invalid_argument(fmt::format(
              "{}: sphere {} at C = {:g} deg (points {}..{}): fitted radius {:.4f} mm is {:+.1f} um from the nominal "
              "{:.4f} mm (limit {:g} um): a bad touch (chip, coolant), a wrong sphere or ball radius in the plan",
              runs[run].source, s + 1, r.c_deg[static_cast<size_t>(a)], all_ids.front(), all_ids.back(), o.fit.rho_mm - ball,
              dev_um, r.nominal_radius_mm, opt.radius_tolerance_um));
        rss_touch += o.fit.rss_mm2;
        dof_touch += o.fit.dof;
        o.held_out = a == opt.hold_out_angle;
        r.points_used += static_cast<int>(ids.size());
        r.observations.push_back(o);
      }
  }
  r.sigma_touch_um = dof_touch > 0 ? mmToUm(std::sqrt(rss_touch / dof_touch)) : 0.0;
  r.sigma_used_um = std::max(opt.prior_sigma_um, r.sigma_touch_um);

  // Stage 2: weighted Gauss-Newton on the exact model.
  Model model;
  if (opt.hold_out_angle >= 0 && opt.model == ComponentModel::Full)
    throw std::invalid_argument("the full component model has no spare angle to hold out");
  model.terms = componentTerms(opt.model, n_angles);
  r.terms = model.terms;
  const int np = model.size();
  r.parameters = np;
  std::vector<Eigen::Matrix3d> whiten;  // L^-1 with cov_unit = L L^T
  int measured_coordinates = 0;
  std::vector<const Spheres3Observation*> fitted;
  for (const auto& o : r.observations) {
    if (o.held_out) continue;
    fitted.push_back(&o);
    if (o.measured == 3) {
      const Eigen::LLT<Eigen::Matrix3d> llt(o.fit.cov_centre_per_sigma2);
      whiten.push_back(llt.matrixL().solve(Eigen::Matrix3d::Identity()));
    } else {
      // W^T W = the information, of rank `measured`: no weight where the touches fix nothing.
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(o.information_per_sigma2);
      whiten.push_back(eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose());
    }
    measured_coordinates += o.measured;
  }
  const int m = 3 * static_cast<int>(fitted.size());
  if (measured_coordinates < np)
    throw std::invalid_argument(fmt::format("{} centre coordinates cannot fix {} parameters", measured_coordinates, np));
  Eigen::VectorXd th = Eigen::VectorXd::Zero(np);
  for (int i = 0; i < 3; ++i) th.segment<3>(4 + 3 * i) = r.nominal_w_mm[static_cast<size_t>(i)];
  Eigen::VectorXd scale(np);
  for (int p = 0; p < np; ++p) scale[p] = model.scale(p);

  auto residuals = [&](const Eigen::VectorXd& t) {
    Eigen::VectorXd f(m);
    for (size_t k = 0; k < fitted.size(); ++k) {
      const auto& o = *fitted[k];
      const double c = degToRad(r.c_deg[static_cast<size_t>(o.angle)]);
      f.segment<3>(3 * static_cast<Eigen::Index>(k)) = whiten[k] * (o.fit.centre_mm - model.predict(t, o.sphere, c));
    }
    return f;
  };
  // The shared engine (core/least_squares) on the whitened residuals, the Jacobian by central
  // differences of the exact model (step 1e-3 of each parameter's typical size). Converged when a
  // step moves no sphere centre at any angle by more than step_tolerance_mm: the measure of this
  // model's linearisation, in the unit the spheres are measured in (the engine's own tolerances off).
  const auto jacobian = [&](const Eigen::VectorXd& t) {
    Eigen::MatrixXd J(m, np);
    for (int p = 0; p < np; ++p) {
      const double h = 1e-3 * scale[p];
      Eigen::VectorXd tp = t, tm = t;
      tp[p] += h;
      tm[p] -= h;
      J.col(p) = (residuals(tp) - residuals(tm)) / (2 * h);
    }
    return J;
  };
  const auto move = [&](const Eigen::VectorXd& before, const Eigen::VectorXd& after) {
    double most = 0.0;
    for (int i = 0; i < 3; ++i)
      for (double c : r.c_deg)
        most = std::max(most, (model.predict(after, i, degToRad(c)) - model.predict(before, i, degToRad(c))).norm());
    return most;
  };
  LeastSquaresOptions lo;
  lo.max_iterations = opt.max_iterations;
  lo.step_tolerance = std::numeric_limits<double>::min();
  lo.function_tolerance = 0.0;
  lo.converged = [&](const Eigen::VectorXd& before, const Eigen::VectorXd& after) {
    r.last_step_mm = move(before, after);
    return r.last_step_mm < opt.step_tolerance_mm;
  };
  const LeastSquaresResult solved = solveLeastSquares(
      [&](const Eigen::VectorXd& t, Eigen::VectorXd& res, Eigen::MatrixXd* J) {
        res = residuals(t);
        if (J) *J = jacobian(t);
      },
      th, lo);
  r.iterations = solved.summary.iterations;
  r.rank = solved.summary.rank;
  if (r.rank < np)
    throw std::invalid_argument(fmt::format("the spheres3 model is rank deficient ({} of {} parameters identifiable)",
                                            r.rank, np));
  if (!solved.summary.usable())
    throw std::invalid_argument(fmt::format("spheres3 fit did not converge in {} iterations (last step {:.3g} um)",
                                            opt.max_iterations, mmToUm(r.last_step_mm)));
  th = solved.x;
  {
    // The condition of the column-scaled whitened Jacobian at the solution, as the report states it.
    Eigen::MatrixXd Js = jacobian(th);
    for (int p = 0; p < np; ++p) Js.col(p) *= scale[p];
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(Js).singularValues();
    r.condition = sv[0] / sv[sv.size() - 1];
  }

  const Eigen::VectorXd f = residuals(th);
  const double s2 = std::pow(umToMm(r.sigma_used_um), 2);
  r.dof = measured_coordinates - np;
  r.chi2 = f.squaredNorm() / s2;
  // Covariance of th: sigma^2 (J^T W J)^-1 (the engine's, for whitened residuals of unit variance).
  r.covariance = s2 * solved.covariance;
  const Eigen::VectorXd u = r.covariance.diagonal().cwiseSqrt();
  r.location = th.head<4>();
  r.location_u = u.head<4>();
  for (int i = 0; i < 3; ++i) r.sphere_w_mm[static_cast<size_t>(i)] = th.segment<3>(4 + 3 * i);
  r.h = th.tail(np - 13);
  r.h_u = u.tail(np - 13);
  r.values.resize(n_angles, kNumComponentErrors);
  r.values_u.resize(n_angles, kNumComponentErrors);
  const Eigen::MatrixXd cov_h = r.covariance.bottomRightCorner(np - 13, np - 13);
  for (int a = 0; a < n_angles; ++a) {
    const double c = degToRad(r.c_deg[static_cast<size_t>(a)]);
    Eigen::MatrixXd B(kNumComponentErrors, np - 13);
    for (int t = 0; t < np - 13; ++t) B.col(t) = model.terms[static_cast<size_t>(t)].value(c);
    r.values.row(a) = (B * r.h).transpose();
    r.values_u.row(a) = (B * cov_h * B.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt().transpose();
  }

  // Residuals, held-out prediction, volumetric errors.
  double ss_fit = 0.0, ss_hold = 0.0;
  int n_fit = 0, n_hold = 0;
  r.volumetric_before_um = Eigen::MatrixXd::Zero(n_angles, 3);
  r.volumetric_after_location_um = Eigen::MatrixXd::Zero(n_angles, 3);
  r.volumetric_after_um = Eigen::MatrixXd::Zero(n_angles, 3);
  for (auto& o : r.observations) {
    const double c = degToRad(r.c_deg[static_cast<size_t>(o.angle)]);
    const Eigen::Vector3d s = r.sphere_w_mm[static_cast<size_t>(o.sphere)];
    o.residual_mm = o.fit.centre_mm - model.predict(th, o.sphere, c);
    if (o.held_out) {
      ss_hold += o.residual_mm.squaredNorm();
      n_hold += 3;
    } else {
      ss_fit += ((Eigen::Matrix3d::Identity() - o.unmeasured) * o.residual_mm).squaredNorm();
      n_fit += o.measured;
    }
    if (o.run == 0) {
      r.volumetric_before_um(o.angle, o.sphere) = mmToUm((o.fit.centre_mm - Dc(-c) * s).norm());
      r.volumetric_after_location_um(o.angle, o.sphere) =
          mmToUm((o.fit.centre_mm - spheres3Table_m_w(r.location, ComponentVector::Zero(), c) * s).norm());
      r.volumetric_after_um(o.angle, o.sphere) = mmToUm(o.residual_mm.norm());
    }
  }
  r.residual_rms_um = n_fit ? mmToUm(std::sqrt(ss_fit / n_fit)) : 0.0;
  r.holdout_rms_um = n_hold ? mmToUm(std::sqrt(ss_hold / n_hold)) : 0.0;
  return r;
}

}  // namespace

// ---- Report -------------------------------------------------------------------------------

namespace {


Json numbers(const Eigen::VectorXd& v) {
  Json a = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(round6(v[i]));
  return a;
}

}  // namespace

Json spheres3ReportJson(const ProbePlan& plan, const Spheres3Result& r, const std::vector<std::string>& files) {
  Json j = documentEnvelope("rotacal-report/1", plan, files);
  j["method"] = "spheres3_lsq";
  Json le = Json::object();
  for (int i = 0; i < 4; ++i) {
    const bool angle = i >= 2;
    le[spheres3LocationNames()[static_cast<size_t>(i)]] = {
        {"value", round6(angle ? radToMdeg(r.location[i]) : mmToUm(r.location[i]))},
        {"unit", angle ? "mdeg" : "um"},
        {"u", round6(angle ? radToMdeg(r.location_u[i]) : mmToUm(r.location_u[i]))},
        {"iso", spheres3LocationIso()[static_cast<size_t>(i)]}};
  }
  j["location_errors"] = le;
  j["location_errors_note"] =
      "C-axis location at the tilt axis' zero (001 Table 1): offsets of the axis average line at z = 0 of the machine "
      "frame, squareness as rotations about X and Y";
  const Eigen::VectorXd c = Eigen::Map<const Eigen::VectorXd>(r.c_deg.data(), static_cast<Eigen::Index>(r.c_deg.size()));
  Json ce = Json::object();
  for (int k = 0; k < kNumComponentErrors; ++k) {
    const double f = isAngle(k) ? kMdegPerRad : kUmPerMm;
    ce[componentNames()[static_cast<size_t>(k)]] = {{"unit", reportUnitOf(k)},
                                                   {"c_deg", numbers(c)},
                                                   {"values", numbers(r.values.col(k) * f)},
                                                   {"u", numbers(r.values_u.col(k) * f)}};
  }
  j["component_errors"] = ce;
  Json terms = Json::array();
  for (size_t t = 0; t < r.terms.size(); ++t) {
    const int comp = r.terms[t].component;
    terms.push_back({{"term", r.terms[t].name()},
                     {"value", round6(toReport(comp, r.h[static_cast<Eigen::Index>(t)]))},
                     {"u", round6(toReport(comp, r.h_u[static_cast<Eigen::Index>(t)]))},
                     {"unit", reportUnitOf(comp)}});
  }
  j["component_error_terms"] = terms;
  j["component_error_terms_u"] =
      "u of each term is its fit's own (the covariance of the series), no Type B evaluated: the signed u (u_c) is "
      "component_errors' at each angle";
  j["component_errors_convention"] =
      "Fourier series over the sampled angles without the mean (a location error or a sphere position) and without the "
      "first harmonic that turns with the table (a sphere position); positive EXC/EYC/EZC move the table in +X/+Y/+Z, "
      "positive EAC/EBC/ECC turn it about +X/+Y/+Z (docs/spheres3.md)";
  Json spheres = Json::array();
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d d = r.sphere_w_mm[static_cast<size_t>(i)] - r.nominal_w_mm[static_cast<size_t>(i)];
    spheres.push_back({{"id", i + 1},
                       {"center_w_mm", {round6(r.sphere_w_mm[i].x()), round6(r.sphere_w_mm[i].y()),
                                        round6(r.sphere_w_mm[i].z())}},
                       {"offset_from_nominal_um", {round6(mmToUm(d.x())), round6(mmToUm(d.y())), round6(mmToUm(d.z()))}}});
  }
  j["spheres"] = spheres;
  j["sphere_fit"] = {{"nominal_radius_mm", r.nominal_radius_mm},
                     {"max_radius_deviation_um", round6(r.max_radius_dev_um)},
                     {"touch_sigma_um", round6(r.sigma_touch_um)},
                     {"sigma_used_um", round6(r.sigma_used_um)}};
  auto maxOf = [](const Eigen::MatrixXd& m) { return m.size() ? m.maxCoeff() : 0.0; };
  j["volumetric_error_um"] = {{"max_before", round6(maxOf(r.volumetric_before_um))},
                              {"max_after_location_only", round6(maxOf(r.volumetric_after_location_um))},
                              {"max_after", round6(maxOf(r.volumetric_after_um))},
                              {"note", "|measured sphere centre - ideal|, first run: before = perfect machine, after = "
                                       "compensating what was identified (001 Fig. 13)"}};
  j["residual_rms_um"] = round6(r.residual_rms_um);
  j["points_used"] = r.points_used;
  j["summary"] = {{"iterations", r.iterations},     {"last_step_um", mmToUm(r.last_step_mm)},
                  {"parameters", r.parameters},     {"rank", r.rank},
                  {"condition", r.condition},       {"dof", r.dof},
                  {"chi2", round6(r.chi2)},         {"observations", 3 * static_cast<int>(r.observations.size())}};

  // Figures (schema: /work/briefs/figures.md).
  Json figs = Json::array();
  for (int group = 0; group < 2; ++group) {
    Json fig = {{"id", group == 0 ? "spheres3_component_errors_um" : "spheres3_component_errors_mdeg"},
                {"title", group == 0 ? "C-axis component errors, translations (001 Fig. 11 a-c)"
                                     : "C-axis component errors, rotations (001 Fig. 11 d-f)"},
                {"x", {{"label", "C"}, {"unit", "deg"}}},
                {"y", {{"label", "error"}, {"unit", group == 0 ? "um" : "mdeg"}}}};
    Json series = Json::array();
    for (int k = 3 * group; k < 3 * group + 3; ++k) {
      const double f = isAngle(k) ? kMdegPerRad : kUmPerMm;
      series.push_back({{"name", std::string(componentNames()[static_cast<size_t>(k)]) + "(C)"},
                        {"style", "line"},
                        {"x", numbers(c)},
                        {"y", numbers(r.values.col(k) * f)},
                        {"u", numbers(r.values_u.col(k) * f)}});
    }
    fig["series"] = series;
    fig["note"] = "zero mean, no component turning with the table (docs/spheres3.md)";
    figs.push_back(fig);
  }
  Json vol = {{"id", "spheres3_volumetric_error"},
              {"title", "Volumetric error of the three spheres before/after compensation (001 Fig. 13)"},
              {"x", {{"label", "C"}, {"unit", "deg"}}},
              {"y", {{"label", "|measured - ideal|"}, {"unit", "um"}}}};
  Json vs = Json::array();
  for (int i = 0; i < 3; ++i) {
    vs.push_back({{"name", fmt::format("sphere {} before", i + 1)}, {"style", "line"}, {"x", numbers(c)},
                  {"y", numbers(r.volumetric_before_um.col(i))}});
    vs.push_back({{"name", fmt::format("sphere {} after", i + 1)}, {"style", "points"}, {"x", numbers(c)},
                  {"y", numbers(r.volumetric_after_um.col(i))}});
  }
  vol["series"] = vs;
  vol["note"] = fmt::format("max {:.2f} um before, {:.2f} um after compensating location and component errors",
                            maxOf(r.volumetric_before_um), maxOf(r.volumetric_after_um));
  figs.push_back(vol);
  j["figures"] = figs;
  return j;
}

std::string spheres3Text(const Spheres3Result& r, const UncertaintyBudget* location) {
  std::string s = fmt::format("spheres3: {} touches, {} sphere centres, {} angles; touch noise {:.3f} um (1 dof per "
                              "sphere), largest radius deviation {:.2f} um\n",
                              r.points_used, r.observations.size(), r.c_deg.size(), r.sigma_touch_um,
                              r.max_radius_dev_um);
  s += fmt::format("C-axis location errors (001 Table 1, {}):\n", location ? "+- u_c, k = 1" : "+- the fit's u, k = 1");
  for (int i = 0; i < 4; ++i) {
    const bool angle = i >= 2;
    const double fit_u = angle ? radToMdeg(r.location_u[i]) : mmToUm(r.location_u[i]);
    const std::string name = spheres3LocationNames()[static_cast<size_t>(i)];
    s += fmt::format("  {} ({})  {:+9.3f} {} +- {:.3f}\n", name, spheres3LocationIso()[static_cast<size_t>(i)],
                     angle ? radToMdeg(r.location[i]) : mmToUm(r.location[i]), angle ? "mdeg" : "um  ",
                     location ? location->uCOr(name, fit_u) : fit_u);
  }
  if (!r.terms.empty()) {
    s += "component errors at each angle (um / mdeg):\n      C";
    for (const char* n : componentNames()) s += fmt::format(" {:>8}", n);
    s += "\n";
    for (size_t a = 0; a < r.c_deg.size(); ++a) {
      s += fmt::format("  {:5.0f}", r.c_deg[a]);
      for (int k = 0; k < kNumComponentErrors; ++k)
        s += fmt::format(" {:8.3f}", toReport(k, r.values(static_cast<Eigen::Index>(a), k)));
      s += "\n";
    }
  }
  s += fmt::format("volumetric error (max over spheres and angles): {:.2f} um before, {:.2f} um after compensating "
                   "the location errors, {:.2f} um after compensating location and component errors\n",
                   r.volumetric_before_um.maxCoeff(), r.volumetric_after_location_um.maxCoeff(),
                   r.volumetric_after_um.maxCoeff());
  s += fmt::format("residual {:.3f} um rms, chi2 {:.1f} on {} dof, {} Gauss-Newton iterations (last step {:.2g} um)\n",
                   r.residual_rms_um, r.chi2, r.dof, r.iterations, mmToUm(r.last_step_mm));
  return s;
}

}  // namespace rotacal

namespace rotacal {

Spheres3Noise spheres3DeclaredNoise(const ProbePlan& plan, const ContributorSet* declared) {
  Spheres3Noise out;
  out.trigger = perTouchDeclaration(declared, plan.machine.probe.repeatability_um);
  const auto n = static_cast<Eigen::Index>(plan.points.size());
  out.nu.resize(n);
  std::vector<Eigen::Vector3d> t, u;
  for (Eigen::Index i = 0; i < n; ++i) {
    const ProbePoint& p = plan.points[static_cast<size_t>(i)];
    if (!p.sphere) throw std::invalid_argument(fmt::format("point {} is not a touch on a sphere", p.id));
    out.index_of_id[p.id] = static_cast<int>(i);
    const Eigen::Vector3d c = T_m_w_nominal(plan.machine.kinematics, p.pose) * p.sphere->center_w_mm;
    out.nu[i] = (p.trigger_m_mm - c).normalized().dot(p.approach_m);
    t.push_back(p.trigger_m_mm);
    u.push_back(p.approach_m);
  }
  out.approach = u;
  if (declared) addProbeAxesPart(*declared, t, u, Eigen::VectorXd(), &out.trigger);
  return out;
}

Spheres3TouchProblem spheres3TouchProblem(const std::vector<MeasurementRun>& runs, const Spheres3Result& r,
                                          const Spheres3Noise& noise) {
  Spheres3TouchProblem out;
  std::vector<std::map<int, Eigen::Vector3d>> trigger(runs.size());
  for (size_t k = 0; k < runs.size(); ++k)
    for (const auto& t : runs[k].points) trigger[k][t.point_id] = t.position_m_mm;
  const int n_angles = static_cast<int>(r.c_deg.size());
  // One radius (R + r) per sphere and run: the same sphere touched by the same ball from the same
  // machine directions at every angle, so a chip that makes one angle's fitted radius smaller
  // stands out against the other angles' (stage 1 fits it per angle and cannot tell). The
  // residuals read from each radius's mean over the angles; its column takes up the rest.
  std::map<std::pair<int, int>, std::pair<double, int>> rho_sum;  // (run, sphere) -> (sum, count)
  for (const auto& o : r.observations) {
    auto& [sum, count] = rho_sum[{o.run, o.sphere}];
    sum += o.fit.rho_mm;
    ++count;
  }
  std::map<std::pair<int, int>, Eigen::Index> radius_col;
  for (const auto& [key, sc] : rho_sum) radius_col.emplace(key, static_cast<Eigen::Index>(radius_col.size()));
  const auto rhoOf = [&](const Spheres3Observation& o) {
    const auto& [sum, count] = rho_sum.at({o.run, o.sphere});
    return sum / count;
  };
  // Columns: 6 per angle (table motion), 9 (sphere positions), one radius per sphere and run.
  const Eigen::Index radius0 = 6 * n_angles + 9;
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> res;
  std::vector<std::pair<int, int>> kept;  // (run, plan index) for the covariance
  const Eigen::Index cols = radius0 + static_cast<Eigen::Index>(radius_col.size());
  for (size_t q = 0; q < r.observations.size(); ++q) {
    const Spheres3Observation& o = r.observations[q];
    const Eigen::Vector3d c = o.fit.centre_mm - o.residual_mm;  // where the stage-2 model puts the sphere
    const double cr = degToRad(r.c_deg[static_cast<size_t>(o.angle)]);
    const Eigen::Matrix3d R = spheres3Table_m_w(Eigen::Vector4d::Zero(), ComponentVector::Zero(), cr).linear();
    const double rho = rhoOf(o);
    const auto residualOf = [&](int id) {
      const Eigen::Vector3d& t = trigger[static_cast<size_t>(o.run)].at(id);
      return std::make_pair(mmToUm((t - c).norm() - rho), Eigen::Vector3d((t - c).normalized()));
    };
    for (int id : o.point_ids) {
      const auto [e, n] = residualOf(id);
      Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(cols);
      row.segment<3>(6 * o.angle) = n.transpose();
      row.segment<3>(6 * o.angle + 3) = c.cross(n).transpose();
      row.segment<3>(6 * n_angles + 3 * o.sphere) = n.transpose() * R;
      row[radius0 + radius_col.at({o.run, o.sphere})] = 1.0;
      rows.push_back(row);
      res.push_back(e);
      out.touches.emplace_back(o.run, id);
      kept.emplace_back(o.run, noise.index_of_id.at(id));
    }
    for (int id : o.held_point_ids) out.held.push_back({{o.run, id}, residualOf(id).first});
  }
  const auto m = static_cast<Eigen::Index>(rows.size());
  out.residual_um = Eigen::Map<const Eigen::VectorXd>(res.data(), m);
  out.J.resize(m, cols);
  for (Eigen::Index j = 0; j < m; ++j) out.J.row(j) = rows[static_cast<size_t>(j)];
  Eigen::VectorXd nu(m);
  for (Eigen::Index j = 0; j < m; ++j) nu[j] = noise.nu[kept[static_cast<size_t>(j)].second];
  out.covariance_um2 = nu.asDiagonal() * noise.trigger.covariance(kept) * nu.asDiagonal();
  out.readings = kept;
  out.nu = nu;

  // The smooth model's span, at the identified location errors and spheres (central differences
  // of the exact table transform; steps 1e-4 um / 1e-7 rad, far below any parameter).
  std::vector<ComponentTerm> smooth;
  for (const auto& t : componentTerms(ComponentModel::Full, n_angles))
    if (t.k <= Spheres3DiagnosisOptions{}.max_harmonic) smooth.push_back(t);
  const Eigen::Index ns = 13 + static_cast<Eigen::Index>(smooth.size());
  out.J_smooth = Eigen::MatrixXd::Zero(m, ns + static_cast<Eigen::Index>(radius_col.size()));
  const double hl = umToMm(1e-4), ha = 1e-7;
  const ComponentVector zero = ComponentVector::Zero();
  Eigen::Index row = 0;
  out.residual_smooth_um.resize(m);
  for (size_t q = 0; q < r.observations.size(); ++q) {
    const Spheres3Observation& o = r.observations[q];
    const double c = degToRad(r.c_deg[static_cast<size_t>(o.angle)]);
    const Eigen::Vector3d& sw = r.sphere_w_mm[static_cast<size_t>(o.sphere)];
    const auto at = [&](const Eigen::Vector4d& L, const ComponentVector& e, const Eigen::Vector3d& s) {
      return Eigen::Vector3d(spheres3Table_m_w(L, e, c) * s);
    };
    const Eigen::Vector3d c0 = at(r.location, zero, sw);
    for (size_t k = 0; k < o.point_ids.size(); ++k)
      out.residual_smooth_um[row + static_cast<Eigen::Index>(k)] =
          mmToUm((trigger[static_cast<size_t>(o.run)].at(o.point_ids[k]) - c0).norm() - rhoOf(o));
    Eigen::MatrixXd D(3, ns);  // d centre / d parameter, mm per mm or rad
    for (int i = 0; i < 4; ++i) {
      const double h = i < 2 ? hl : ha;
      Eigen::Vector4d lp = r.location, lm = r.location;
      lp[i] += h;
      lm[i] -= h;
      D.col(i) = (at(lp, zero, sw) - at(lm, zero, sw)) / (2 * h);
    }
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3d sp = sw, sm = sw;
      sp[a] += hl;
      sm[a] -= hl;
      D.col(4 + 3 * o.sphere + a) = (at(r.location, zero, sp) - at(r.location, zero, sm)) / (2 * hl);
      for (int b = 0; b < 3; ++b)
        if (b != o.sphere) D.col(4 + 3 * b + a).setZero();
    }
    for (size_t t = 0; t < smooth.size(); ++t) {
      const double h = smooth[t].component >= 3 ? ha : hl;
      const ComponentVector v = smooth[t].value(c);
      D.col(13 + static_cast<Eigen::Index>(t)) = (at(r.location, h * v, sw) - at(r.location, -h * v, sw)) / (2 * h);
    }
    for (size_t k = 0; k < o.point_ids.size(); ++k, ++row) {
      const Eigen::Vector3d n = out.J.row(row).segment<3>(6 * o.angle).transpose();  // the touch's normal
      out.J_smooth.row(row).head(ns) = n.transpose() * D;
      out.J_smooth(row, ns + radius_col.at({o.run, o.sphere})) = 1.0;
    }
  }

  // What the full model leaves of each touch: P_ii / (S^-1)_ii, P = S^-1 - S^-1 J (J^T S^-1 J)^+ J^T S^-1.
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(out.covariance_um2);
  const Eigen::MatrixXd Si = ldlt.solve(Eigen::MatrixXd::Identity(m, m));
  const Eigen::MatrixXd SiJ = Si * out.J;
  const Eigen::MatrixXd F = (out.J.transpose() * SiJ).completeOrthogonalDecomposition().pseudoInverse();
  out.full_share.resize(m);
  for (Eigen::Index j = 0; j < m; ++j)
    out.full_share[j] = (Si(j, j) - SiJ.row(j).dot(F * SiJ.row(j).transpose())) / Si(j, j);
  return out;
}

Eigen::MatrixXd spheres3OutlierStatisticColumns(const Spheres3TouchProblem& p, const Eigen::MatrixXd& y) {
  Eigen::MatrixXd t = deletionStatisticsColumns(y, p.J, p.covariance_um2);
  if ((p.full_share.array() < kSpheres3FullShareFloor).any()) {
    const Eigen::MatrixXd ts = deletionStatisticsColumns(y, p.J_smooth, p.covariance_um2);
    for (Eigen::Index j = 0; j < t.rows(); ++j)
      if (p.full_share[j] < kSpheres3FullShareFloor) t.row(j) = ts.row(j);
  }
  return t;
}

Eigen::VectorXd spheres3OutlierStatistic(const Spheres3TouchProblem& p) {
  Eigen::VectorXd t = deletionStatistics(p.residual_um, p.J, p.covariance_um2);
  if ((p.full_share.array() < kSpheres3FullShareFloor).any()) {
    const Eigen::VectorXd ts = deletionStatistics(p.residual_smooth_um, p.J_smooth, p.covariance_um2);
    for (Eigen::Index j = 0; j < t.size(); ++j)
      if (p.full_share[j] < kSpheres3FullShareFloor) t[j] = ts[j];
  }
  return t;
}

Eigen::VectorXd spheres3OutlierSensitivity(const Spheres3TouchProblem& p) {
  Eigen::VectorXd k = deletionSensitivity(p.J, p.covariance_um2);
  if ((p.full_share.array() < kSpheres3FullShareFloor).any()) {
    const Eigen::VectorXd ks = deletionSensitivity(p.J_smooth, p.covariance_um2);
    for (Eigen::Index j = 0; j < k.size(); ++j)
      if (p.full_share[j] < kSpheres3FullShareFloor) k[j] = ks[j];
  }
  return k;
}

Spheres3Screen screenSpheres3Touches(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const Spheres3Noise& noise, const Spheres3Options& options) {
  // Each fit the screen asks for, by the touches it holds out: the statistic reads its problem.
  using Key = std::vector<std::pair<int, int>>;  // (run, point id), sorted
  const auto problems = std::make_shared<std::map<Key, Spheres3TouchProblem>>();
  const auto keyOf = [](const std::vector<PointResidual>& residuals) { return heldOutTouches(residuals); };
  Spheres3Options o = options;
  o.radius_tolerance_um = std::numeric_limits<double>::infinity();
  // The statistic reads P r, the same for any parameters in the model's span to first order: a
  // step of 1e-3 um changes none, and a gross chip (Gauss-Newton converges linearly on a large
  // residual) then needs no more than the screen's few iterations.
  o.step_tolerance_mm = std::max(o.step_tolerance_mm, umToMm(1e-3));
  o.max_iterations = std::max(o.max_iterations, 50);
  const auto fit = [&](const std::function<bool(int, const ProbePoint&)>& hold) {
    ScreenedFit out;
    Spheres3Options oh = o;
    oh.hold_out_touch = hold;
    std::optional<Spheres3Result> r;
    if (!hold) {
      r = identifySpheres3(plan, runs, oh);
    } else {
      try {
        r = identifySpheres3(plan, runs, oh);
      } catch (const std::invalid_argument& e) {
        // This touch cannot be left out (its sphere would fix fewer than two coordinates of its centre,
        // or the model would lose a parameter): the screen keeps it.
        out.summary.termination = Termination::RankDeficient;
        out.summary.message = e.what();
        return out;
      }
    }
    Spheres3TouchProblem p = spheres3TouchProblem(runs, *r, noise);
    out.summary.termination = Termination::Converged;
    for (Eigen::Index j = 0; j < p.residual_um.size(); ++j)
      out.residuals.push_back({p.touches[static_cast<size_t>(j)].first, p.touches[static_cast<size_t>(j)].second,
                               p.residual_um[j], 0.0, false});
    for (const auto& [touch, e] : p.held) out.residuals.push_back({touch.first, touch.second, e, 0.0, true});
    (*problems)[keyOf(out.residuals)] = std::move(p);
    return out;
  };
  Spheres3Screen s;
  s.options.sigma_um = std::sqrt(noise.trigger.white_um2);
  s.options.declaration = noise.trigger.declaration;
  s.options.statistic = [problems, keyOf](const ScreenedFit& f) {
    const auto it = problems->find(keyOf(f.residuals));
    if (it == problems->end()) throw std::logic_error("spheres3 outlier screen: a statistic asked of a fit never made");
    return spheres3OutlierStatistic(it->second);
  };
  s.options.null_maxima = [problems, keyOf, &noise](const ScreenedFit& f) {
    const Spheres3TouchProblem& p = problems->at(keyOf(f.residuals));
    const Eigen::MatrixXd draws = noise.trigger.nullDraws(p.readings, kDeclaredNullSeed + 1);
    if (draws.cols() == 0) return Eigen::VectorXd();
    return screenNullMaxima(spheres3OutlierStatisticColumns(p, p.nu.asDiagonal() * draws));
  };
  s.options.sensitivity = [problems, keyOf](const ScreenedFit& f) {
    return spheres3OutlierSensitivity(problems->at(keyOf(f.residuals)));
  };
  s.screen = screenOutliers(fit, s.options);
  s.options.null_maxima = nullptr;  // it reads this call's declaration
  s.options.sensitivity = nullptr;
  if (s.screen.too_many) return s;
  // The problem of the fit holding `held` out (made once), or null when that fit fails.
  const auto problemFor = [&](const Key& held) -> const Spheres3TouchProblem* {
    if (problems->find(held) == problems->end()) {
      const std::set<std::pair<int, int>> out(held.begin(), held.end());
      const ScreenedFit f =
          fit([out](int run, const ProbePoint& p) { return out.count({run, p.id}) > 0; });
      if (f.summary.termination != Termination::Converged) return nullptr;
    }
    const auto it = problems->find(held);
    return it == problems->end() ? nullptr : &it->second;
  };
  const auto consistent = [&](const Key& held) {
    const Spheres3TouchProblem* p = problemFor(held);
    return p && (spheres3OutlierStatistic(*p).array().abs() <= s.screen.threshold_t).all();
  };
  // The screen leaves out the worst touch first, but a chip on one side of a sphere makes the
  // sphere look narrower along that line whichever of the two opposite touches it sits under:
  // within its sphere's five touches a chip on +X and one on -X read the same, and only where the
  // sphere's centre then sits (against the other two spheres at that angle) tells them apart. So
  // per sphere and angle with a touch left out, every touch of it is tried alone in its place:
  // those whose deletion alone leaves no touch beyond the threshold are the chip's confidence set
  // at the screen's own level (under a single chip there, the right one fails to pass with at
  // most the screen's alpha). One: it is the chip (the screen's worst or not). Several: the data cannot
  // tell which; all are left out. None: the screen's own choice stands (more than one bad touch).
  Key held;
  for (const auto& e : s.screen.excluded) held.emplace_back(e.run, e.point_id);
  std::sort(held.begin(), held.end());
  const auto groupOf = [&](int id) {
    const ProbePoint* p = plan.findPoint(id);
    return std::make_pair(p->pose_name, p->sphere ? p->sphere->id : 0);
  };
  std::map<std::pair<int, int>, double> first_t;  // (run, id) -> the statistic the screen left it out at
  for (const auto& e : s.screen.excluded) first_t[{e.run, e.point_id}] = e.t;
  std::set<std::tuple<int, std::string, int>> done;
  for (const auto& [run, id] : Key(held)) {
    const auto [pose, sphere] = groupOf(id);
    if (!done.insert({run, pose, sphere}).second) continue;
    Key others;
    for (const auto& h : held)
      if (!(h.first == run && groupOf(h.second) == std::make_pair(pose, sphere))) others.push_back(h);
    std::vector<int> confident;
    for (const auto& q : plan.points) {
      if (q.pose_name != pose || !q.sphere || q.sphere->id != sphere) continue;
      Key trial = others;
      trial.emplace_back(run, q.id);
      std::sort(trial.begin(), trial.end());
      if (consistent(trial)) confident.push_back(q.id);
    }
    if (confident.empty()) continue;
    Key all = others;
    for (int q : confident) all.emplace_back(run, q);
    std::sort(all.begin(), all.end());
    const double c_deg = plan.findPoint(confident.front())->pose.C;
    if (confident.size() > 1 && !problemFor(all)) {
      // All of them cannot be left out (the sphere would fix fewer than two coordinates of its
      // centre there, and the table's pose at that angle would go unfixed). The screen's own pick
      // already makes the data consistent at its level: it stands, reported with the set. A set
      // this wide comes of a touch barely beyond the threshold, not of a gross chip, whose
      // deletion alone is the only one that clears the data.
      std::vector<int> picked;
      for (const auto& h : held)
        if (h.first == run && groupOf(h.second) == std::make_pair(pose, sphere)) picked.push_back(h.second);
      s.ambiguous.push_back({run, sphere, c_deg, confident, picked});
      continue;
    }
    held = all;
    if (confident.size() > 1) s.ambiguous.push_back({run, sphere, c_deg, confident, {}});
  }
  // The excluded list as left out now: each touch against the model fitted without it, at the
  // statistic the screen left it out at (or, for a touch added here, its own in the fit with its
  // sphere's touches all in).
  const Spheres3TouchProblem* last = problemFor(held);
  if (!last) {
    std::string list;
    for (const auto& a : s.ambiguous) list += (list.empty() ? "" : "; ") + a.text();
    s.refused = fmt::format("outlier screen: {}; without them the sphere's centre at that angle is not fixed, nor the "
                            "table's pose there: clean the sphere and measure again",
                            list.empty() ? "the touches left out cannot all be done without" : list);
    return s;
  }
  std::vector<ExcludedTouch> excluded;
  for (const auto& [run, id] : held) {
    ExcludedTouch e{run, id, 0.0, 0.0};
    for (const auto& [touch, res] : last->held)
      if (touch == std::make_pair(run, id)) e.residual_um = res;
    const auto ft = first_t.find({run, id});
    if (ft != first_t.end()) {
      e.t = ft->second;
    } else {
      Key in;
      for (const auto& h : held)
        if (!(h.first == run && groupOf(h.second) == groupOf(id))) in.push_back(h);
      if (const Spheres3TouchProblem* p = problemFor(in)) {
        const Eigen::VectorXd t = spheres3OutlierStatistic(*p);
        for (size_t j = 0; j < p->touches.size(); ++j)
          if (p->touches[j] == std::make_pair(run, id)) e.t = t[static_cast<Eigen::Index>(j)];
      }
    }
    excluded.push_back(e);
  }
  s.screen.excluded = excluded;
  // A touch beyond the threshold that could not be left out (the screen keeps a touch whose
  // removal leaves the fit without a parameter) is named here: the data must not be analysed
  // with it.
  const Eigen::VectorXd t = spheres3OutlierStatistic(*last);
  for (Eigen::Index j = 0; j < t.size(); ++j)
    if (std::abs(t[j]) > s.screen.threshold_t)
      s.kept_beyond.push_back({last->touches[static_cast<size_t>(j)].first, last->touches[static_cast<size_t>(j)].second,
                               last->residual_um[j], t[j]});
  return s;
}

std::string Spheres3Ambiguity::text() const {
  const auto listOf = [](const std::vector<int>& ids) {
    std::string list;
    for (int id : ids) list += fmt::format("{}{}", list.empty() ? "" : ", ", id);
    return list;
  };
  const std::string where = fmt::format("sphere {} at C = {:g} deg{}", sphere, c_deg,
                                        run > 0 ? fmt::format(" (run {})", run + 1) : std::string());
  if (!left_out.empty())
    return fmt::format("{}: one of points {} is beyond the declared noise (the deletion of each alone makes the data "
                       "consistent with it, so the data cannot tell which), and without all of them the sphere's "
                       "centre there is not fixed: the screen's pick, point{} {}, is left out",
                       where, listOf(point_ids), left_out.size() == 1 ? "" : "s", listOf(left_out));
  return fmt::format("{}: points {} left out: one of them hit a chip or dirt (the deletion of each alone makes the "
                     "data consistent with the declared noise, so the data cannot tell which); the sphere's centre at "
                     "that angle is measured only where its other touches fix it",
                     where, listOf(point_ids));
}

std::string Spheres3Screen::keptBeyondText() const {
  if (kept_beyond.empty()) return "";
  std::string list;
  for (const auto& e : kept_beyond)
    list += fmt::format("{}point {}{} (t {:.1f})", list.empty() ? "" : ", ", e.point_id,
                        e.run > 0 ? fmt::format(" of run {}", e.run + 1) : std::string(), std::abs(e.t));
  return fmt::format("outlier screen: {} beyond {:.2f} x the declared noise, but the model cannot do without {} (its "
                     "sphere's centre at that angle, or the table's pose there, would not be fixed): a chip or dirt there "
                     "would go into the errors; clean the sphere and measure again",
                     list, screen.threshold_t, kept_beyond.size() == 1 ? "it" : "them");
}

}  // namespace rotacal
