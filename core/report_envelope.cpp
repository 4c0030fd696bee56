#include "core/report_envelope.hpp"

#include <cmath>

#include "core/machine.hpp"
#include "core/units.hpp"

namespace rotacal {

double round6(double v) { return std::round(v * 1e6) / 1e6; }

Json fitSummaryJson(const FitSummary& s) {
  return {{"termination", std::string(terminationName(s.termination))},
          {"message", s.message},
          {"iterations", s.iterations},
          {"observations", s.observations},
          {"parameters", s.parameters},
          {"rank", s.rank},
          {"condition", std::isfinite(s.condition) ? Json(s.condition) : Json(nullptr)},
          {"dof", s.dof},
          {"sigma_um", round6(s.sigma_um)},
          {"residual_rms_um", round6(s.residual_rms_um)}};
}

Json documentEnvelope(std::string_view format, const ProbePlan& plan, const std::vector<std::string>& result_files) {
  Json j;
  j["format"] = std::string(format);
  j["cycle"] = plan.cycle;
  j["machine"] = plan.machine.name;
  j["machine_model"] = machineToJson(plan.machine);
  j["results"] = result_files;
  return j;
}

Json locationErrorValues(const LocationErrors& e) {
  Json j = Json::object();
  const auto& params = locationParameters(e.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i) j[std::string(params[i].name)] = e.reportValue(i);
  return j;
}

Json locationErrorsJson(const LocationErrors& e, const ErrorVector& u) {
  Json j = Json::object();
  const auto& params = locationParameters(e.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double ur = params[i].kind == ParamKind::Length ? mmToUm(u[i]) : radToMdeg(u[i]);
    j[std::string(params[i].name)] = {{"value", e.reportValue(i)},
                                      {"unit", std::string(reportUnit(params[i].kind))},
                                      {"u", ur},
                                      {"iso", std::string(params[i].iso)}};
  }
  return j;
}

}  // namespace rotacal
