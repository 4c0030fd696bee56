#include "history/trend_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include <fmt/format.h>

namespace rotacal::history {

namespace {
double r6(double v) { return std::round(v * 1e6) / 1e6; }
}  // namespace

Json historyJson(const std::string& machine_id, const std::vector<Calibration>& cals, const TrendOptions& o) {
  Json j;
  j["format"] = "rotacal-history/1";
  j["machine_id"] = machine_id;
  j["alpha"] = o.alpha;
  j["test"] = fmt::format(
      "Weighted least squares (weights 1/u^2) of each parameter against time. Drift: the straight line lowers chi^2 "
      "by more than the {:.3g} quantile of chi^2(1). Step: the best single step (with the line) lowers chi^2 against the "
      "line by more than the 1 - alpha/m quantile of chi^2(1), m splits tried; alpha = {:g} per parameter and test.",
      1 - o.alpha, o.alpha);
  const double t0 = cals.empty() ? 0.0 : cals.front().time_s;
  Json cl = Json::array();
  std::vector<std::string> order;
  std::map<std::string, std::vector<TrendPoint>> series;
  std::map<std::string, std::vector<long long>> seqs;
  std::map<std::string, std::string> unit;
  for (size_t i = 0; i < cals.size(); ++i) {
    const auto& c = cals[i];
    cl.push_back({{"seq", i + 1}, {"id", c.id}, {"time_utc", c.time_utc}, {"t_days", r6((c.time_s - t0) / 86400.0)},
                  {"cycle", c.cycle}, {"method", c.method}, {"machine", c.machine_name},
                  {"residual_rms_um", c.residual_rms_um}, {"points_used", c.points_used}, {"source", c.source}});
    for (const auto& p : c.parameters) {
      if (!series.count(p.name)) order.push_back(p.name);
      series[p.name].push_back({(c.time_s - t0) / 86400.0, p.value, p.u});
      seqs[p.name].push_back(static_cast<long long>(i + 1));
      unit[p.name] = p.unit;
    }
  }
  j["calibrations"] = cl;
  // The papers' order (000 Table 1, 002 Table 2), others after.
  static const std::vector<std::string> paper = {"dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA",
                                                 "dx_BY", "dy_CB", "dz_BY", "a_BY", "b_BY", "c_BY"};
  std::stable_sort(order.begin(), order.end(), [](const std::string& a, const std::string& b) {
    const auto ia = std::find(paper.begin(), paper.end(), a) - paper.begin();
    const auto ib = std::find(paper.begin(), paper.end(), b) - paper.begin();
    return ia < ib;
  });
  Json trends = Json::object(), figures = Json::array();
  for (const auto& name : order) {
    const auto& pts = series[name];
    const Trend t = analyzeTrend(pts, o);
    Json tj = {{"unit", unit[name]},
               {"n", t.n},
               {"mean", r6(t.mean)},
               {"chi2_constant", r6(t.chi2_constant)},
               {"dof_constant", std::max(0, t.n - 1)},
               {"drift", t.drift},
               {"drift_per_day", r6(t.drift_per_day)},
               {"drift_u_per_day", r6(t.drift_u)},
               {"chi2_drift", r6(t.chi2_drift)},
               {"dof_drift", std::max(0, t.n - 2)},
               {"step", t.step},
               {"verdict", t.verdict},
               // With fewer than 3 calibrations there is no mean to speak of and no drift was
               // tested: `mean` is then the latest value and the drift fields are not measurements.
               {"value_is", t.n >= 3 ? "mean" : "latest"},
               {"drift_evaluated", t.n >= 3}};
    if (t.step_after) {
      tj["step_after_seq"] = seqs[name][static_cast<size_t>(*t.step_after)];
      tj["step_size"] = r6(t.step_size);
      tj["step_u"] = r6(t.step_u);
      tj["chi2_step"] = r6(t.chi2_step);
    } else {
      tj["step_after_seq"] = nullptr;
    }
    trends[name] = tj;

    Json x = Json::array(), y = Json::array(), u = Json::array(), lo = Json::array(), hi = Json::array(), fit = Json::array();
    for (size_t i = 0; i < pts.size(); ++i) {
      x.push_back(r6(pts[i].t_days));
      y.push_back(r6(pts[i].value));
      u.push_back(r6(pts[i].u));
      lo.push_back(r6(pts[i].value - 2 * pts[i].u));
      hi.push_back(r6(pts[i].value + 2 * pts[i].u));
      fit.push_back(0.0);  // filled below
    }
    // The model the tests chose (slope, step) drawn through the points' weighted mean, for the eye.
    {
      const bool step = t.step_after.has_value();
      const double slope = step ? t.step_drift_per_day : (t.drift ? t.drift_per_day : 0.0);
      double sw = 0, swr = 0;
      for (size_t i = 0; i < pts.size(); ++i) {
        const double w = 1.0 / std::pow(std::max(pts[i].u, o.u_floor), 2);
        const double shape = slope * pts[i].t_days + (step && static_cast<int>(i) > *t.step_after ? t.step_size : 0.0);
        sw += w;
        swr += w * (pts[i].value - shape);
      }
      const double a = sw > 0 ? swr / sw : 0.0;
      for (size_t i = 0; i < pts.size(); ++i)
        fit[i] = r6(a + slope * pts[i].t_days + (step && static_cast<int>(i) > *t.step_after ? t.step_size : 0.0));
    }
    Json fig = {{"id", "trend_" + [&] {
                   std::string s;
                   for (char ch : name) s += (std::isalnum(static_cast<unsigned char>(ch)) ? static_cast<char>(std::tolower(ch)) : '_');
                   return s;
                 }()},
                {"title", fmt::format("{}: {}", name, t.verdict)},
                {"x", {{"label", "time since the first calibration"}, {"unit", "d"}}},
                {"y", {{"label", name}, {"unit", unit[name]}}},
                {"series", Json::array({{{"name", "identified, u (k = 1): u_between, what differs between calibrations"}, {"style", "points"}, {"x", x}, {"y", y}, {"u", u}},
                                        {{"name", "model chosen by the tests"}, {"style", "line"}, {"x", x}, {"y", fit}}})},
                {"bands", Json::array({{{"name", "value ± 2u (u_between, k = 2)"}, {"x", x}, {"lo", lo}, {"hi", hi}}})}};
    if (t.step_after)
      fig["note"] = fmt::format("Step of {:.3f} {} (u {:.3f}) after calibration #{}.", t.step_size, unit[name], t.step_u,
                                seqs[name][static_cast<size_t>(*t.step_after)]);
    else if (t.drift)
      fig["note"] = fmt::format("Drift of {:.3f} {}/day (u {:.3f}).", t.drift_per_day, unit[name], t.drift_u);
    if (t.step_after) {
      // Draw the step as a step: both levels at the midpoint between the calibrations around it.
      const size_t k = static_cast<size_t>(*t.step_after);
      const double tm = r6(0.5 * (pts[k].t_days + pts[k + 1].t_days));
      const double slope = t.step_drift_per_day;
      Json fx = Json::array(), fy = Json::array();
      for (size_t i = 0; i < pts.size(); ++i) {
        fx.push_back(x[i]);
        fy.push_back(fit[i]);
        if (i == k) {
          const double before = fit[k].get<double>() + slope * (tm - pts[k].t_days);
          fx.push_back(tm);
          fy.push_back(r6(before));
          fx.push_back(tm);
          fy.push_back(r6(before + t.step_size));
        }
      }
      fig["series"][1]["x"] = fx;
      fig["series"][1]["y"] = fy;
    }
    figures.push_back(fig);
  }
  j["trends"] = trends;
  j["figures"] = figures;
  return j;
}

std::string historyText(const Json& h) {
  std::string s = fmt::format("rotacal history: machine {}, {} calibration(s)\n", h.value("machine_id", ""),
                              h["calibrations"].size());
  for (const auto& c : h["calibrations"])
    s += fmt::format("  #{:<3} {}  {:<9} residual {:.3f} um  {}\n", c["seq"].get<int>(), c["time_utc"].get<std::string>(),
                     c["cycle"].get<std::string>(), c["residual_rms_um"].get<double>(), c["source"].get<std::string>());
  s += fmt::format("\n{:<8} {:<5} {:>10} {:<6} {:>16} {:>8} {:>12}  {}\n", "param", "unit", "value", "", "drift /day (u)", "step",
                   "size", "verdict");
  for (const auto& [name, t] : h["trends"].items()) {
    const bool evaluated = t["n"].get<int>() >= 3;
    s += fmt::format("{:<8} {:<5} {:>10.3f} {:<6} {:>16} {:>8} {:>12}  {}\n", name, t["unit"].get<std::string>(),
                     t["mean"].get<double>(), evaluated ? "mean" : "latest",
                     evaluated ? fmt::format("{:.3f} ({:.3f})", t["drift_per_day"].get<double>(), t["drift_u_per_day"].get<double>())
                               : std::string("-"),
                     t["step_after_seq"].is_null() ? std::string("-") : "after #" + std::to_string(t["step_after_seq"].get<int>()),
                     t.contains("step_size") ? fmt::format("{:.3f}", t["step_size"].get<double>()) : std::string("-"),
                     t["verdict"].get<std::string>());
  }
  return s;
}

}  // namespace rotacal::history
