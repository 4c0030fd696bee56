#include "cycles/probe_qual/analyze.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/contributor_draw.hpp"
#include "core/errors.hpp"
#include "core/report_envelope.hpp"
#include "core/least_squares.hpp"
#include "core/statistics.hpp"
#include "core/uncertainty_budget.hpp"
#include "core/units.hpp"
#include "cycles/probe_qual/plan.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

namespace {

constexpr double kRoundingUm = 1e-6;

/// The two-sided Student t quantile: the t with P(|T| > t) = p at nu degrees of freedom
/// (bisection on the survival function, which is monotone).
double studentTwoSidedQuantile(double p, double nu) {
  double lo = 0.0, hi = 1.0;
  while (studentTwoSided(hi, nu) > p) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (studentTwoSided(mid, nu) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// Each kept touch's externally studentized deviation from its own repeats (ProbeQualScreen), 0
/// where it is no candidate; `residual` in um along the approach.
std::vector<double> studentizedDeviations(const std::vector<double>& residual, const std::vector<int>& group, int groups,
                                          const std::vector<char>& keep, std::vector<double>* deviation, int* dof) {
  std::vector<double> sum(static_cast<size_t>(groups), 0.0);
  std::vector<int> count(static_cast<size_t>(groups), 0);
  for (size_t j = 0; j < residual.size(); ++j)
    if (keep[j]) sum[static_cast<size_t>(group[j])] += residual[j], ++count[static_cast<size_t>(group[j])];
  double ss = 0.0;
  int kept = 0, used_groups = 0;
  deviation->assign(residual.size(), 0.0);
  for (size_t j = 0; j < residual.size(); ++j) {
    if (!keep[j]) continue;
    const auto g = static_cast<size_t>(group[j]);
    (*deviation)[j] = residual[j] - sum[g] / count[g];
    ss += (*deviation)[j] * (*deviation)[j];
    ++kept;
  }
  for (int c : count) used_groups += c > 0 ? 1 : 0;
  *dof = kept - used_groups;
  std::vector<double> t(residual.size(), 0.0);
  if (*dof < 2) return t;
  for (size_t j = 0; j < residual.size(); ++j) {
    const int n = count[static_cast<size_t>(group[j])];
    if (!keep[j] || n < 3) continue;
    const double one_less_h = 1.0 - 1.0 / n;
    const double e = (*deviation)[j];
    // A scatter below 1e-6 um is the rounding of mm coordinates (1e-16 of 100 mm is 1e-8 um),
    // not a probe: noise-free data must not make rounding a chip.
    const double s2 = std::max(kRoundingUm * kRoundingUm, std::max(0.0, ss - e * e / one_less_h) / (*dof - 1));
    t[j] = e / std::sqrt(s2 * one_less_h);
  }
  return t;
}

}  // namespace

std::string ProbeQualScreen::text() const {
  const std::string rule = fmt::format("{:.2f} (Student t, {} dof, at {:g} / {} touches)", threshold_t, dof, alpha, touches);
  if (too_many)
    return fmt::format("outlier screen: {} of {} touches beyond {} even with the worst left out: more than a few chips "
                       "(a drift, a loose stylus?); none excluded",
                       beyond, touches, rule);
  if (excluded.empty()) return fmt::format("outlier screen: no touch beyond {}", rule);
  std::string list;
  for (const auto& e : excluded)
    list += fmt::format("{}point {} ({}, repeat {}{}: {:+.2f} um, t {:.1f})", list.empty() ? "" : ", ", e.point_id,
                        e.direction, e.repeat + 1, e.run > 0 ? fmt::format(" of run {}", e.run + 1) : std::string(),
                        e.deviation_um, std::abs(e.t));
  return fmt::format("outlier screen: excluded {} of {} touches beyond {} (a chip or dirt on the sphere; the "
                     "repeatability and the fit without them): {}",
                     excluded.size(), touches, rule, list);
}

ProbeQualification qualifyProbe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                const ProbeQualOptions& options) {
  const ProbeQualLayout l = probeQualLayoutOf(plan);
  const auto touches = l.touches();
  const auto approaches = l.approaches();
  const auto names = l.approachNames();
  const auto G = static_cast<int>(touches.size());  // touches per repeat
  const int A = l.azimuths;                         // horizontal approaches; approach A is the top
  const std::string source = runs.empty() ? std::string("results") : runs.front().source;
  ProbeQualification q;
  q.directions = A + 1;
  if (!(options.alpha > 0 && options.alpha < 1) || !(options.max_fraction >= 0 && options.max_fraction < 0.5))
    throw std::invalid_argument("probe_qual screen: alpha must be in (0, 1) and max_fraction in [0, 0.5)");
  std::vector<Eigen::Vector3d> t, u;
  std::vector<int> approach_of, run_of;
  for (const PlannedTrigger& pt : triggersInPlanOrder(plan, runs)) {
    const ProbePoint& p = plan.points[pt.point_index];
    t.push_back(pt.trigger->position_m_mm);
    u.push_back(p.approach_m);
    q.touch_of.push_back(p.target - 1);
    approach_of.push_back(touches[static_cast<size_t>(p.target - 1)].approach);
    q.repeat_of.push_back(pt.run * l.repeats + static_cast<int>(pt.point_index) / G);
    q.t_s.push_back(pt.t_s);
    q.point_index.push_back(static_cast<int>(pt.point_index));
    run_of.push_back(pt.run);
  }
  auto N = static_cast<Eigen::Index>(t.size());

  // The horizontal pretravel in the span that a centre offset cannot mimic: an orthonormal basis
  // B of the azimuths' space less their cos and sin (the mean and the higher harmonics).
  Eigen::MatrixXd CS(2, A);
  for (int k = 0; k < A; ++k) {
    const double th = degToRad(360.0 * k / A);
    CS(0, k) = std::cos(th);
    CS(1, k) = std::sin(th);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(CS, Eigen::ComputeFullV);
  const Eigen::MatrixXd B = svd.matrixV().rightCols(A - 2);
  const Eigen::Index nb = A - 2, nx = 3 + nb + 1;
  q.parameter_names = {"sphere X", "sphere Y", "sphere Z"};
  for (Eigen::Index k = 0; k < nb; ++k) q.parameter_names.push_back(fmt::format("horizontal pretravel basis {}", k + 1));
  q.parameter_names.push_back("top pretravel");
  const double rho0 = l.radius_mm + plan.machine.probe.ball_radius_mm();
  const auto pretravelOf = [&](const Eigen::VectorXd& x, int a) {
    return a == A ? x[nx - 1] : B.row(a).dot(x.segment(3, nb));
  };
  // r_j = (|t_j - p u_j - c| - (R + r)) / |m_j . u_j|: exact (the trigger less its pretravel lies
  // on the sphere grown by the ball), in mm along the approach.
  const auto model = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    r.resize(N);
    if (J) J->setZero(N, nx);
    for (Eigen::Index j = 0; j < N; ++j) {
      const auto js = static_cast<size_t>(j);
      const int a = approach_of[js];
      const Eigen::Vector3d d = t[js] - pretravelOf(x, a) * u[js] - x.head<3>();
      const Eigen::Vector3d m = d.normalized();
      const double w = 1.0 / std::max(1e-6, std::abs(m.dot(u[js])));
      r[j] = w * (d.norm() - rho0);
      if (J) {
        J->row(j).head<3>() = -w * m.transpose();
        const double dp = -w * m.dot(u[js]);
        if (a == A) (*J)(j, nx - 1) = dp;
        else J->row(j).segment(3, nb) = dp * B.row(a);
      }
    }
  };
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(nx);
  // The centre as the axes read it (a head's reading is the pivot, the ball L below it).
  x0.head<3>() = T_m_w_nominal(plan.machine.kinematics, Pose{}) * l.center_w_mm - ballFromAxes_m(plan.machine, Pose{});
  LeastSquaresResult fit = solveLeastSquares(model, x0);
  if (!fit.summary.usable())
    throw InputError(source, 0, "the probe qualification's fit did not converge: " + fit.summary.briefReport());

  // The screen on the repeats: a touch's deviation from its own repeats does not depend on the
  // fit (every repeat of a touch has the same model row), so the first fit's residuals serve.
  {
    Eigen::VectorXd r0;
    model(fit.x, r0, nullptr);
    std::vector<double> res(static_cast<size_t>(N));
    for (Eigen::Index j = 0; j < N; ++j) res[static_cast<size_t>(j)] = mmToUm(r0[j]);
    std::vector<char> keep(static_cast<size_t>(N), 1);
    std::vector<size_t> excluded_at;
    std::vector<double> dev;
    int dof = 0;
    std::vector<double> ts = studentizedDeviations(res, q.touch_of, G, keep, &dev, &dof);
    ProbeQualScreen& sc = q.screen;
    sc.alpha = options.alpha;
    sc.max_fraction = options.max_fraction;
    sc.touches = static_cast<int>(N);
    sc.dof = dof - 1;
    if (sc.dof >= 1) {
      sc.threshold_t = studentTwoSidedQuantile(options.alpha / static_cast<double>(N), sc.dof);
      const int cap = static_cast<int>(std::floor(options.max_fraction * static_cast<double>(N)));
      while (true) {
        size_t worst = 0;
        for (size_t j = 1; j < ts.size(); ++j)
          if (std::abs(ts[j]) > std::abs(ts[worst])) worst = j;
        if (!(std::abs(ts[worst]) > sc.threshold_t)) break;
        if (static_cast<int>(sc.excluded.size()) >= cap) {
          // Still beyond with the most a few chips can be left out: not chips. All data stay.
          sc.too_many = true;
          sc.beyond = static_cast<int>(std::count_if(ts.begin(), ts.end(), [&](double v) { return std::abs(v) > sc.threshold_t; }));
          sc.excluded.clear();
          excluded_at.clear();
          std::fill(keep.begin(), keep.end(), 1);
          break;
        }
        const int pi = q.point_index[worst];
        excluded_at.push_back(worst);
        sc.excluded.push_back({run_of[worst], q.repeat_of[worst] - run_of[worst] * l.repeats,
                               plan.points[static_cast<size_t>(pi)].id, touches[static_cast<size_t>(q.touch_of[worst])].name,
                               dev[worst], ts[worst]});
        keep[worst] = 0;
        ts = studentizedDeviations(res, q.touch_of, G, keep, &dev, &dof);
      }
    }
    // What each excluded touch deviates by from its repeats that stayed.
    for (size_t k = 0; k < sc.excluded.size(); ++k) {
      const size_t at = excluded_at[k];
      double sum = 0.0;
      int n = 0;
      for (size_t j = 0; j < keep.size(); ++j)
        if (keep[j] && q.touch_of[j] == q.touch_of[at]) sum += res[j], ++n;
      if (n > 0) sc.excluded[k].deviation_um = res[at] - sum / n;
    }
    if (!sc.excluded.empty()) {
      // The fit and everything after it on the kept touches.
      const auto filter = [&keep](auto& v) {
        size_t k = 0;
        for (size_t j = 0; j < v.size(); ++j)
          if (keep[j]) v[k++] = v[j];
        v.resize(k);
      };
      filter(t);
      filter(u);
      filter(approach_of);
      filter(run_of);
      filter(q.touch_of);
      filter(q.repeat_of);
      filter(q.t_s);
      filter(q.point_index);
      N = static_cast<Eigen::Index>(t.size());
      fit = solveLeastSquares(model, fit.x);
      if (!fit.summary.usable())
        throw InputError(source, 0, "the probe qualification's fit without the excluded touches did not converge: " +
                                        fit.summary.briefReport());
    }
  }
  q.touches = static_cast<int>(N);
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  model(fit.x, r, &J);
  q.J_weighted = J;
  q.centre_m_mm = fit.x.head<3>();
  for (Eigen::Index j = 0; j < N; ++j) {
    q.residuals_um.push_back(mmToUm(r[j]));
    q.normals.push_back((t[static_cast<size_t>(j)] - fit.x.head<3>()).normalized());
  }

  // Repeatability: each touch of the repeat against its own repeats (the fit is the same for
  // all of them to within the pretravel's second order), in um along the approach.
  std::vector<double> mean(static_cast<size_t>(G), 0.0);
  std::vector<int> count(static_cast<size_t>(G), 0);
  for (Eigen::Index j = 0; j < N; ++j) {
    mean[static_cast<size_t>(q.touch_of[static_cast<size_t>(j)])] += r[j];
    ++count[static_cast<size_t>(q.touch_of[static_cast<size_t>(j)])];
  }
  for (int g = 0; g < G; ++g) mean[static_cast<size_t>(g)] /= std::max(1, count[static_cast<size_t>(g)]);
  double ss = 0.0;
  for (Eigen::Index j = 0; j < N; ++j) ss += std::pow(r[j] - mean[static_cast<size_t>(q.touch_of[static_cast<size_t>(j)])], 2);
  q.dof = static_cast<int>(N) - static_cast<int>(std::count_if(count.begin(), count.end(), [](int c) { return c > 0; }));
  if (q.dof < 1) throw InputError(source, 0, "every touch needs at least 2 repeats for a repeatability");
  q.repeatability_um = mmToUm(std::sqrt(ss / q.dof));
  q.repeatability_lo_um = q.repeatability_um * std::sqrt(q.dof / chiSquareUpperQuantile(0.025, q.dof));
  q.repeatability_hi_um = q.repeatability_um * std::sqrt(q.dof / chiSquareUpperQuantile(0.975, q.dof));

  // u_A: the repeatability through the fit's covariance (per unit variance of the weighted rows).
  const Eigen::MatrixXd cov = std::pow(umToMm(q.repeatability_um), 2) * fit.covariance;
  const auto uOf = [&](const Eigen::VectorXd& g) { return mmToUm(std::sqrt(std::max(0.0, g.dot(cov * g)))); };
  // u_B: the declared linear axes move each touch's reading along its approach by their error
  // where it is read (probeAxesCovariance: scale, squareness and random nodes, to first order),
  // the same in every repeat, so the repeats cannot see it. Over the sphere's few centimetres the
  // random nodes (000 Eq. (22): 2 um every 20-50 mm on 000 Table 5's machine) differ between
  // opposite contacts, which the fit reads as pretravel: without this term a machine as its
  // contributors file declares it gets a pretravel "significant" by what its axes do. The axes'
  // error e at a touch puts its reading on the sphere moved by -e, so its weighted row moves by
  // -w m . e: what it reads of e is w m, the contact normal over |m . u|, not the approach (above
  // the equator a horizontal approach reads the vertical error too, tan(latitude) of it, which
  // the sphere's height then takes up). The parameters move by (J^T J)^-1 J^T of the rows.
  Eigen::MatrixXd covB = Eigen::MatrixXd::Zero(nx, nx);
  if (options.declared) {
    ContributorSet linear;
    linear.node_spacing_min_mm = options.declared->node_spacing_min_mm;
    linear.node_spacing_max_mm = options.declared->node_spacing_max_mm;
    std::vector<std::string> ids;
    for (const Contributor& c : options.declared->items)
      if (c.info && isLinearAxisContributor(*c.info) && c.u.cwiseAbs().maxCoeff() > 0) {
        linear.items.push_back(c);
        ids.push_back(std::string(c.info->id));
      }
    if (!linear.items.empty()) {
      std::vector<Eigen::Vector3d> reads(static_cast<size_t>(N));
      for (size_t j = 0; j < reads.size(); ++j)
        reads[j] = q.normals[j] / std::max(1e-6, std::abs(q.normals[j].dot(u[j])));
      const Eigen::MatrixXd S = probeAxesCovariance(linear, isLinearAxisContributor, t, reads);
      const Eigen::MatrixXd K = (J.transpose() * J).ldlt().solve(J.transpose());
      covB = K * S * K.transpose();
      q.type_b_source = fmt::format("the declared linear axes ({}{}) at each touch, the same in every repeat, through "
                                    "the fit to first order",
                                    fmt::join(ids, ", "), options.declared->file.empty() ? "" : ", " + options.declared->file);
    }
  }
  const auto uBOf = [&](const Eigen::VectorXd& g) { return mmToUm(std::sqrt(std::max(0.0, g.dot(covB * g)))); };
  double lo = 1e300, hi = -1e300, sum = 0.0, sum2 = 0.0;
  Eigen::VectorXd g_mean = Eigen::VectorXd::Zero(nx);
  for (int a = 0; a <= A; ++a) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(nx);
    if (a == A) g[nx - 1] = 1.0;
    else g.segment(3, nb) = B.row(a).transpose();
    DirectionPretravel p;
    p.name = names[static_cast<size_t>(a)];
    p.approach = approaches[static_cast<size_t>(a)];
    p.pretravel_um = mmToUm(pretravelOf(fit.x, a));
    p.u_a_um = uOf(g);
    p.u_b_um = uBOf(g);
    p.u_um = std::hypot(p.u_a_um, p.u_b_um);
    for (int ap : approach_of) p.touches += ap == a;
    if (a < A) {
      lo = std::min(lo, p.pretravel_um);
      hi = std::max(hi, p.pretravel_um);
      sum += p.pretravel_um;
      sum2 += p.pretravel_um * p.pretravel_um;
      g_mean += g / A;
    }
    q.by_direction.push_back(p);
  }
  q.mean_pretravel_um = sum / A;
  q.u_a_mean_pretravel_um = uOf(g_mean);
  q.u_b_mean_pretravel_um = uBOf(g_mean);
  q.u_mean_pretravel_um = std::hypot(q.u_a_mean_pretravel_um, q.u_b_mean_pretravel_um);
  q.lobing_range_um = hi - lo;
  q.lobing_rms_um = std::sqrt(std::max(0.0, sum2 / A - q.mean_pretravel_um * q.mean_pretravel_um));
  // E[rms^2] of a probe without lobing: trace(H C H) / A, C the horizontal pretravels' covariance
  // (the repeats' scatter and the declared linear axes: neither is the probe's) and H the centring.
  const Eigen::MatrixXd C = B * (cov + covB).block(3, 3, nb, nb) * B.transpose();
  const Eigen::MatrixXd H = Eigen::MatrixXd::Identity(A, A) - Eigen::MatrixXd::Constant(A, A, 1.0 / A);
  q.lobing_rms_noise_um = mmToUm(std::sqrt(std::max(0.0, (H * C * H).trace() / A)));
  q.lobing_rms_net_um = std::sqrt(std::max(0.0, q.lobing_rms_um * q.lobing_rms_um - q.lobing_rms_noise_um * q.lobing_rms_noise_um));
  q.effective_ball_diameter_mm = plan.machine.probe.ball_diameter_mm - 2.0 * umToMm(q.mean_pretravel_um);
  return q;
}

