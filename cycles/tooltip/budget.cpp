#include "cycles/tooltip/budget.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/units.hpp"

namespace rotacal {

bool tooltipTypeA(const ContributorInfo& c) {
  return c.kind == ContributorKind::LaserResolution || c.kind == ContributorKind::LaserSphereForm ||
         c.kind == ContributorKind::LaserLateralCoupling;
}

bool tooltipTypeB(const ContributorInfo& c) {
  switch (c.kind) {
    case ContributorKind::LaserAlignment:
    case ContributorKind::LinearScale:
    case ContributorKind::LinearRandom:
    case ContributorKind::Squareness: return true;
    default: return false;
  }
}

namespace {

/// The contributors that act on the tool-tip readings as Type B: the linear axes carry the pivot
/// (004 Sec. VII's machine positioning), and the beams' alignment. The touch and R-test ids have
/// no probe, piece or sensor nest here.
bool actsAsTypeB(const ContributorInfo& c) { return tooltipTypeB(c); }

int transverse(char axis) { return axis == 'A' ? 1 : 0; }  // Y for A, X for B
int unread(char axis) { return axis == 'A' ? 0 : 1; }      // the direction 004's laser does not read

int angleIndex(const std::vector<double>& angles, double a) {
  for (size_t j = 0; j < angles.size(); ++j)
    if (std::abs(angles[j] - a) < 1e-9) return static_cast<int>(j);
  throw std::invalid_argument("tooltip budget: a plan angle is not among the head's angles");
}

/// The budget's parameters: indices of the estimated angular errors (the fit's order), and dR.
struct Layout {
  std::vector<int> e;  // indices into the fit's angles
  bool dR = false;
  int size() const { return static_cast<int>(e.size()) + (dR ? 1 : 0); }
};

Layout layoutOf(const ProbePlan& plan, const TooltipAnalysis& a) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const std::vector<double>& angles = a.joint.angles_deg;
  // From the transverse reading alone the zero pose's error is fixed at 0 (the reference): not
  // estimated, so not budgeted.
  std::vector<bool> fixed(angles.size(), false);
  if (a.transverse_only)
    for (int r : tooltipReferences(plan)) {
      const Pose& p = plan.points[static_cast<size_t>(r)].pose;
      fixed[static_cast<size_t>(angleIndex(angles, o.axis == 'A' ? p.A : p.B))] = true;
    }
  Layout l;
  // An angle the fit has no value for (its readings left out by the screen, or unseen from the
  // transverse reading alone) is not estimated either.
  for (size_t j = 0; j < angles.size(); ++j)
    if (!fixed[j] && std::isfinite(a.joint.e_mdeg[j])) l.e.push_back(static_cast<int>(j));
  l.dR = !a.transverse_only;
  return l;
}

Eigen::VectorXd valuesOf(const Layout& l, const TooltipFit& f) {
  Eigen::VectorXd v(l.size());
  for (size_t i = 0; i < l.e.size(); ++i) v[static_cast<int>(i)] = f.e_mdeg[static_cast<size_t>(l.e[i])];
  if (l.dR) v[v.size() - 1] = f.dR_um;
  return v;
}

}  // namespace

void drawTooltip(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, int run, int only,
                 TooltipDraw* d) {
  *d = TooltipDraw{};
  for (size_t i = 0; i < set.items.size(); ++i) {
    const Contributor& c = set.items[i];
    if (only >= 0 && static_cast<size_t>(only) != i) continue;
    if (!actsAsTypeB(*c.info)) continue;
    if (c.info->kind == ContributorKind::LaserAlignment) {
      Rng rng(seed, contributorStream(*c.info, run));
      d->in_t = c.u[0] * rng.normal();
      d->out_t = c.u[0] * rng.normal();
      d->in_z = c.u[0] * rng.normal();
      d->out_z = c.u[0] * rng.normal();
    }  // the linear axes: drawn together below
  }
  Eigen::Vector3d lo, hi;
  triggerSpan(plan, &lo, &hi);  // the commanded pivot positions: where the linear axes are read
  d->linear = drawLinearAxes(set, only, lo, hi, seed, run, &d->linear_errors);
}

TooltipMachine tooltipMachineOf(const ProbePlan& plan, const TooltipDraw& draw) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const int ti = transverse(o.axis), ui = unread(o.axis);
  TooltipMachine m;
  if (draw.linear) m.pivot_error_mm = draw.linear_errors.asFunction();
  // The beams' directions: a tilt in the read plane is the cosine error plus cross-talk of the
  // other read component; a tilt out of it reads the unread component.
  m.beam_t = Eigen::Vector3d::Zero();
  m.beam_z = Eigen::Vector3d::Zero();
  m.beam_t[ti] = std::cos(draw.out_t) * std::cos(draw.in_t);
  m.beam_t[2] = std::cos(draw.out_t) * std::sin(draw.in_t);
  m.beam_t[ui] = std::sin(draw.out_t);
  m.beam_z[2] = std::cos(draw.out_z) * std::cos(draw.in_z);
  m.beam_z[ti] = std::cos(draw.out_z) * std::sin(draw.in_z);
  m.beam_z[ui] = std::sin(draw.out_z);
  return m;
}

