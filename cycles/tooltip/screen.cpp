#include "cycles/tooltip/screen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "cycles/tooltip/analyze.hpp"

namespace rotacal {

namespace {

bool transverseOnlyRuns(const std::vector<TooltipRun>& runs) {
  for (const auto& run : runs)
    for (const auto& r : run)
      if (std::isfinite(r.z_um)) return false;
  return true;
}

std::vector<TooltipRun> without(const std::vector<TooltipRun>& runs, const std::set<std::pair<int, int>>& readings) {
  std::vector<TooltipRun> out = runs;
  for (const auto& [r, k] : readings) {
    TooltipReading& x = out[static_cast<size_t>(r)][static_cast<size_t>(k)];
    x.t_um = x.z_um = std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

char transverseName(const ProbePlan& plan) {
  return tooltipOptionsFrom(plan.options, plan.machine).axis == 'A' ? 'y' : 'x';
}

}  // namespace

std::vector<std::pair<int, int>> TooltipScreen::excludedReadings() const {
  std::vector<std::pair<int, int>> v;
  for (const auto& e : screen.excluded) v.emplace_back(e.run, e.point_id / 2);
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

TooltipScreen screenTooltipReadings(const ProbePlan& plan, const std::vector<TooltipRun>& runs, const DeclaredNoise& noise) {
  if (!(noise.white_um2 > 0)) throw std::invalid_argument("tooltip screen: the declared noise per reading must be > 0");
  TooltipFitOptions fo;
  fo.fit_pivot_length = !transverseOnlyRuns(runs);
  const std::vector<int> refs = tooltipReferences(plan);
  // Each fit's statistics, by the values it held out (the screen asks for them after the fit).
  std::map<std::vector<std::pair<int, int>>, Eigen::VectorXd> stats, sensitivities;
  auto fit = [&](const std::function<bool(int, const ProbePoint&)>& hold_out) {
    std::set<std::pair<int, int>> held;  // (run, plan point)
    if (hold_out)
      for (size_t r = 0; r < runs.size(); ++r)
        for (size_t k = 0; k < runs[r].size(); ++k) {
          ProbePoint t, z;
          t.id = static_cast<int>(2 * k);
          z.id = static_cast<int>(2 * k + 1);
          if (hold_out(static_cast<int>(r), t) || hold_out(static_cast<int>(r), z))
            held.insert({static_cast<int>(r), static_cast<int>(k)});
        }
    ScreenedFit res;
    res.summary.termination = Termination::Converged;
    TooltipFit f;
    try {
      f = fitTooltip(plan, without(runs, held), fo);
    } catch (const std::invalid_argument&) {
      if (held.empty()) throw;  // the data themselves: analyze says why
      res.summary.termination = Termination::RankDeficient;  // leaving this reading out broke the fit
      return res;
    }
    for (size_t i = 0; i < f.kept_values.size(); ++i)
      res.residuals.push_back({f.kept_values[i].first, f.kept_values[i].second, f.kept_residual_um[static_cast<Eigen::Index>(i)], 0.0, false});
    // The readings left out: what the fit without them predicts for them.
    int reading = 0;
    for (size_t r = 0; r < runs.size(); ++r)
      for (size_t k = 0; k < runs[r].size(); ++k, ++reading) {
        if (!held.count({static_cast<int>(r), static_cast<int>(k)}) || refs[k] == static_cast<int>(k)) continue;
        const TooltipReading& x = runs[r][k];
        if (std::isfinite(x.t_um))
          res.residuals.push_back({static_cast<int>(r), static_cast<int>(2 * k), x.t_um - f.model_t_um[static_cast<size_t>(reading)], 0.0, true});
        if (std::isfinite(x.z_um))
          res.residuals.push_back({static_cast<int>(r), static_cast<int>(2 * k + 1), x.z_um - f.model_z_um[static_cast<size_t>(reading)], 0.0, true});
      }
    const Eigen::MatrixXd C = noise.covariance(f.kept_values);
    Eigen::VectorXd t = deletionStatistics(f.kept_residual_um, f.kept_J, C);
    // A value the others cannot predict (its angle seen by it alone) cannot be tested: 0.
    for (Eigen::Index i = 0; i < t.size(); ++i)
      if (!std::isfinite(t[i])) t[i] = 0.0;
    stats[heldOutTouches(res.residuals)] = t;
    sensitivities[heldOutTouches(res.residuals)] = deletionSensitivity(f.kept_J, C);
    return res;
  };
  TooltipScreen out;
  out.options.sigma_um = std::sqrt(noise.white_um2);
  out.options.alpha = kTooltipScreenAlpha;
  out.options.max_fraction = kTooltipScreenMaxFraction;
  out.options.declaration = noise.declaration;
  out.options.statistic = [&stats](const ScreenedFit& f) { return stats.at(heldOutTouches(f.residuals)); };
  out.options.sensitivity = [&sensitivities](const ScreenedFit& f) { return sensitivities.at(heldOutTouches(f.residuals)); };
  out.screen = screenOutliers(fit, out.options);
  out.options.statistic = nullptr;  // they read this call's fits
  out.options.sensitivity = nullptr;
  const TooltipOptions opt = tooltipOptionsFrom(plan.options, plan.machine);
  const char tn = transverseName(plan);
  for (auto& v : out.screen.reach) {
    const auto& p = plan.points[static_cast<size_t>(v.point_id / 2)];
    v.name = fmt::format("run {} {} = {:g} deg ({}) d{}", v.run + 1, opt.axis, opt.axis == 'A' ? p.pose.A : p.pose.B,
                         p.pose_name, v.point_id % 2 == 0 ? tn : 'z');
    v.point_id = p.id;  // the plan's point, as the excluded list names it; the name says which value
  }
  return out;
}

std::vector<TooltipRun> withoutScreened(const std::vector<TooltipRun>& runs, const TooltipScreen& s) {
  if (s.screen.too_many) return runs;
  const auto ex = s.excludedReadings();
  return without(runs, std::set<std::pair<int, int>>(ex.begin(), ex.end()));
}

Json tooltipScreenJson(const ProbePlan& plan, const TooltipScreen& s) {
  Json ex = Json::array();
  const char tn = transverseName(plan);
  for (const auto& e : s.screen.excluded) {
    const size_t k = static_cast<size_t>(e.point_id / 2);
    const auto& p = plan.points[k];
    const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
    ex.push_back({{"run", e.run + 1},
                  {"point", p.id},
                  {"angle_deg", o.axis == 'A' ? p.pose.A : p.pose.B},
                  {"sweep", p.pose_name},
                  {"value", fmt::format("d{}", e.point_id % 2 == 0 ? tn : 'z')},
                  {"residual_um", std::round(e.residual_um * 1e4) / 1e4},
                  {"t", std::round(e.t * 1e3) / 1e3},
                  {"reason", "beyond the threshold: a gross reading (a laser glitch, a chip on the sphere); the reading "
                             "(both components) is left out of every fit"}});
  }
  return screenJson(s.screen, s.options,
                    "each read value (transverse and Z apart) against what every other value predicts for it under the "
                    "declared noise (generalized least squares deletion residual of the joint model) against the normal "
                    "quantile at alpha / (2 N), worst first, refitted after each; the reading of a value beyond leaves",
                    "values", std::move(ex), tooltipScreenText(plan, s));
}

std::string tooltipScreenText(const ProbePlan& plan, const TooltipScreen& s) {
  const OutlierScreen& o = s.screen;
  const std::string against = fmt::format("the declared noise ({})", s.options.declaration);
  if (o.too_many)
    return fmt::format("reading screen: {} of {} values beyond {:.2f} sigma of {} even with the worst left out: more "
                       "than a few glitches, a model that does not fit or a noise declared too small; none left out "
                       "(rotacal diagnose)",
                       o.beyond, o.touches, o.threshold_t, against);
  if (o.excluded.empty())
    return fmt::format("reading screen: no value beyond {:.2f} sigma of {} ({} values)", o.threshold_t, against, o.touches);
  const TooltipOptions opt = tooltipOptionsFrom(plan.options, plan.machine);
  const char tn = transverseName(plan);
  std::string list;
  for (const auto& e : o.excluded) {
    const auto& p = plan.points[static_cast<size_t>(e.point_id / 2)];
    list += fmt::format("{}run {} {} = {:g} deg ({}) d{} {:+.2f} um, {:.1f} sigma", list.empty() ? "" : "; ", e.run + 1,
                        opt.axis, opt.axis == 'A' ? p.pose.A : p.pose.B, p.pose_name, e.point_id % 2 == 0 ? tn : 'z',
                        e.residual_um, std::abs(e.t));
  }
  return fmt::format("reading screen: left out {} reading(s) of {} values beyond {:.2f} sigma of {} (a laser glitch or "
                     "a chip; every fit runs without them): {}",
                     o.excluded.size(), o.touches, o.threshold_t, against, list);
}

}  // namespace rotacal