Json probeQualReportJson(const ProbePlan& plan, const ProbeQualification& q, const std::vector<std::string>& files) {
  Json j = documentEnvelope("rotacal-report/1", plan, files);
  j["method"] = "sphere_fit_by_direction";
  j["repeatability"] = {{"value", round6(q.repeatability_um)},
                        {"unit", "um"},
                        {"dof", q.dof},
                        {"interval_95", {round6(q.repeatability_lo_um), round6(q.repeatability_hi_um)}},
                        {"description", "pooled sd of each direction's repeats about their own mean (ISO 230-10's "
                                        "unidirectional repeatability of the probing system)"}};
  j["mean_pretravel"] = {{"value", round6(q.mean_pretravel_um)},
                         {"u", round6(q.u_mean_pretravel_um)},
                         {"unit", "um"},
                         {"description", "over the horizontal approaches: how much smaller the probe's effective "
                                         "radius is than the nominal (the sphere's calibrated radius taken as exact)"}};
  Json dirs = Json::array();
  for (const auto& p : q.by_direction)
    dirs.push_back({{"direction", p.name},
                    {"approach", {round6(p.approach.x()), round6(p.approach.y()), round6(p.approach.z())}},
                    {"pretravel", round6(p.pretravel_um)},
                    {"u", round6(p.u_um)},
                    {"unit", "um"},
                    {"touches", p.touches}});
  j["pretravel_by_direction"] = dirs;
  // u means u_c in every report: u_A from the repeats, u_B from the declared linear axes.
  setUncertaintyFields(&j["mean_pretravel"], q.u_a_mean_pretravel_um, q.u_b_mean_pretravel_um, kCoverageFactor);
  for (size_t i = 0; i < q.by_direction.size(); ++i)
    setUncertaintyFields(&j["pretravel_by_direction"][i], q.by_direction[i].u_a_um, q.by_direction[i].u_b_um, kCoverageFactor);
  const bool type_b = !q.type_b_source.empty();
  j["uncertainty"] = {{"coverage_probability", round6(kCoverageProbability)},
                      {"coverage_factor", fmt::format("k = {:g}, the distribution taken as normal (no Monte Carlo distribution)",
                                                      kCoverageFactor)},
                      {"type_a", "the repeatability through the fit's covariance (the pooled scatter of the repeats)"},
                      {"type_b", type_b ? q.type_b_source
                                        : std::string("not evaluated: no linear axis declared (the qualification measures "
                                                      "the probe's own contributors, repeatability and pretravel), so u_c = "
                                                      "u_A, the data's scatter only")},
                      {"type_b_evaluated", type_b}};
  j["pretravel_note"] = "along the approach, late triggers positive; the horizontal pattern's first harmonic (cos and "
                        "sin of the azimuth) is a centre offset and is in the sphere's centre";
  j["lobing"] = {{"range", round6(q.lobing_range_um)},
                 {"rms", round6(q.lobing_rms_um)},
                 {"rms_expected_from_noise", round6(q.lobing_rms_noise_um)},
                 {"rms_net", round6(q.lobing_rms_net_um)},
                 {"unit", "um"},
                 {"description", "the horizontal approaches' pretravel about its mean; rms_net is the rms less what "
                                 "the repeatability and the declared linear axes give it (in quadrature)"}};
  j["sphere_centre_m_mm"] = {round6(q.centre_m_mm.x()), round6(q.centre_m_mm.y()), round6(q.centre_m_mm.z())};
  // What the qualification feeds: MACHINE.json's probe section and CONTRIB.json's probe entries.
  j["machine_probe"] = {{"ball_diameter_mm", round6(q.effective_ball_diameter_mm)},
                        {"repeatability_um", round6(q.repeatability_um)}};
  j["contributors"] = {{"probe_repeatability", {{"u", round6(q.repeatability_um)}, {"unit", "um"},
                                                {"note", "probe_qual: pooled repeatability"}}},
                       {"probe_pretravel", {{"u", round6(q.lobing_rms_net_um)}, {"unit", "um"},
                                            {"note", "probe_qual: rms of the pretravel by direction about its mean, "
                                                     "less what the repeatability and the declared linear axes give it"}}}};
  j["fit"] = {{"touches", q.touches}, {"approach_directions", q.directions}, {"dof", q.dof}};
  // The envelope's figures every report shows: the touches used and their rms residual.
  double ss = 0.0;
  for (const double r : q.residuals_um) ss += r * r;
  j["points_used"] = q.touches;
  j["residual_rms_um"] = round6(q.residuals_um.empty() ? 0.0 : std::sqrt(ss / static_cast<double>(q.residuals_um.size())));
  Json ex = Json::array();
  for (const auto& e : q.screen.excluded)
    ex.push_back({{"run", e.run + 1},
                  {"repeat", e.repeat + 1},
                  {"point", e.point_id},
                  {"direction", e.direction},
                  {"deviation_um", round6(e.deviation_um)},
                  {"t", std::round(e.t * 1e4) / 1e4},
                  {"reason", "beyond the threshold: a chip or dirt on the sphere; left out of the repeatability and the fit"}});
  j["outliers"] = {{"test", "each touch's deviation from the mean of its own repeats, externally studentized by the "
                            "pooled scatter of every other touch (Student t with dof - 1), against the two-sided t "
                            "quantile at alpha / N; worst first, recomputed after each; no declared repeatability assumed"},
                   {"alpha", q.screen.alpha},
                   {"threshold_t", std::round(q.screen.threshold_t * 1e4) / 1e4},
                   {"t_dof", q.screen.dof},
                   {"touches", q.screen.touches},
                   {"max_fraction", q.screen.max_fraction},
                   {"too_many", q.screen.too_many},
                   {"beyond", q.screen.beyond},
                   {"excluded", ex},
                   {"summary", q.screen.text()}};
  return j;
}