Json tooltipDrawJson(const TooltipDraw& d) {
  auto r6 = [](double v) { return std::round(v * 1e6) / 1e6; };
  Json j;
  j["laser_alignment_urad"] = {{"transverse_beam_in_plane", r6(d.in_t * 1e6)},
                               {"transverse_beam_out_of_plane", r6(d.out_t * 1e6)},
                               {"z_beam_in_plane", r6(d.in_z * 1e6)},
                               {"z_beam_out_of_plane", r6(d.out_z * 1e6)}};
  if (d.linear) j["linear_axes"] = linearAxesRecord(d.linear_errors);
  return j;
}

TooltipRun simulateTooltipHead(const ProbePlan& plan, const TooltipHead& head, const TooltipDraw& draw, bool read_z,
                               double noise_um, Rng* rng) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  if (head.e_mdeg.size() != head.angles_deg.size())
    throw std::invalid_argument("tooltip head: one angular error per angle");
  const double r_true = o.radius_mm + umToMm(head.dR_um);
  std::vector<Eigen::Vector3d> devs;
  devs.reserve(plan.points.size());
  for (const auto& pt : plan.points) {
    // The head turns to the commanded angle plus its error at that angle; the linear axes put
    // the pivot at its command plus their error there; the tip hangs at the true R.
    Pose actual = pt.pose;
    double& th = o.axis == 'A' ? actual.A : actual.B;
    th += head.e_mdeg[static_cast<size_t>(angleIndex(head.angles_deg, th))] / 1000.0;  // mdeg -> deg
    Eigen::Vector3d pivot = pt.trigger_m_mm;
    if (draw.linear) pivot += draw.linear_errors.error(pt.trigger_m_mm);
    devs.push_back(pivot + tipOffset_m(degToRad(actual.A), degToRad(actual.B), r_true) - pt.contact_w_mm);
  }
  const TooltipMachine m = tooltipMachineOf(plan, draw);
  const Eigen::Vector3d& nt = m.beam_t;
  const Eigen::Vector3d& nz = m.beam_z;
  const std::vector<int> refs = tooltipReferences(plan);
  // The laser is zeroed on a reading of each sweep's zero pose, as noisy as any: drawn first, in
  // plan order, then every later reading of the sweep is its own less that one.
  const bool noisy = rng && noise_um > 0;
  std::vector<Eigen::Vector2d> zero_noise(plan.points.size(), Eigen::Vector2d::Zero());
  if (noisy)
    for (size_t k = 0; k < plan.points.size(); ++k)
      if (refs[k] == static_cast<int>(k)) {
        zero_noise[k].x() = noise_um * rng->normal();
        if (read_z) zero_noise[k].y() = noise_um * rng->normal();
      }
  TooltipRun run;
  run.reserve(plan.points.size());
  for (size_t k = 0; k < plan.points.size(); ++k) {
    const Eigen::Vector3d rel = mmToUm(1.0) * (devs[k] - devs[static_cast<size_t>(refs[k])]);
    TooltipReading r;
    r.angle_deg = o.axis == 'A' ? plan.points[k].pose.A : plan.points[k].pose.B;
    r.t_um = nt.dot(rel);
    r.z_um = read_z ? nz.dot(rel) : std::numeric_limits<double>::quiet_NaN();
    if (noisy && refs[k] != static_cast<int>(k)) {  // the zero reading is 0 by construction
      const Eigen::Vector2d& zero = zero_noise[static_cast<size_t>(refs[k])];
      r.t_um += noise_um * rng->normal() - zero.x();
      if (read_z) r.z_um += noise_um * rng->normal() - zero.y();
    }
    run.push_back(r);
  }
  return run;
}

Eigen::VectorXd tooltipBudgetValues(const TooltipAnalysis& a, const UncertaintyBudget& b) {
  Eigen::VectorXd v(b.size());
  for (int i = 0; i < b.size(); ++i) {
    if (b.names[static_cast<size_t>(i)] == "dR") {
      v[i] = a.joint.dR_um;
      continue;
    }
    v[i] = std::numeric_limits<double>::quiet_NaN();
    for (size_t j = 0; j < a.joint.angles_deg.size(); ++j)
      if (b.names[static_cast<size_t>(i)].substr(3) == fmt::format("{:g}", a.joint.angles_deg[j])) v[i] = a.joint.e_mdeg[j];
  }
  return v;
}

