#include "core/outliers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/statistics.hpp"

namespace rotacal {

bool OutlierOptions::validate(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (!(sigma_um > 0 && std::isfinite(sigma_um))) return fail("outlier screen: sigma_um must be > 0");
  if (!(alpha > 0 && alpha < 1)) return fail("outlier screen: alpha must be in (0, 1)");
  if (!(max_fraction >= 0 && max_fraction < 0.5)) return fail("outlier screen: max_fraction must be in [0, 0.5)");
  return true;
}

std::function<bool(int, const ProbePoint&)> OutlierScreen::holdOut() const {
  if (excluded.empty()) return nullptr;
  std::set<std::pair<int, int>> out;
  for (const auto& e : excluded) out.insert({e.run, e.point_id});
  return [out](int run, const ProbePoint& p) { return out.count({run, p.id}) > 0; };
}

std::string OutlierScreen::text() const {
  const std::string against = declaration.empty() ? "the declared repeatability" : "the declared noise (" + declaration + ")";
  if (too_many)
    return fmt::format("outlier screen: {} of {} touches beyond {:.2f} x {} even with the worst "
                       "left out: more than a few chips, a model that does not fit the data or a noise declared "
                       "too small; none excluded (rotacal diagnose)",
                       beyond, touches, threshold_t, against);
  if (excluded.empty())
    return fmt::format("outlier screen: no touch beyond {:.2f} x {} ({} touches)", threshold_t, against, touches);
  std::string list;
  for (const auto& e : excluded)
    list += fmt::format("{}point {}{} ({:+.2f} um, {:.1f} x)", list.empty() ? "" : ", ", e.point_id,
                        e.run > 0 ? fmt::format(" of run {}", e.run + 1) : std::string(), e.residual_um, std::abs(e.t));
  return fmt::format("outlier screen: excluded {} of {} touches beyond {:.2f} x {} (a chip "
                     "or dirt on the surface; fit without them): {}",
                     excluded.size(), touches, threshold_t, against, list);
}

Eigen::VectorXd screenNullMaxima(const Eigen::MatrixXd& t, const std::vector<bool>& screened) {
  if (!screened.empty() && static_cast<Eigen::Index>(screened.size()) != t.rows())
    throw std::invalid_argument(fmt::format("screenNullMaxima: {} flags for {} statistics", screened.size(), t.rows()));
  Eigen::VectorXd m = Eigen::VectorXd::Zero(t.cols());
  for (Eigen::Index i = 0; i < t.rows(); ++i)
    if (screened.empty() || screened[static_cast<size_t>(i)]) m = m.cwiseMax(t.row(i).cwiseAbs().transpose());
  return m;
}

std::vector<std::pair<int, int>> heldOutTouches(const std::vector<PointResidual>& residuals) {
  std::vector<std::pair<int, int>> k;
  for (const auto& p : residuals)
    if (p.held_out) k.emplace_back(p.run, p.point_id);
  std::sort(k.begin(), k.end());
  return k;
}

OutlierScreen screenOutliers(const std::function<ScreenedFit(const HoldOutRule&)>& fit, const OutlierOptions& options) {
  std::string why;
  if (!options.validate(&why)) throw std::invalid_argument(why);
  OutlierScreen s;
  ScreenedFit r = fit(nullptr);
  for (const auto& p : r.residuals) s.touches += p.held_out ? 0 : 1;
  if (s.touches == 0) return s;
  s.gaussian_t = normalQuantile(1.0 - options.alpha / (2.0 * s.touches));
  s.threshold_t = s.gaussian_t;
  const Eigen::VectorXd null_max = options.null_maxima ? options.null_maxima(r) : Eigen::VectorXd();
  if (null_max.size() >= kMinScreenNullDraws) {
    std::vector<double> m(null_max.data(), null_max.data() + null_max.size());
    const auto k = static_cast<size_t>(std::ceil((1.0 - options.alpha) * static_cast<double>(m.size()))) - 1;
    std::nth_element(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(k), m.end());
    s.null_draws = static_cast<int>(m.size());
    s.threshold_t = std::max(s.gaussian_t, m[k]);
  }
  const int cap = static_cast<int>(std::floor(options.max_fraction * s.touches));
  s.declaration = options.declaration;
  // Each fitted touch and its statistic, in the residuals' order.
  auto statistics = [&](const ScreenedFit& fit, std::vector<const PointResidual*>* fitted) {
    fitted->clear();
    for (const auto& p : fit.residuals)
      if (!p.held_out) fitted->push_back(&p);
    if (options.statistic) {
      Eigen::VectorXd t = options.statistic(fit);
      if (t.size() != static_cast<Eigen::Index>(fitted->size()))
        throw std::logic_error(fmt::format("outlier screen: {} statistics for {} touches", t.size(), fitted->size()));
      return t;
    }
    Eigen::VectorXd t(static_cast<Eigen::Index>(fitted->size()));
    for (size_t i = 0; i < fitted->size(); ++i) t[static_cast<Eigen::Index>(i)] = (*fitted)[i]->residual_um / options.sigma_um;
    return t;
  };
  auto beyondIn = [&](const ScreenedFit& fit) {
    std::vector<const PointResidual*> fitted;
    const Eigen::VectorXd t = statistics(fit, &fitted);
    return static_cast<int>((t.array().abs() > s.threshold_t).count());
  };
  // Worst first: one gross outlier (a value millimetres off) drags the whole fit and puts many
  // touches beyond the threshold; left out, the others come back.
  while (true) {
    std::vector<const PointResidual*> fitted;
    const Eigen::VectorXd t = statistics(r, &fitted);
    if (t.size() == 0) break;
    Eigen::Index at = 0;
    const double worst_t = t.cwiseAbs().maxCoeff(&at);
    const PointResidual* worst = fitted[static_cast<size_t>(at)];
    if (worst_t <= s.threshold_t) break;
    if (static_cast<int>(s.excluded.size()) >= cap) {
      // Still beyond after the most a few chips can be: the model or the declared repeatability
      // is wrong. Nothing is left out: the analysis and the adequacy test see all the data.
      s.too_many = true;
      s.beyond = beyondIn(r);
      s.excluded.clear();
      return s;
    }
    s.excluded.push_back({worst->run, worst->point_id, worst->residual_um, t[at]});
    ScreenedFit next = fit(s.holdOut());
    if (next.summary.termination != Termination::Converged) {
      // Leaving this touch out broke the fit (a point the model cannot do without): keep it.
      s.excluded.pop_back();
      break;
    }
    r = std::move(next);
  }
  // What each excluded touch is against the model fitted without it.
  for (auto& e : s.excluded)
    for (const auto& p : r.residuals)
      if (p.run == e.run && p.point_id == e.point_id) e.residual_um = p.residual_um;
  if (options.sensitivity) {
    std::vector<const PointResidual*> fitted;
    for (const auto& p : r.residuals)
      if (!p.held_out) fitted.push_back(&p);
    const Eigen::VectorXd k = options.sensitivity(r);
    if (k.size() != static_cast<Eigen::Index>(fitted.size()))
      throw std::logic_error(fmt::format("outlier screen: {} sensitivities for {} touches", k.size(), fitted.size()));
    const double shift = s.threshold_t + normalQuantile(kScreenReachPower);
    for (size_t i = 0; i < fitted.size(); ++i) {
      const double ki = k[static_cast<Eigen::Index>(i)];
      s.reach.push_back({fitted[i]->run, fitted[i]->point_id,
                         ki > 0 ? shift / ki : std::numeric_limits<double>::infinity(), std::string()});
    }
  }
  return s;
}

namespace {

/// A reach in um, or in mm from 1 mm on (a gross error the size of the part is no chip).
std::string reachSize(double um) { return um < 1000.0 ? fmt::format("{:.1f} um", um) : fmt::format("{:.1f} mm", um / 1000.0); }

std::string nameOf(const TouchReach& t) {
  if (!t.name.empty()) return t.name;
  return fmt::format("point {}{}", t.point_id, t.run > 0 ? fmt::format(" of run {}", t.run + 1) : std::string());
}

}  // namespace

std::string OutlierScreen::reachLine(const std::string& counted) const {
  return reach.empty() ? std::string() : reachText(counted) + "\n";
}

std::string OutlierScreen::lines() const { return text() + "\n" + reachLine(); }

std::string OutlierScreen::reachText(const std::string& counted) const {
  if (reach.empty()) return {};
  std::vector<double> seen;
  std::string unseen;
  int n_unseen = 0;
  const TouchReach* worst = nullptr;
  for (const auto& t : reach) {
    if (std::isfinite(t.detectable_um)) {
      seen.push_back(t.detectable_um);
      if (!worst || t.detectable_um > worst->detectable_um) worst = &t;
      continue;
    }
    if (++n_unseen <= 5) unseen += (unseen.empty() ? "" : ", ") + nameOf(t);
  }
  if (seen.empty())
    return fmt::format("the screen cannot see a gross error at any of its {} {}: the fit takes every error up",
                       reach.size(), counted);
  std::nth_element(seen.begin(), seen.begin() + static_cast<std::ptrdiff_t>(seen.size() / 2), seen.end());
  std::string out = fmt::format(
      "the screen catches a gross error at one of its {} {} {:.0f} times in 10 from {} (median; {} at {})", reach.size(),
      counted, 10 * kScreenReachPower, reachSize(seen[seen.size() / 2]), reachSize(worst->detectable_um), nameOf(*worst));
  if (n_unseen > 0)
    out += fmt::format("; {} of them it cannot see at any size, the fit taking their whole error up ({}{}): an error there "
                       "moves the estimate, and only another reading of the same quantity (a repeat) exposes it",
                       n_unseen, unseen, n_unseen > 5 ? ", ..." : "");
  return out;
}

Json outlierScreenJson(const OutlierScreen& s, const OutlierOptions& o) {
  Json ex = Json::array();
  for (const auto& e : s.excluded)
    ex.push_back({{"run", e.run + 1},
                  {"point", e.point_id},
                  {"residual_um", std::round(e.residual_um * 1e6) / 1e6},
                  {"t", std::round(e.t * 1e4) / 1e4},
                  {"reason", "beyond the threshold: a chip or dirt on the surface; left out of the fit"}});
  OutlierOptions named = o;
  if (named.declaration.empty()) named.declaration = fmt::format("declared: repeatability only ({:.3f} um)", o.sigma_um);
  return screenJson(s, named,
                    o.statistic ? "|t| of each touch against everything the others predict for it under the declared "
                                  "covariance of the touches (generalized least squares deletion residual) against the "
                                  "normal quantile at alpha / (2 N), worst first, refitted after each"
                                : "|residual| / declared repeatability against the normal quantile at alpha / (2 N), "
                                  "worst first, refitted after each",
                    "touches", std::move(ex), s.text());
}

namespace {

Json reachJson(const OutlierScreen& s, const std::string& counted) {
  if (s.reach.empty()) return nullptr;
  Json per = Json::array();
  int unseen = 0;
  for (const auto& t : s.reach) {
    const bool seen = std::isfinite(t.detectable_um);
    unseen += seen ? 0 : 1;
    Json e = {{"run", t.run + 1},
              {"point", t.point_id},
              {"detectable_um", seen ? Json(std::round(t.detectable_um * 1e3) / 1e3) : Json(nullptr)}};
    if (!t.name.empty()) e["name"] = t.name;
    per.push_back(std::move(e));
  }
  return {{"what", fmt::format("per {}, the smallest gross error there that the screen catches with probability {:g} under "
                               "the declared noise, (threshold + z({:g})) / sqrt(P_ii), P the declared residual projector "
                               "(the minimal detectable bias); null where the fit takes the whole error up",
                               counted, kScreenReachPower, kScreenReachPower)},
          {"power", kScreenReachPower},
          {"unseen", unseen},
          {"points", std::move(per)},
          {"summary", s.reachText(counted)}};
}

}  // namespace

Json screenJson(const OutlierScreen& s, const OutlierOptions& o, const std::string& test, const std::string& counted,
                Json excluded, const std::string& summary) {
  return {{"test", test},
          {"declaration", o.declaration},
          {"sigma_um", o.sigma_um},
          {"alpha", o.alpha},
          {"threshold_t", std::round(s.threshold_t * 1e4) / 1e4},
          {"gaussian_threshold_t", std::round(s.gaussian_t * 1e4) / 1e4},
          {"null_draws", s.null_draws},
          {"threshold_from", s.null_draws > 0 ? fmt::format("the larger of the normal bound at alpha / (2 N) and the (1 - alpha) "
                                                             "quantile of the largest |t| over {} draws of the declared machine",
                                                             s.null_draws)
                                              : std::string("the normal bound at alpha / (2 N)")},
          {counted, s.touches},
          {"max_fraction", o.max_fraction},
          {"too_many", s.too_many},
          {"beyond", s.beyond},
          {"excluded", std::move(excluded)},
          {"summary", summary},
          {"reach", reachJson(s, counted)}};
}

}  // namespace rotacal