Json probeQualFiguresJson(const ProbePlan& plan, const ProbeQualification& q) {
  const int repeats_per_run = probeQualLayoutOf(plan).repeats;
  Json figs = Json::array();
  // The horizontal approaches' pretravel around the sphere: lobing is a pattern in the azimuth.
  std::vector<double> az, pre, u;
  for (const auto& p : q.by_direction) {
    if (std::abs(p.approach.z()) > 1e-9) continue;
    const double a = std::atan2(-p.approach.y(), -p.approach.x()) * 180.0 / M_PI;
    az.push_back(round6(a < -1e-9 ? a + 360.0 : std::abs(a)));
    pre.push_back(round6(p.pretravel_um));
    u.push_back(round6(p.u_um));
  }
  if (!az.empty()) {
    const auto [lo, hi] = std::minmax_element(az.begin(), az.end());
    figs.push_back({{"id", "probe_qual_pretravel"},
                    {"title", "Pretravel by approach direction"},
                    {"x", {{"label", "contact azimuth"}, {"unit", "deg"}}},
                    {"y", {{"label", "pretravel"}, {"unit", "um"}}},
                    {"series", Json::array({{{"name", "horizontal approach (u_c)"}, {"style", "points"}, {"x", az}, {"y", pre}, {"u", u}},
                                            {{"name", "mean: the effective radius's deficit"},
                                             {"style", "line"},
                                             {"x", {*lo, *hi}},
                                             {"y", {round6(q.mean_pretravel_um), round6(q.mean_pretravel_um)}}}})},
                    {"note", fmt::format("late triggers positive; lobing rms {:.3f} um, of which the repeatability alone gives "
                                         "{:.3f} um. The first harmonic is a centre offset and sits in the sphere's centre.",
                                         q.lobing_rms_um, q.lobing_rms_noise_um)}});
  }
  // Each touch against its own repeats: the scatter the repeatability pools, and the chips left out.
  std::map<int, std::pair<double, int>> by_touch;
  for (size_t j = 0; j < q.residuals_um.size(); ++j) {
    auto& m = by_touch[q.touch_of[j]];
    m.first += q.residuals_um[j];
    ++m.second;
  }
  std::vector<double> rep, dev;
  for (size_t j = 0; j < q.residuals_um.size(); ++j) {
    const auto& m = by_touch[q.touch_of[j]];
    rep.push_back(q.repeat_of[j] + 1);
    dev.push_back(round6(q.residuals_um[j] - m.first / m.second));
  }
  Json series = Json::array({{{"name", "touches kept"}, {"style", "points"}, {"x", rep}, {"y", dev}}});
  std::vector<double> ex_rep, ex_dev;
  for (const auto& e : q.screen.excluded) {
    ex_rep.push_back(e.run * repeats_per_run + e.repeat + 1);  // as repeat_of counts them
    ex_dev.push_back(round6(e.deviation_um));
  }
  if (!ex_rep.empty()) series.push_back({{"name", "left out (a chip or dirt)"}, {"style", "points"}, {"x", ex_rep}, {"y", ex_dev}});
  if (!rep.empty()) {
    const auto [lo, hi] = std::minmax_element(rep.begin(), rep.end());
    const double s2 = 2 * q.repeatability_um;
    Json fig = {{"id", "probe_qual_repeats"},
                {"title", "Each touch against the mean of its own repeats"},
                {"x", {{"label", "repeat"}, {"unit", "no."}}},
                {"y", {{"label", "deviation along the approach"}, {"unit", "um"}}},
                {"series", series},
                {"note", fmt::format("the band is +-2 x the pooled repeatability {:.3f} um", q.repeatability_um)}};
    if (*hi > *lo)
      fig["bands"] = Json::array({{{"name", "+-2 x repeatability"}, {"x", {*lo, *hi}}, {"lo", {-s2, -s2}}, {"hi", {s2, s2}}}});
    figs.push_back(fig);
  }
  return figs;
}