UncertaintyBudget tooltipBudget(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const TooltipAnalysis& a,
                                double declared_noise_um, const ContributorSet* contributors,
                                const TooltipBudgetOptions& options) {
  options.validateOrThrow();
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const TooltipFit& fit = a.joint;
  const int J = static_cast<int>(fit.angles_deg.size());
  const Layout l = layoutOf(plan, a);
  const int n = l.size();
  UncertaintyBudget b;
  Eigen::VectorXd f(n);  // internal (rad, mm) -> report units (mdeg, um)
  for (size_t i = 0; i < l.e.size(); ++i) {
    b.names.push_back(fmt::format("e_{}{:g}", o.axis, fit.angles_deg[static_cast<size_t>(l.e[i])]));
    b.units.emplace_back("mdeg");
    f[static_cast<int>(i)] = radToMdeg(1.0);
  }
  if (l.dR) {
    b.names.emplace_back("dR");
    b.units.emplace_back("um");
    f[n - 1] = mmToUm(1.0);
  }

  // The fit's map at its solution: sigma^2 (J^T J)^-1 over the estimated parameters, on the
  // components actually read (a transverse-only file has no Z rows).
  Eigen::VectorXd x = Eigen::VectorXd::Zero(J + 1);
  for (int j = 0; j < J; ++j)
    x[j] = std::isfinite(fit.e_mdeg[static_cast<size_t>(j)]) ? mdegToRad(fit.e_mdeg[static_cast<size_t>(j)]) : 0.0;
  x[J] = l.dR ? umToMm(fit.dR_um) : 0.0;
  const TooltipModelEval ev = evaluateTooltipModel(plan, runs, x);
  const std::vector<int> refs = tooltipReferences(plan);
  std::vector<int> rows;
  std::vector<size_t> zero_of_row;  // which laser zero each row reads against: (run, zero reading, direction)
  int obs = 0;
  for (size_t ri = 0; ri < runs.size(); ++ri)
    for (size_t k = 0; k < runs[ri].size(); ++k) {
      const TooltipRun& run = runs[ri];
      if (refs[k] == static_cast<int>(k)) continue;
      const size_t zero = (ri * plan.points.size() + static_cast<size_t>(refs[k])) * 2;
      if (std::isfinite(run[k].t_um)) {  // NaN: left out by the screen
        rows.push_back(2 * obs);
        zero_of_row.push_back(zero);
      }
      if (std::isfinite(run[k].z_um)) {
        rows.push_back(2 * obs + 1);
        zero_of_row.push_back(zero + 1);
      }
      ++obs;
    }
  std::vector<int> cols(l.e.begin(), l.e.end());
  if (l.dR) cols.push_back(J);
  Eigen::MatrixXd jr(static_cast<int>(rows.size()), n);
  for (size_t r = 0; r < rows.size(); ++r)
    for (int c = 0; c < n; ++c) jr(static_cast<int>(r), c) = ev.J_model_x(rows[r], cols[static_cast<size_t>(c)]);
  // Column scaling: rad and mm columns differ by R (about 1e3).
  const Eigen::VectorXd scale = jr.colwise().norm().transpose();
  const Eigen::MatrixXd js = jr * scale.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd cov_unit = scale.cwiseInverse().asDiagonal() *
                                   (js.transpose() * js).ldlt().solve(Eigen::MatrixXd::Identity(n, n)) *
                                   scale.cwiseInverse().asDiagonal();  // per um^2 of reading variance
  // The laser's zero (cycles/tooltip/noise.hpp): it is read with the per-reading scatter, and
  // every value of its sweep and direction in that run is read less it, so those values share
  // one error. Through the fit's map A = (J^T J)^-1 J^T it adds A Z A^T per um^2 (Z = 1 between
  // the values of one zero), and it leaves tr(M Z) in the residual (M = I - J A) beside the
  // dof of the independent part: the residual's variance per dof is the reading's times kappa.
  const Eigen::MatrixXd A =
      scale.cwiseInverse().asDiagonal() * (js.transpose() * js).ldlt().solve(js.transpose());  // params x rows
  Eigen::MatrixXd cov_zero_unit = Eigen::MatrixXd::Zero(n, n);
  double trace_MZ = 0.0;
  {
    std::vector<size_t> zeros = zero_of_row;
    std::sort(zeros.begin(), zeros.end());
    zeros.erase(std::unique(zeros.begin(), zeros.end()), zeros.end());
    for (size_t z : zeros) {
      Eigen::VectorXd ones = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rows.size()));
      for (size_t r = 0; r < rows.size(); ++r)
        if (zero_of_row[r] == z) ones[static_cast<Eigen::Index>(r)] = 1.0;
      const Eigen::VectorXd a_z = A * ones;
      cov_zero_unit += a_z * a_z.transpose();
      trace_MZ += ones.sum() - ones.dot(jr * a_z);
    }
  }
  const double independent_dof = static_cast<double>(rows.size()) - n;
  const double kappa = independent_dof > 0 ? 1.0 + trace_MZ / independent_dof : 1.0;

  // The per-reading scatter declared: the laser's own error (laser_resolution, else the plan's
  // laser_noise_um: the same 004 figure), the sphere's form, lateral coupling.
  const ContributorSplit split = contributors ? splitContributors(*contributors, tooltipTypeA, actsAsTypeB) : ContributorSplit{};
  double declared_um2 = split.per_reading_mm2 * kUmPerMm * kUmPerMm;
  const bool resolution_declared =
      contributors && std::any_of(contributors->items.begin(), contributors->items.end(),
                                  [](const Contributor& c) { return c.info->kind == ContributorKind::LaserResolution; });
  const ContributorSet& type_b = split.type_b;
  const std::vector<std::string>& ignored = split.left_out;
  if (!resolution_declared) declared_um2 += declared_noise_um * declared_noise_um;

  TooltipHead truth;
  truth.angles_deg = fit.angles_deg;
  for (int j = 0; j < J; ++j)
    truth.e_mdeg.push_back(std::isfinite(fit.e_mdeg[static_cast<size_t>(j)]) ? fit.e_mdeg[static_cast<size_t>(j)] : 0.0);
  truth.dR_um = l.dR ? fit.dR_um : 0.0;
  TooltipFitOptions fo;
  fo.fit_pivot_length = l.dR;
  const Eigen::VectorXd truth_v = valuesOf(l, fit);
  // Readings of the exact geometry with a draw, through the same fit.
  auto estimate = [&](const TooltipDraw& d) {
    const TooltipRun run = simulateTooltipHead(plan, truth, d, !a.transverse_only, 0.0, nullptr);
    return fitTooltip(plan, {run}, fo);
  };

  // Type A (readingScatter): the residual also holds the part of the Type B contributors the
  // model cannot absorb (the linear axes between poses), which u_B counts.
  std::vector<double> sys_um2;
  if (!type_b.items.empty() && fit.dof > 0) {
    sys_um2 = contributorResidualVariances(200, options.seed, [&](std::uint64_t seed, int r) {
      TooltipDraw d;
      drawTooltip(plan, type_b, seed, r, -1, &d);
      const TooltipFit e = estimate(d);
      return e.dof > 0 ? e.rss_um2 / e.dof : 0.0;
    });
  }
  const double s_obs = fit.dof > 0 ? fit.sigma_um : 0.0;
  // The residual and the contributors' share of it on the per-reading scale (kappa above).
  for (double& v : sys_um2) v /= kappa;
  const ReadingScatter scatter = readingScatter(declared_um2, s_obs * s_obs / kappa, fit.dof, sys_um2);
  const double sigma2 = scatter.variance_um2;
  Eigen::MatrixXd cov_a = f.asDiagonal() * (sigma2 * (cov_unit + cov_zero_unit)) * f.asDiagonal();
  b.type_a_source = fmt::format(
      "the per-reading scatter {:.3f} um ({}; declared: laser, sphere form, lateral coupling) through the fit, "
      "each reading's own and its sweep's laser zero's",
      std::sqrt(sigma2), scatter.why);
  // Repeats: a parameter whose repeats scatter more than that (drift between runs, a set-up that
  // moved) takes the standard error of the repeats' mean instead; correlations kept by scaling.
  if (runs.size() >= 2) {
    std::vector<Eigen::VectorXd> each;
    for (const auto& run : runs) each.push_back(valuesOf(l, fitTooltip(plan, {run}, fo)));
    b.type_a_source += raiseToRepeatScatter(&cov_a, each);
  }
  b.cov_a = cov_a;
  b.cov_b = Eigen::MatrixXd::Zero(n, n);
  b.terms.push_back({"data", b.uA()});
  if (!typeBToRun(&b, contributors != nullptr, !type_b.items.empty(), "the tool-tip readings",
                  " (docs/uncertainty.md, tooltip)"))
    return b;
  runTypeB(&b, type_b, options, [&](std::uint64_t seed, int run, int c) -> Eigen::VectorXd {
    TooltipDraw d;
    drawTooltip(plan, type_b, seed, run, c, &d);
    return valuesOf(l, estimate(d)) - truth_v;
  });
  b.type_b_source = typeBDrawnSource(type_b.items.size(), *contributors,
                                     "the exact head geometry around the identified errors (the pivot where the linear "
                                     "axes put it, the beams as aligned) and run through the tooltip fit",
                                     options, leftOutNote("the tool-tip readings", ignored));
  return b;
}

}  // namespace rotacal
