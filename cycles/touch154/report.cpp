#include "cycles/touch154/report.hpp"

#include <cmath>

#include <fmt/format.h>

#include "core/units.hpp"

namespace rotacal {

namespace {

double uReport(const LocationErrors& e, const ErrorVector& u, int i) {
  return locationParameters(e.kinematics)[i].kind == ParamKind::Length ? mmToUm(u[i]) : radToMdeg(u[i]);
}

// A repeat alone or another estimator has no budget of its own: its u is not the signed u_c,
// and says so where it stands.
constexpr const char* kOwnFitU =
    "u here is this estimate's own fit (its covariance scaled by its residual), no Type B evaluated: not the report's "
    "u_c, which location_errors carries";


}  // namespace

Json analysisToJson(const Analysis& a) {
  const IdentificationResult& m = a.main;
  Json j = documentEnvelope("rotacal-report/1", *a.plan, a.result_files);
  j["method"] = std::string(methodName(m.method));
  j["location_errors"] = locationErrorsJson(m.estimate, m.u);
  addBudgetFields(&j["location_errors"], a.budget);
  j["uncertainty"] = budgetJson(a.budget);
  j["residual_rms_um"] = round6(m.summary.residual_rms_um);
  j["points_used"] = m.summary.observations;
  j["summary"] = fitSummaryJson(m.summary);
  if (!a.per_run.empty()) {
    Json runs = Json::array();
    for (size_t r = 0; r < a.per_run.size(); ++r)
      runs.push_back({{"results", r < a.result_files.size() ? a.result_files[r] : ""},
                      {"location_errors", locationErrorsJson(a.per_run[r].estimate, a.per_run[r].u)},
                      {"u_source", kOwnFitU},
                      {"residual_rms_um", round6(a.per_run[r].summary.residual_rms_um)}});
    j["runs"] = runs;
  }
  if (!a.other_methods.empty()) {
    Json other = Json::object();
    for (const auto& o : a.other_methods) {
      if (o.summary.termination != Termination::Converged) {
        other[std::string(methodName(o.method))] = {{"summary", fitSummaryJson(o.summary)}};
        continue;
      }
      other[std::string(methodName(o.method))] = {{"location_errors", locationErrorsJson(o.estimate, o.u)},
                                                  {"u_source", kOwnFitU},
                                                  {"summary", fitSummaryJson(o.summary)}};
    }
    j["other_methods"] = other;
  }
  if (!a.patterns.empty()) {
    Json pats = Json::array();
    for (const auto& p : a.patterns)
      pats.push_back({{"pattern", p.name},
                      {"equation", p.equation},
                      {"value", p.name == "4" ? radToMdeg(p.value_mm) : mmToUm(p.value_mm)},
                      {"unit", p.name == "4" ? "mdeg" : "um"},
                      {"points", p.points}});
    j["closed_form_patterns"] = pats;
  }
  Json res = Json::array();
  for (const auto& r : m.residuals) res.push_back({{"run", r.run + 1}, {"point", r.point_id}, {"residual_um", round6(r.residual_um)}});
  j["residuals"] = res;
  return j;
}

std::string analysisText(const Analysis& a) {
  const IdentificationResult& m = a.main;
  std::string s;
  s += fmt::format("rotacal analysis: cycle {}, machine {}\n", a.plan->cycle, a.plan->machine.name);
  s += fmt::format("results: {} file(s), {} triggers\n", a.result_files.size(), m.summary.observations);
  s += fmt::format("method: {} ({})\n\n", methodName(m.method), m.summary.message);
  const auto& params = locationParameters(m.estimate.kinematics);
  // The headline's u is what REPORT.json's u is: u_c, the budget's combination.
  const Eigen::VectorXd uc = a.budget.size() == kNumLocationErrors ? a.budget.uC() : Eigen::VectorXd();
  s += fmt::format("{:<8} {:<9} {:>10} {:>9}  {:<5}", "error", "ISO", "value", uc.size() ? "u_c (k=1)" : "u (fit)", "unit");
  for (const auto& o : a.other_methods)
    if (o.summary.termination == Termination::Converged) s += fmt::format(" {:>16}", methodName(o.method));
  s += "\n";
  for (int i = 0; i < kNumLocationErrors; ++i) {
    s += fmt::format("{:<8} {:<9} {:>10.3f} {:>9.3f}  {:<5}", params[i].name, params[i].iso, m.estimate.reportValue(i),
                     uc.size() == kNumLocationErrors ? uc[i] : uReport(m.estimate, m.u, i), reportUnit(params[i].kind));
    for (const auto& o : a.other_methods)
      if (o.summary.termination == Termination::Converged) s += fmt::format(" {:>16.3f}", o.estimate.reportValue(i));
    s += "\n";
  }
  if (m.method != Method::ClosedForm)
    s += fmt::format("\nresidual rms {:.3f} um, noise estimate {:.3f} um ({} dof), rank {}/{}, condition {:.3g}\n",
                     m.summary.residual_rms_um, m.summary.sigma_um, m.summary.dof, m.summary.rank,
                     m.summary.parameters, m.summary.condition);
  s += "\n" + budgetText(a.budget, [&] {
    Eigen::VectorXd v(kNumLocationErrors);
    for (int i = 0; i < kNumLocationErrors; ++i) v[i] = m.estimate.reportValue(i);
    return v;
  }());
  if (a.per_run.size() > 1) {
    s += "\nper run (000 Table 4 layout):\n";
    s += fmt::format("{:<8}", "error");
    for (size_t r = 0; r < a.per_run.size(); ++r) s += fmt::format(" {:>9}", fmt::format("run {}", r + 1));
    s += "\n";
    for (int i = 0; i < kNumLocationErrors; ++i) {
      s += fmt::format("{:<8}", params[i].name);
      for (const auto& r : a.per_run) s += fmt::format(" {:>9.3f}", r.estimate.reportValue(i));
      s += fmt::format("  {}\n", reportUnit(params[i].kind));
    }
  }
  return s;
}

}  // namespace rotacal
