// The verdict block (core/verdict.hpp).
#include "core/verdict.hpp"

#include <cmath>
#include <vector>

#include <fmt/format.h>

namespace rotacal {

std::string_view verdictText(ParameterVerdict v) {
  switch (v) {
    case ParameterVerdict::NotSignificant: return "not significant: leave as is";
    case ParameterVerdict::WithinTolerance: return "within tolerance";
    case ParameterVerdict::Adjust: return "adjust";
    case ParameterVerdict::Undecided: return "undecided: within U of the tolerance";
    case ParameterVerdict::Significant: return "significant (no tolerance given)";
  }
  return {};
}

ParameterVerdict decide(double value, double U, std::optional<double> tolerance) {
  const double a = std::abs(value);
  if (a <= U) return ParameterVerdict::NotSignificant;
  if (!tolerance) return ParameterVerdict::Significant;
  if (a + U <= *tolerance) return ParameterVerdict::WithinTolerance;
  if (a - U > *tolerance) return ParameterVerdict::Adjust;
  return ParameterVerdict::Undecided;
}

Json verdictJson(const Json& errs, const LocationTolerance& tol) {
  if (!errs.is_object()) return nullptr;
  Json params = Json::object();
  std::vector<std::string> adjust, undecided, significant;
  int not_significant = 0, within = 0;
  for (const auto& [name, e] : errs.items()) {
    if (!e.is_object() || !e.contains("value") || !e.contains("U") || !e["value"].is_number() || !e["U"].is_number())
      continue;
    const std::string unit = e.contains("unit") && e["unit"].is_string() ? e["unit"].get<std::string>() : "";
    const std::optional<double> t = unit == "um" ? tol.length_um : unit == "mdeg" ? tol.angle_mdeg : std::nullopt;
    const double v = e["value"].get<double>(), U = e["U"].get<double>();
    const ParameterVerdict d = decide(v, U, t);
    Json p = {{"value", v}, {"U", U}, {"unit", unit}, {"verdict", std::string(verdictText(d))}};
    if (t) p["tolerance"] = *t;
    if (e.contains("iso")) p["iso"] = e["iso"];
    params[name] = p;
    switch (d) {
      case ParameterVerdict::NotSignificant: ++not_significant; break;
      case ParameterVerdict::WithinTolerance: ++within; break;
      case ParameterVerdict::Adjust: adjust.push_back(name); break;
      case ParameterVerdict::Undecided: undecided.push_back(name); break;
      case ParameterVerdict::Significant: significant.push_back(name); break;
    }
  }
  if (params.empty()) return nullptr;
  auto list = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& n : v) s += (s.empty() ? "" : ", ") + n;
    return s;
  };
  std::string summary;
  if (!adjust.empty()) summary += fmt::format("adjust {}; ", list(adjust));
  if (!undecided.empty()) summary += fmt::format("undecided {}; ", list(undecided));
  if (!significant.empty()) summary += fmt::format("significant {}; ", list(significant));
  if (within) summary += fmt::format("{} within tolerance; ", within);
  summary += fmt::format("{} not significant (within their own U: leave as is)", not_significant);
  Json j = {{"rule", "ISO 14253-1 with U = k u_c: not significant where |value| <= U; within tolerance where |value| + U "
                     "<= T; adjust where |value| - U > T; undecided between"},
            {"parameters", params},
            {"summary", summary}};
  Json t = Json::object();
  if (tol.length_um) t["length_um"] = *tol.length_um;
  if (tol.angle_mdeg) t["angle_mdeg"] = *tol.angle_mdeg;
  j["tolerance"] = tol.any() ? t : Json(nullptr);
  return j;
}

std::string verdictText(const Json& v) {
  if (!v.is_object() || !v.contains("parameters")) return {};
  std::string s = "verdict (" + v["rule"].get<std::string>() + "):\n";
  for (const auto& [name, p] : v["parameters"].items())
    s += fmt::format("  {:<8} {:>10.3f} +- {:<8.3f} {:<5} {}{}\n", name, p["value"].get<double>(), p["U"].get<double>(),
                     p["unit"].get<std::string>(), p["verdict"].get<std::string>(),
                     p.contains("tolerance") ? fmt::format(" (tolerance {:g})", p["tolerance"].get<double>()) : "");
  s += "  " + v["summary"].get<std::string>() + "\n";
  return s;
}

}  // namespace rotacal
