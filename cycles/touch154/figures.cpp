#include "cycles/touch154/figures.hpp"

#include <cmath>
#include <string>

namespace rotacal {

namespace {

Json series(const std::string& name, const IdentificationResult& fit, const ProbePlan& plan, bool vs_time) {
  Json x = Json::array(), y = Json::array();
  for (const auto& r : fit.residuals) {
    if (r.held_out) continue;
    double xv = r.t_h;
    if (!vs_time) {
      const ProbePoint* p = plan.findPoint(r.point_id);
      if (p == nullptr) continue;
      xv = p->pose.C;
    }
    if (!std::isfinite(xv)) continue;
    x.push_back(std::round(xv * 1e4) / 1e4);
    y.push_back(std::round(r.residual_um * 1e4) / 1e4);
  }
  return {{"name", name}, {"style", "points"}, {"x", x}, {"y", y}};
}

}  // namespace

Json touch154DiagnosisFigures(const Touch154Diagnosis& d, const ProbePlan& plan) {
  Json figs = Json::array();
  for (bool vs_time : {true, false}) {
    Json s = Json::array();
    s.push_back(series("baseline (location errors only)", d.lin.baseline, plan, vs_time));
    for (const auto& f : d.findings) s.push_back(series("+ " + f.extension->cause(), f.fit, plan, vs_time));
    if (s[0]["x"].empty()) continue;
    Json fig = {{"id", vs_time ? "diagnose_residual_vs_time" : "diagnose_residual_vs_c"},
                {"title", vs_time ? "Residuals against time, before and after the named cause"
                                  : "Residuals against the C angle, before and after the named cause"},
                {"x", {{"label", vs_time ? "t - mean time" : "C"}, {"unit", vs_time ? "h" : "deg"}}},
                {"y", {{"label", "residual"}, {"unit", "um"}}},
                {"series", s},
                {"note", "Measured minus model along the probing direction, fitted points only."}};
    figs.push_back(fig);
  }
  return figs;
}

}  // namespace rotacal
