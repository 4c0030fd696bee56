#include "cycles/spheres3/budget.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/probe_plan.hpp"
#include "core/report_envelope.hpp"
#include "core/rng.hpp"
#include "core/sphere_centre_fit.hpp"
#include "core/units.hpp"

namespace rotacal {

bool spheres3TypeA(const ContributorInfo& c) { return isPerTouchContributor(c); }

bool spheres3TypeB(const ContributorInfo& c) { return isProbeAxesContributor(c); }

namespace {

constexpr int kLocation = 4;
bool isAngleComponent(int k) { return k >= 3; }
double componentFactor(int k) { return isAngleComponent(k) ? kMdegPerRad : kUmPerMm; }
double locationFactor(int i) { return i < 2 ? kUmPerMm : kMdegPerRad; }

/// The parameter scales of analyze's stage 2 (1 um, 10 urad): the finite-difference steps.
double parameterScale(const Spheres3Result& r, int p) {
  if (p < 2) return 1e-3;
  if (p < 4) return 1e-5;
  if (p < 13) return 1e-3;
  return isAngleComponent(r.terms[static_cast<size_t>(p - 13)].component) ? 1e-5 : 1e-3;
}

Eigen::VectorXd parameters(const Spheres3Result& r) {
  Eigen::VectorXd th(13 + r.h.size());
  th.head<4>() = r.location;
  for (int i = 0; i < 3; ++i) th.segment<3>(4 + 3 * i) = r.sphere_w_mm[static_cast<size_t>(i)];
  th.tail(r.h.size()) = r.h;
  return th;
}

Eigen::Vector3d predict(const Spheres3Result& r, const Eigen::VectorXd& th, int sphere, double c_rad) {
  ComponentVector e = ComponentVector::Zero();
  for (size_t t = 0; t < r.terms.size(); ++t) e += th[13 + static_cast<Eigen::Index>(t)] * r.terms[t].value(c_rad);
  return spheres3Table_m_w(th.head<4>(), e, c_rad) * th.segment<3>(4 + 3 * sphere);
}

}  // namespace

Truth spheres3IdentifiedTruth(const ProbePlan& plan, const Spheres3Result& r) {
  Truth t;
  t.errors.kinematics = plan.machine.kinematics;
  // The table at each sampled C computed once: the simulator asks for it at every touch.
  std::vector<std::pair<double, Eigen::Isometry3d>> table;
  for (double c : r.c_deg)
    table.emplace_back(c, spheres3Table_m_w(r.location, r.componentAt(c), degToRad(c)));
  const Eigen::Vector4d location = r.location;
  const std::vector<ComponentTerm> terms = r.terms;
  const Eigen::VectorXd h = r.h;
  t.table_transform = [table, location, terms, h](const Pose& pose, double) {
    for (const auto& [c, T] : table)
      if (std::abs(c - pose.C) < 1e-12) return T;
    ComponentVector e = ComponentVector::Zero();
    for (size_t k = 0; k < terms.size(); ++k) e += h[static_cast<Eigen::Index>(k)] * terms[k].value(degToRad(pose.C));
    return spheres3Table_m_w(location, e, degToRad(pose.C));
  };
  for (int i = 0; i < 3; ++i)
    t.sphere_center_error_w_mm[i + 1] = r.sphere_w_mm[static_cast<size_t>(i)] - r.nominal_w_mm[static_cast<size_t>(i)];
  return t;
}

Spheres3LinearMap linearSpheres3(const ProbePlan& plan, const Spheres3Result& r) {
  const int np_points = static_cast<int>(plan.points.size());
  const int n_angles = static_cast<int>(r.c_deg.size());
  const int np = 13 + static_cast<int>(r.h.size());
  Spheres3LinearMap out;
  const MeasurementRun ideal = simulate(plan, spheres3IdentifiedTruth(plan, r), {1});
  out.ideal_s_mm.resize(np_points);
  for (int i = 0; i < np_points; ++i)
    out.ideal_s_mm[i] = alongApproach(plan.points[static_cast<size_t>(i)], ideal.points[static_cast<size_t>(i)]);

  // The same grouping as identifySpheres3: angle (pose order) x sphere.
  std::map<std::string, int> angle_of;
  for (size_t a = 0; a < plan.poses.size(); ++a) angle_of[plan.poses[a].name] = static_cast<int>(a);
  std::vector<std::vector<int>> group(static_cast<size_t>(n_angles * 3));  // plan point indices
  for (int i = 0; i < np_points; ++i) {
    const ProbePoint& p = plan.points[static_cast<size_t>(i)];
    group[static_cast<size_t>(angle_of.at(p.pose_name) * 3 + p.sphere->id - 1)].push_back(i);
  }
  const double rho = r.nominal_radius_mm + plan.machine.probe.ball_radius_mm();

  // Stage 1, per sphere and angle: the centre's change from the touches' shifts along their
  // approach, -pinv(J1)_xyz diag(n.u), J1 = [-n^T, -1] the sphere fit's own Jacobian; and what
  // stays in its residual, (I - J1 pinv(J1)) diag(n.u).
  const int m = 3 * n_angles * 3;
  Eigen::MatrixXd centre_map = Eigen::MatrixXd::Zero(m, np_points);
  Eigen::MatrixXd whiten = Eigen::MatrixXd::Zero(m, m);
  out.residual = Eigen::MatrixXd::Zero(np_points, np_points);
  // The touches the analysis left out (the outlier screen's, first run's) are left out here too:
  // their shifts reach nothing, and a sphere whose other touches fix only part of its centre
  // passes on only that part (as identifySpheres3 weighs it), so that U is the estimator's own.
  std::map<int, const Spheres3Observation*> analysed;  // group -> the first run's observation
  for (const auto& o : r.observations)
    if (o.run == 0) analysed[o.angle * 3 + o.sphere] = &o;
  for (int g = 0; g < n_angles * 3; ++g) {
    const Spheres3Observation* o = analysed.count(g) ? analysed.at(g) : nullptr;
    std::vector<int> ids;
    for (int i : group[static_cast<size_t>(g)]) {
      const int id = plan.points[static_cast<size_t>(i)].id;
      if (!o || std::find(o->held_point_ids.begin(), o->held_point_ids.end(), id) == o->held_point_ids.end())
        ids.push_back(i);
    }
    std::vector<Eigen::Vector3d> pts;
    for (int i : ids) pts.push_back(ideal.points[static_cast<size_t>(i)].position_m_mm);
    const Eigen::Vector3d guess =
        predict(r, parameters(r), g % 3, degToRad(r.c_deg[static_cast<size_t>(g / 3)]));
    const int n = static_cast<int>(ids.size());
    std::vector<Eigen::Vector3d> approaches;
    for (int i : ids) approaches.push_back(plan.points[static_cast<size_t>(i)].approach_m);
    Eigen::MatrixXd dc, res;
    if (!o || o->measured == 3) {
      const SphereFit fit = fitSphereCentre(pts, guess, {rho, true, 50});
      const SphereFitMap sm = linearSphereFit(pts, approaches, fit);
      dc = sm.centre;
      res = sm.residual;
      out.stage1_dof += fit.dof;
      const Eigen::LLT<Eigen::Matrix3d> llt(fit.cov_centre_per_sigma2);
      whiten.block<3, 3>(3 * g, 3 * g) = llt.matrixL().solve(Eigen::Matrix3d::Identity());
    } else {
      // The fit over the radius and the measured directions V alone (the ideal touches lie on
      // the sphere around the identified centre): J = [-n^T V, -1].
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(Eigen::Matrix3d::Identity() - o->unmeasured);
      Eigen::MatrixXd V(3, o->measured);
      for (int i = 0, c = 0; i < 3; ++i)
        if (eig.eigenvalues()[i] > 0.5 && c < o->measured) V.col(c++) = eig.eigenvectors().col(i);
      Eigen::MatrixXd J(n, o->measured + 1);
      Eigen::VectorXd nu(n);
      for (int j = 0; j < n; ++j) {
        const Eigen::Vector3d nj = (pts[static_cast<size_t>(j)] - guess).normalized();
        J.row(j).head(o->measured) = -(nj.transpose() * V);
        J(j, o->measured) = -1.0;
        nu[j] = nj.dot(approaches[static_cast<size_t>(j)]);
      }
      const Eigen::MatrixXd pinv = J.completeOrthogonalDecomposition().pseudoInverse();
      dc = -V * pinv.topRows(o->measured) * nu.asDiagonal();
      res = (Eigen::MatrixXd::Identity(n, n) - J * pinv) * nu.asDiagonal();
      out.stage1_dof += n - o->measured - 1;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> info(o->information_per_sigma2);
      whiten.block<3, 3>(3 * g, 3 * g) =
          info.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * info.eigenvectors().transpose();
    }
    for (int j = 0; j < n; ++j) {
      centre_map.block(3 * g, ids[static_cast<size_t>(j)], 3, 1) = dc.col(j);
      for (int k = 0; k < n; ++k)
        out.residual(ids[static_cast<size_t>(k)], ids[static_cast<size_t>(j)]) = res(k, j);
    }
  }

  // Stage 2: the weighted least squares' own map at the identified parameters,
  // d theta = S pinv(W J S) W d centres (S the column scales, J by central differences).
  const Eigen::VectorXd th = parameters(r);
  Eigen::MatrixXd J(m, np);
  for (int p = 0; p < np; ++p) {
    const double h = 1e-3 * parameterScale(r, p);
    Eigen::VectorXd tp = th, tm = th;
    tp[p] += h;
    tm[p] -= h;
    for (int g = 0; g < n_angles * 3; ++g) {
      const double c = degToRad(r.c_deg[static_cast<size_t>(g / 3)]);
      J.block(3 * g, p, 3, 1) = (predict(r, tp, g % 3, c) - predict(r, tm, g % 3, c)) / (2 * h) * parameterScale(r, p);
    }
  }
  Eigen::VectorXd scale(np);
  for (int p = 0; p < np; ++p) scale[p] = parameterScale(r, p);
  const Eigen::MatrixXd pinv2 = (whiten * J).completeOrthogonalDecomposition().pseudoInverse();
  out.G = scale.asDiagonal() * pinv2 * whiten * centre_map;
  out.values.resize(kNumComponentErrors * n_angles, np_points);
  const int nt = static_cast<int>(r.terms.size());
  for (int a = 0; a < n_angles; ++a) {
    Eigen::MatrixXd B(kNumComponentErrors, nt);
    for (int t = 0; t < nt; ++t) B.col(t) = r.terms[static_cast<size_t>(t)].value(degToRad(r.c_deg[static_cast<size_t>(a)]));
    out.values.middleRows(kNumComponentErrors * a, kNumComponentErrors) = B * out.G.bottomRows(nt);
  }
  return out;
}

void drawSpheres3(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, int run, int only,
                  Spheres3Draw* d) {
  drawProbeAxes(plan, set, spheres3TypeB, seed, run, only, d);
}

void applySpheres3Draw(const Spheres3Draw& d, Truth* truth) { applyProbeAxesDraw(d, truth); }

Spheres3Budget spheres3Budget(const ProbePlan& plan, const Spheres3Result& r, const std::vector<Spheres3Result>& per_run,
                              const ContributorSet* contributors, const Spheres3BudgetOptions& options) {
  options.validateOrThrow();
  const int n_angles = static_cast<int>(r.c_deg.size());
  const int n = kLocation + kNumComponentErrors * n_angles;
  const double repeats = static_cast<double>(std::max<size_t>(1, per_run.size()));

  // Every parameter the budget covers, in report units: the four location errors, then each
  // component error at each sampled angle ("EXC@30").
  UncertaintyBudget full;
  Eigen::VectorXd factor(n);
  for (int i = 0; i < kLocation; ++i) {
    full.names.emplace_back(spheres3LocationNames()[static_cast<size_t>(i)]);
    full.units.emplace_back(i < 2 ? "um" : "mdeg");
    factor[i] = locationFactor(i);
  }
  for (int a = 0; a < n_angles; ++a)
    for (int k = 0; k < kNumComponentErrors; ++k) {
      full.names.push_back(fmt::format("{}@{:g}", componentNames()[static_cast<size_t>(k)], r.c_deg[static_cast<size_t>(a)]));
      full.units.emplace_back(isAngleComponent(k) ? "mdeg" : "um");
      factor[kLocation + kNumComponentErrors * a + k] = componentFactor(k);
    }
  const Spheres3LinearMap lin = linearSpheres3(plan, r);
  Eigen::MatrixXd G(n, lin.G.cols());
  G.topRows(kLocation) = lin.G.topRows(kLocation);
  G.bottomRows(n - kLocation) = lin.values;
  G = factor.asDiagonal() * G;

  // The split of the declared contributors.
  const ContributorSplit split = contributors ? splitContributors(*contributors, spheres3TypeA, spheres3TypeB) : ContributorSplit{};
  const double declared_mm2 = split.per_reading_mm2;
  const ContributorSet& type_b = split.type_b;
  const std::vector<std::string>& left_out = split.left_out;
  const Truth base = spheres3IdentifiedTruth(plan, r);
  // The triggers' deviation along the approach under a draw (exact simulator), mm.
  auto triggerShift = [&](const Spheres3Draw& d) {
    Truth t = base;
    applySpheres3Draw(d, &t);
    return Eigen::VectorXd(triggersAlong(plan, t) - lin.ideal_s_mm);
  };

  // Type A (readingScatter). The sphere fits' residual (1 dof per sphere and angle) measures the
  // per-touch scatter, and also the part of the Type B contributors a sphere cannot absorb (the
  // linear axes' random errors across its 38 mm; pretravel differing between opposite directions
  // is absorbed by the centre), which u_B counts.
  double sigma2 = 0.0;
  std::string how;
  const double s_obs_mm = umToMm(r.sigma_touch_um);
  if (!contributors) {
    sigma2 = std::pow(umToMm(r.sigma_used_um), 2);
    how = fmt::format("the larger of the sphere fits' touch noise {:.3f} um and the probe repeatability of the machine",
                      r.sigma_touch_um);
  } else {
    std::vector<double> sys_um2;
    if (!type_b.items.empty() && lin.stage1_dof > 0) {
      sys_um2 = contributorResidualVariances(200, options.seed, [&](std::uint64_t seed, int k) {
        Spheres3Draw d;
        drawSpheres3(plan, type_b, seed, k, -1, &d);
        return mmToUm(1.0) * mmToUm(1.0) * (lin.residual * triggerShift(d)).squaredNorm() / lin.stage1_dof;
      });
    }
    const ReadingScatter scatter = readingScatter(mmToUm(1.0) * mmToUm(1.0) * declared_mm2,
                                                  mmToUm(s_obs_mm) * mmToUm(s_obs_mm),
                                                  lin.stage1_dof * static_cast<int>(repeats), sys_um2);
    sigma2 = umToMm(1.0) * umToMm(1.0) * scatter.variance_um2;
    how = scatter.why + "; declared: probe repeatability, surface roughness";
  }
  Eigen::MatrixXd cov_a = sigma2 / repeats * G * G.transpose();
  full.type_a_source = fmt::format("the per-touch scatter {:.3f} um ({}) through the estimator, {} run(s)",
                                   mmToUm(std::sqrt(sigma2)), how, per_run.size() > 1 ? per_run.size() : 1);
  // Repeats: a parameter whose repeats scatter more (drift between runs, a sphere that moved)
  // takes the scatter of their mean instead; correlations kept by scaling.
  {
    std::vector<Eigen::VectorXd> each;
    for (const auto& pr : per_run) {
      Eigen::VectorXd v(n);
      v.head<kLocation>() = pr.location;
      for (int a = 0; a < n_angles; ++a) v.segment<kNumComponentErrors>(kLocation + kNumComponentErrors * a) = pr.values.row(a).transpose();
      each.push_back(factor.cwiseProduct(v));
    }
    full.type_a_source += raiseToRepeatScatter(&cov_a, each);
  }
  full.cov_a = cov_a;
  full.cov_b = Eigen::MatrixXd::Zero(n, n);
  full.terms.push_back({"data", full.uA()});
  const std::string left_out_text = leftOutNote("three spheres", left_out);
  if (typeBToRun(&full, contributors != nullptr, !type_b.items.empty(), "the three-sphere cycle", left_out_text)) {
    runTypeB(&full, type_b, options, [&](std::uint64_t seed, int run, int c) -> Eigen::VectorXd {
      Spheres3Draw d;
      drawSpheres3(plan, type_b, seed, run, c, &d);
      return G * triggerShift(d);
    });
    full.type_b_source = typeBDrawnSource(type_b.items.size(), *contributors,
                                          "the exact simulator (full HTMs, exact ball-on-sphere contact) around the "
                                          "identified errors, the triggers' deviation run through the estimator "
                                          "linearised there (both stages)",
                                          options, left_out_text);
  }

  Spheres3Budget out;
  out.location = full.slice(0, kLocation);
  const Eigen::VectorXd ua = full.uA(), ub = full.uB(), uc = full.uC(), kf = full.coverageFactors();
  out.coverage_source = coverageFactorSource(full);
  out.component_u_a.resize(n_angles, kNumComponentErrors);
  out.component_u_b.resize(n_angles, kNumComponentErrors);
  out.component_u_c.resize(n_angles, kNumComponentErrors);
  out.component_k.resize(n_angles, kNumComponentErrors);
  for (int a = 0; a < n_angles; ++a)
    for (int k = 0; k < kNumComponentErrors; ++k) {
      const int i = kLocation + kNumComponentErrors * a + k;
      out.component_u_a(a, k) = ua[i];
      out.component_u_b(a, k) = ub[i];
      out.component_u_c(a, k) = uc[i];
      out.component_k(a, k) = kf[i];
    }
  return out;
}

void addSpheres3Budget(Json* report, const Spheres3Budget& b) {
  addBudgetFields(&(*report)["location_errors"], b.location);
  (*report)["uncertainty"] = budgetJson(b.location);
  if (!report->contains("component_errors")) return;
  for (int k = 0; k < kNumComponentErrors; ++k) {
    Json& e = (*report)["component_errors"][componentNames()[static_cast<size_t>(k)]];
    setUncertaintyArrays(&e, b.component_u_a.col(k), b.component_u_b.col(k), b.component_k.col(k));
  }
}

}  // namespace rotacal