Json probeQualVerdictJson(const ProbeQualification& q, double declared_repeatability_um) {
  // The repeatability against MACHINE.json's by its own 95 % interval (chi-square): the value
  // every other cycle's screen and uncertainty read. The mean pretravel against its U: whether
  // the ball diameter MACHINE.json holds should change.
  const double U_pre = kCoverageFactor * q.u_mean_pretravel_um;
  std::string rep_verdict;
  if (declared_repeatability_um <= 0)
    rep_verdict = "none declared: copy machine_probe.repeatability_um into MACHINE.json";
  else if (declared_repeatability_um < q.repeatability_lo_um)
    rep_verdict = fmt::format("larger than the declared {:.3f} um: copy machine_probe.repeatability_um into MACHINE.json",
                              declared_repeatability_um);
  else if (declared_repeatability_um > q.repeatability_hi_um)
    rep_verdict = fmt::format("smaller than the declared {:.3f} um: MACHINE.json may take machine_probe.repeatability_um",
                              declared_repeatability_um);
  else
    rep_verdict = fmt::format("consistent with the declared {:.3f} um: leave as is", declared_repeatability_um);
  const bool pre_significant = std::abs(q.mean_pretravel_um) > U_pre;
  const std::string pre_verdict =
      pre_significant ? fmt::format("significant: the effective ball diameter is {:.4f} mm (machine_probe.ball_diameter_mm)",
                                    q.effective_ball_diameter_mm)
                      : "not significant: leave the ball diameter as is";
  Json params = {{"repeatability",
                  {{"value", round6(q.repeatability_um)},
                   {"U", round6(std::max(q.repeatability_hi_um - q.repeatability_um, q.repeatability_um - q.repeatability_lo_um))},
                   {"unit", "um"},
                   {"verdict", rep_verdict}}},
                 {"mean_pretravel",
                  {{"value", round6(q.mean_pretravel_um)}, {"U", round6(U_pre)}, {"unit", "um"}, {"verdict", pre_verdict}}}};
  const bool rep_changes = rep_verdict.rfind("consistent", 0) != 0;
  std::string summary = rep_changes || pre_significant
                            ? std::string("update MACHINE.json's probe section: ") +
                                  (rep_changes ? "repeatability_um" : "") + (rep_changes && pre_significant ? ", " : "") +
                                  (pre_significant ? "ball_diameter_mm" : "")
                            : std::string("the probe is as MACHINE.json declares it: leave as is");
  return {{"rule", "repeatability: the declared value against the measured one's 95 % interval (chi-square; U here is its "
                   "larger half-width); mean pretravel: significant where |value| > U = k u_c"},
          {"parameters", params},
          {"summary", summary},
          {"tolerance", nullptr}};
}

