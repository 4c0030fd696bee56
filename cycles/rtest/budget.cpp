#include "cycles/rtest/budget.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/report_envelope.hpp"
#include "core/units.hpp"

namespace rotacal {

bool rtestTypeA(const ContributorInfo& c) { return c.kind == ContributorKind::RtestSphereForm; }

/// The contributors that act on an R-test cycle as Type B (the touch cycles' probe, set-up and
/// piece contributors do not: the R-test has no probe and no piece).
bool rtestActsAsTypeB(const ContributorInfo& c) {
  switch (c.kind) {
    case ContributorKind::RtestSensorGain:
    case ContributorKind::RtestSensorDirection:
    case ContributorKind::RtestSphereOffset:
    case ContributorKind::RtestCycleDrift:
    case ContributorKind::LinearScale:
    case ContributorKind::LinearRandom:
    case ContributorKind::Squareness: return true;
    default: return false;
  }
}

namespace {

bool actsAsTypeB(const ContributorInfo& c) { return rtestActsAsTypeB(c); }

/// The commanded sphere positions of the plan (machine frame): the span of the linear axes.
void commandedSpan(const ProbePlan& plan, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  const Eigen::Vector3d nest = rtestNest_w(plan);
  *lo = Eigen::Vector3d::Constant(1e300);
  *hi = Eigen::Vector3d::Constant(-1e300);
  for (const auto& p : plan.points) {
    const Eigen::Vector3d q = T_m_w_nominal(plan.machine.kinematics, p.pose) * nest;
    *lo = lo->cwiseMin(q);
    *hi = hi->cwiseMax(q);
  }
}

}  // namespace

void drawRtest(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, int run, int only, RtestDraw* d) {
  *d = RtestDraw{};
  for (size_t i = 0; i < set.items.size(); ++i) {
    const Contributor& c = set.items[i];
    if (only >= 0 && static_cast<size_t>(only) != i) continue;
    if (!actsAsTypeB(*c.info)) continue;
    Rng rng(seed, contributorStream(*c.info, run));
    switch (c.info->kind) {
      case ContributorKind::RtestSensorGain:
        for (int a = 0; a < 3; ++a) d->sensor_response(a, a) += c.u[0] * rng.normal();
        break;
      case ContributorKind::RtestSensorDirection:
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            if (a != b) d->sensor_response(a, b) += c.u[0] * rng.normal();
        break;
      case ContributorKind::RtestSphereOffset:
        for (int a = 0; a < 3; ++a) d->sphere_offset_mm[a] = c.u[a] * rng.normal();
        break;
      case ContributorKind::RtestCycleDrift:
        for (int a = 0; a < 3; ++a) d->cycle_drift_mm[a] = c.u[a] * rng.normal();
        break;
      default: break;  // the linear axes, drawn together below
    }
  }
  Eigen::Vector3d lo, hi;
  commandedSpan(plan, &lo, &hi);
  d->linear = drawLinearAxes(set, only, lo, hi, seed, run, &d->linear_errors);
}

void applyRtestDraw(const ProbePlan& plan, const RtestDraw& d, Truth* truth, RtestTruthExtras* extras) {
  if (d.linear) truth->linear_axis_error = d.linear_errors.asFunction();
  extras->sensor_response = d.sensor_response * extras->sensor_response;
  extras->sphere_offset_m_mm += d.sphere_offset_mm;
  if (!d.cycle_drift_mm.isZero()) {
    const double T = std::max(1.0, rtestCycleTime_s(plan));
    const Eigen::Vector3d v = d.cycle_drift_mm / T;
    auto before = extras->sphere_drift_m_mm;
    extras->sphere_drift_m_mm = [v, before](double t) {
      return Eigen::Vector3d(v * t + (before ? before(t) : Eigen::Vector3d::Zero()));
    };
  }
}

Json rtestDrawJson(const RtestDraw& d) {
  auto r6 = [](double v) { return std::round(v * 1e6) / 1e6; };
  Json j;
  Json S = Json::array();
  for (int a = 0; a < 3; ++a) {
    Json row = Json::array();
    for (int b = 0; b < 3; ++b) row.push_back(r6((d.sensor_response(a, b) - (a == b ? 1.0 : 0.0)) * 1e6));
    S.push_back(row);
  }
  j["sensor_response_minus_identity_ppm_or_urad"] = S;
  j["sphere_offset_um"] = {r6(mmToUm(d.sphere_offset_mm.x())), r6(mmToUm(d.sphere_offset_mm.y())), r6(mmToUm(d.sphere_offset_mm.z()))};
  j["cycle_drift_um"] = {r6(mmToUm(d.cycle_drift_mm.x())), r6(mmToUm(d.cycle_drift_mm.y())), r6(mmToUm(d.cycle_drift_mm.z()))};
  if (d.linear) j["linear_axes"] = linearAxesRecord(d.linear_errors);
  return j;
}

UncertaintyBudget rtestBudget(const ProbePlan& plan, const RtestCycle& first, const RtestLocationFit& fit,
                              double sensor_sigma_um, const ContributorSet* contributors,
                              const RtestBudgetOptions& options) {
  options.validateOrThrow();
  const Kinematics k = plan.machine.kinematics;
  const auto& params = locationParameters(k);
  const int n = kNumLocationErrors;
  UncertaintyBudget b;
  Eigen::VectorXd f(n);  // internal -> report units
  for (int i = 0; i < n; ++i) {
    b.names.emplace_back(params[static_cast<size_t>(i)].name);
    b.units.emplace_back(reportUnit(params[static_cast<size_t>(i)].kind));
    f[i] = params[static_cast<size_t>(i)].kind == ParamKind::Length ? mmToUm(1.0) : radToMdeg(1.0);
  }
  b.cov_a = Eigen::MatrixXd::Zero(n, n);
  b.cov_b = Eigen::MatrixXd::Zero(n, n);
  if (!fit.identifiable) {
    b.type_a_source = "not evaluated: " + fit.why;
    b.type_b_source = "not evaluated: " + fit.why;
    return b;
  }
  const bool own = first.reset.has_value() && first.reread.has_value();
  const RtestLocationEstimator est = rtestLocationEstimator(plan, own);
  const Eigen::MatrixXd G8 = est.G.topRows(n);

  // The per-reading scatter declared: the sensors' noise and the sphere's form.
  const ContributorSplit split = contributors ? splitContributors(*contributors, rtestTypeA, actsAsTypeB) : ContributorSplit{};
  const double declared_mm2 = umToMm(sensor_sigma_um) * umToMm(sensor_sigma_um) + split.per_reading_mm2;
  const ContributorSet& type_b = split.type_b;
  const std::vector<std::string>& ignored = split.left_out;
  Truth truth0;
  truth0.errors.kinematics = k;
  truth0.errors.values = fit.value;
  RtestSimOptions so;
  so.noise_um = 0.0;
  so.cycles = 1;
  // Readings of the exact simulator with a draw, through the estimator: estimate - truth.
  auto estimate = [&](const RtestDraw& d, Eigen::VectorXd* y_out) {
    Truth t = truth0;
    RtestTruthExtras x;
    applyRtestDraw(plan, d, &t, &x);
    const RtestSeries s = simulateRtest(plan, t, x, so);
    const Eigen::VectorXd y = rtestLocationRows(plan, s.cycles.front(), own);
    if (y_out) *y_out = y;
    return Eigen::VectorXd(est.G * y);
  };

  // Type A (readingScatter): the residual also holds the part of the Type B contributors the
  // eight-error model cannot absorb (linear axes between poses, cross-talk), which u_B counts.
  std::vector<double> sys_um2;
  const int dof = fit.dof;
  if (!type_b.items.empty() && dof > 0)
    sys_um2 = contributorResidualVariances(200, options.seed, [&](std::uint64_t seed, int r) {
      RtestDraw d;
      drawRtest(plan, type_b, seed, r, -1, &d);
      Eigen::VectorXd y;
      const Eigen::VectorXd x = estimate(d, &y);
      return mmToUm(1.0) * mmToUm(1.0) * (y - est.A * x).squaredNorm() / dof;
    });
  const ReadingScatter scatter = readingScatter(mmToUm(1.0) * mmToUm(1.0) * declared_mm2,
                                                fit.residual_sd_um * fit.residual_sd_um, dof, sys_um2);
  const double sigma2 = umToMm(1.0) * umToMm(1.0) * scatter.variance_um2;
  b.cov_a = f.asDiagonal() * (sigma2 * G8 * G8.transpose()) * f.asDiagonal();
  b.type_a_source = fmt::format(
      "the per-reading scatter {:.3f} um ({}; declared: sensor noise and sphere form) through the location fit",
      std::sqrt(scatter.variance_um2), scatter.why);
  b.terms.push_back({"data", b.uA()});
  if (!typeBToRun(&b, contributors != nullptr, !type_b.items.empty(), "the R-test", " (docs/uncertainty.md, rtest)"))
    return b;
  runTypeB(&b, type_b, options, [&](std::uint64_t seed, int run, int c) -> Eigen::VectorXd {
    RtestDraw d;
    drawRtest(plan, type_b, seed, run, c, &d);
    const Eigen::VectorXd x = estimate(d, nullptr);
    return f.cwiseProduct(Eigen::VectorXd(x.head(n) - fit.value));
  });
  b.type_b_source = typeBDrawnSource(type_b.items.size(), *contributors,
                                     "the exact simulator of the cycle (full HTMs) around the identified errors and run "
                                     "through the location fit (linear in the readings)",
                                     options, leftOutNote("an R-test", ignored));
  return b;
}

namespace {

Eigen::MatrixXd asTilts(const Eigen::VectorXd& v, int tilts) { return Eigen::Map<const Eigen::MatrixXd>(v.data(), kRtestParams, tilts); }

}  // namespace

Eigen::MatrixXd RtestTiltBudget::uA() const { return asTilts(budget.uA(), tilts); }
Eigen::MatrixXd RtestTiltBudget::uB() const { return asTilts(budget.uB(), tilts); }
Eigen::MatrixXd RtestTiltBudget::uC() const { return asTilts(budget.uC(), tilts); }
Eigen::MatrixXd RtestTiltBudget::expanded() const { return asTilts(budget.expanded(), tilts); }
Eigen::MatrixXd RtestTiltBudget::coverageFactors() const { return asTilts(budget.coverageFactors(), tilts); }

RtestTiltBudget rtestTiltBudget(const ProbePlan& plan, const RtestCycle& first, const RtestAnalysis& a,
                                const RtestFitOptions& fit_options, const ContributorSet* contributors,
                                const RtestBudgetOptions& options) {
  options.validateOrThrow();
  if (a.cycles.empty()) throw std::invalid_argument("rtest tilt budget: no cycle analyzed");
  const Kinematics k = plan.machine.kinematics;
  const int nt = static_cast<int>(a.tilt_deg.size());
  const int n = kRtestParams * nt;
  RtestTiltBudget out;
  out.tilts = nt;
  UncertaintyBudget& b = out.budget;
  Eigen::VectorXd f(n);  // internal -> report units
  for (int i = 0; i < nt; ++i)
    for (int p = 0; p < kRtestParams; ++p) {
      b.names.push_back(fmt::format("{}@{:g}", rtestParameterName(k, p), a.tilt_deg[static_cast<size_t>(i)]));
      b.units.emplace_back(rtestParameterIsLength(p) ? "um" : "mdeg");
      f[kRtestParams * i + p] = rtestParameterIsLength(p) ? kUmPerMm : kMdegPerRad;
    }
  const RtestCycleFit& fit = a.cycles.front();
  b.cov_b = Eigen::MatrixXd::Zero(n, n);
  const ContributorSplit split =
      contributors ? splitContributors(*contributors, rtestTypeA, actsAsTypeB) : ContributorSplit{};
  Truth truth0;
  truth0.errors.kinematics = k;
  if (a.location.identifiable) truth0.errors.values = a.location.value;
  RtestSimOptions so;
  so.noise_um = 0.0;
  so.cycles = 1;
  // The per-tilt fit of the exact simulator's first cycle, read as the data were.
  auto fitOf = [&](const Truth& t, const RtestTruthExtras& x) -> RtestCycleFit {
    RtestSeries s = simulateRtest(plan, t, x, so);  // one cycle
    if (!first.reset || !first.reread)
      for (auto& c : s.cycles) c.reset = c.reread = std::nullopt;
    RtestFitOptions o = fit_options;
    o.screen = false;
    return analyzeRtest(plan, s.cycles, o).cycles.front();
  };
  auto perTilt = [&](const Truth& t, const RtestTruthExtras& x) -> Eigen::VectorXd {
    const RtestCycleFit c = fitOf(t, x);
    return f.cwiseProduct(Eigen::Map<const Eigen::VectorXd>(c.value.data(), n));
  };
  // Type A, the rule of the location fit (readingScatter): the per-tilt fit's residual also holds
  // what the Type B contributors leave in it (the linear axes between poses), which u_B counts.
  const double declared_um2 =
      fit_options.sensor_sigma_um * fit_options.sensor_sigma_um + mmToUm(1.0) * mmToUm(1.0) * split.per_reading_mm2;
  std::vector<double> sys_um2;
  if (!split.type_b.items.empty() && fit.dof > 0) {
    sys_um2 = contributorResidualVariances(100, options.seed, [&](std::uint64_t seed, int run) {
      RtestDraw d;
      drawRtest(plan, split.type_b, seed, run, -1, &d);
      Truth t = truth0;
      RtestTruthExtras x;
      applyRtestDraw(plan, d, &t, &x);
      return std::pow(fitOf(t, x).residual_sd_um, 2);
    });
  }
  const ReadingScatter scatter = readingScatter(declared_um2, fit.residual_sd_um * fit.residual_sd_um, fit.dof, sys_um2);
  const double sigma2 = umToMm(1.0) * umToMm(1.0) * scatter.variance_um2;
  // The fit's covariance is sigma_um^2 N^-1: rescaled to this per-reading scatter.
  const double fit_sigma2 = std::pow(umToMm(fit.sigma_um), 2);
  b.cov_a = fit_sigma2 > 0 ? Eigen::MatrixXd(sigma2 / fit_sigma2 * f.asDiagonal() * fit.cov * f.asDiagonal())
                           : Eigen::MatrixXd::Zero(n, n);
  b.type_a_source = fmt::format(
      "the first cycle's per-tilt fit (002 Eq. (6)): the per-reading scatter {:.3f} um ({}) through that fit",
      std::sqrt(scatter.variance_um2), scatter.why);
  b.terms.push_back({"data", b.uA()});
  if (!typeBToRun(&b, contributors != nullptr, !split.type_b.items.empty(), "the R-test",
                  " (docs/uncertainty.md, rtest)"))
    return out;
  const Eigen::VectorXd base = perTilt(truth0, RtestTruthExtras{});
  runTypeB(&b, split.type_b, options, [&](std::uint64_t seed, int run, int c) -> Eigen::VectorXd {
    RtestDraw d;
    drawRtest(plan, split.type_b, seed, run, c, &d);
    Truth t = truth0;
    RtestTruthExtras x;
    applyRtestDraw(plan, d, &t, &x);
    return perTilt(t, x) - base;
  });
  b.type_b_source = typeBDrawnSource(split.type_b.items.size(), *contributors,
                                     "the exact simulator of the cycle (full HTMs) around the identified location errors, "
                                     "the first cycle's readings run through the per-tilt fit",
                                     options, leftOutNote("an R-test", split.left_out));
  return out;
}

void addRtestTiltBudget(Json* report, const ProbePlan& plan, const RtestTiltBudget& b) {
  if (!report->contains("cycles") || (*report)["cycles"].empty()) return;
  const Eigen::MatrixXd ua = b.uA(), ub = b.uB(), k = b.coverageFactors();
  const Eigen::VectorXd k_normal = Eigen::VectorXd::Constant(b.tilts, kCoverageFactor);
  Json& cycles = (*report)["cycles"];
  for (size_t c = 0; c < cycles.size(); ++c) {
    Json& errors = cycles[c]["errors"];
    for (int p = 0; p < kRtestParams; ++p) {
      const std::string name = rtestParameterName(plan.machine.kinematics, p);
      if (!errors.contains(name)) continue;
      Json& e = errors[name];
      if (c == 0) {
        setUncertaintyArrays(&e, ua.row(p).transpose(), ub.row(p).transpose(), k.row(p).transpose());
        continue;
      }
      // A later cycle's Type A is its own fit's u. Its Type B is the first cycle's: the same
      // contributors on the same poses, around errors a few micrometres apart. No Monte Carlo
      // of its own to read k from: the normal k.
      Eigen::VectorXd own = Eigen::VectorXd::Zero(b.tilts);
      for (int i = 0; i < b.tilts && i < static_cast<int>(e["u"].size()); ++i) own[i] = e["u"][static_cast<size_t>(i)].get<double>();
      setUncertaintyArrays(&e, own, ub.row(p).transpose(), k_normal);
    }
  }
  if (report->contains("per_tilt_errors")) {
    Json& errors = (*report)["per_tilt_errors"]["errors"];
    for (int p = 0; p < kRtestParams; ++p) {
      const std::string name = rtestParameterName(plan.machine.kinematics, p);
      if (errors.contains(name))
        setUncertaintyArrays(&errors[name], ua.row(p).transpose(), ub.row(p).transpose(), k.row(p).transpose());
    }
  }
  if (report->contains("conventions"))
    (*report)["conventions"]["u"] =
        "u = u_c, the standard uncertainty (k = 1), with u_a (the data's), u_b (the declared contributors') and U = k u_c "
        "beside it; the first cycle's from its budget (per_tilt_uncertainty); a later cycle's u_a from its own fit, "
        "max(sensor repeatability, residual), including the first cycle's reference, its u_b the first cycle's and k = 2";
  (*report)["per_tilt_uncertainty"] = {{"type_a", b.budget.type_a_source},
                                       {"type_b", b.budget.type_b_source},
                                       {"coverage_factor", coverageFactorSource(b.budget)},
                                       {"where", "cycles[*].errors and per_tilt_errors: u (= u_c) u_a u_b u_c U k per tilt"}};
}

RtestDriftBudget rtestDriftBudget(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestAnalysis& a,
                                  const RtestFitOptions& fit_options, const ContributorSet* contributors) {
  RtestDriftBudget out;
  if (a.cycles.size() < 3) return out;
  const int nt = static_cast<int>(a.tilt_deg.size());
  Eigen::MatrixXd f(kRtestParams, nt);  // internal per s -> report units per h
  for (int p = 0; p < kRtestParams; ++p) f.row(p).setConstant((rtestParameterIsLength(p) ? kUmPerMm : kMdegPerRad) * 3600.0);
  out.u_a = a.rate_u.cwiseProduct(f);
  out.u_b = Eigen::MatrixXd::Zero(kRtestParams, nt);
  if (!contributors) {
    out.type_b_source = typeBNotDeclared();
    return out;
  }
  double u_gain = 0.0, u_direction = 0.0;
  std::vector<std::string> cancel;
  for (const auto& c : contributors->items) {
    if (c.info->kind == ContributorKind::RtestSensorGain) u_gain = c.u[0];
    else if (c.info->kind == ContributorKind::RtestSensorDirection) u_direction = c.u[0];
    else if (!rtestTypeA(*c.info)) cancel.emplace_back(c.info->id);
  }
  out.type_b_evaluated = true;
  // d rate / d S_ab: every reading (reset and re-read too) gets eps times its component b added
  // to its component a, the series is analyzed again.
  constexpr double kEps = 1e-4;
  for (int ra = 0; ra < 3; ++ra)
    for (int rb = 0; rb < 3; ++rb) {
      const double u = ra == rb ? u_gain : u_direction;
      if (u == 0.0) continue;
      std::vector<RtestCycle> moved = cycles;
      auto perturb = [&](RtestReading& r) { r.dq_w_mm[ra] += kEps * r.dq_w_mm[rb]; };
      for (auto& c : moved) {
        for (auto& r : c.readings) perturb(r);
        if (c.reset) perturb(*c.reset);
        if (c.reread) perturb(*c.reread);
      }
      RtestFitOptions o = fit_options;
      o.screen = false;
      const Eigen::MatrixXd d = (analyzeRtest(plan, moved, o).rate - a.rate) / kEps;
      out.u_b += (u * d.cwiseProduct(f)).cwiseAbs2();
    }
  out.u_b = out.u_b.cwiseSqrt();
  out.type_b_source = fmt::format(
      "the sensors' gain ({:g} %) and cross-talk ({:g} mrad) scale the drift they read: first-order propagation through "
      "the trend, each entry of the sensors' response perturbed in the measured series and re-analyzed{}",
      100.0 * u_gain, 1000.0 * u_direction,
      cancel.empty() ? std::string()
                     : fmt::format("; the same in every cycle, so cancelling in a rate: {}", fmt::join(cancel, ", ")));
  return out;
}

void addRtestDriftBudget(Json* report, const ProbePlan& plan, const RtestDriftBudget& b) {
  if (!report->contains("drift") || b.u_a.size() == 0) return;
  Json& drift = (*report)["drift"];
  const Eigen::VectorXd k = Eigen::VectorXd::Constant(b.u_a.cols(), kCoverageFactor);
  for (int p = 0; p < kRtestParams; ++p) {
    const std::string name = rtestParameterName(plan.machine.kinematics, p);
    if (!drift.contains(name)) continue;
    Json& e = drift[name];
    setUncertaintyArrays(&e, b.u_a.row(p).transpose(), b.u_b.row(p).transpose(), k);
    // First order, no distribution to read k from: one k for every rate, as before.
    e["k"] = kCoverageFactor;
  }
  (*report)["drift_uncertainty"] = {{"type_a", "the trend's own u: the cycles' u, widened by the scatter about the line"},
                                    {"type_b", b.type_b_source}};
}

}  // namespace rotacal