std::string probeQualText(const ProbeQualification& q) {
  std::string s = fmt::format(
      "probe qualification: {} touches, {} directions\n"
      "repeatability {:.3f} um ({} dof; 95 % interval {:.3f} .. {:.3f} um)\n"
      "mean pretravel {:+.3f} um (u_c {:.3f} um): effective ball diameter {:.4f} mm\n"
      "pretravel by direction (um, u_c):\n",
      q.touches, q.directions, q.repeatability_um, q.dof, q.repeatability_lo_um, q.repeatability_hi_um, q.mean_pretravel_um,
      q.u_mean_pretravel_um, q.effective_ball_diameter_mm);
  for (const auto& p : q.by_direction) s += fmt::format("  {:<16} {:+8.3f}  {:.3f}\n", p.name, p.pretravel_um, p.u_um);
  const bool type_b = !q.type_b_source.empty();
  s += fmt::format("lobing: range {:.3f} um, rms {:.3f} um (the repeatability{} {:.3f} um: net {:.3f} um)\n",
                   q.lobing_range_um, q.lobing_rms_um, type_b ? " and the declared linear axes give" : " alone gives",
                   q.lobing_rms_noise_um, q.lobing_rms_net_um);
  s += type_b ? fmt::format("u_c (k = 1): u_A the repeats' scatter, u_B {} (mean pretravel: u_A {:.3f}, u_B {:.3f} um)\n",
                            q.type_b_source, q.u_a_mean_pretravel_um, q.u_b_mean_pretravel_um)
              : std::string("u_c (k = 1) = u_A: no linear axis declared, no Type B (the qualification measures the probe's "
                            "own contributors)\n");
  s += q.screen.text() + "\n";
  return s;
}

}  // namespace rotacal
