#include "cli/spheres3_cli.hpp"
#include "cli/output.hpp"

#include <cstdio>
#include <stdexcept>

#include "core/json_io.hpp"
#include "core/spheres3_diagnosis.hpp"
#include "core/spheres3_identification.hpp"

namespace rotacal {

int analyzeSpheres3(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                    const std::vector<std::string>& result_files, const std::string& json_out,
                    const std::string& text_out, const std::string& offsets_out, const std::string& html_out) {
  if (!offsets_out.empty())
    throw CLI::ValidationError("--offsets",
                               "spheres3 identifies component errors as functions of C: they need the controller's "
                               "rotary compensation table, which no dialect writes yet");
  Spheres3Options opt;
  opt.prior_sigma_um = plan.machine.probe.repeatability_um;
  Spheres3Result r;
  try {
    r = identifySpheres3(plan, runs, opt);
  } catch (const std::invalid_argument& e) {
    failFile(result_files.front(), e.what());
  }
  const std::string text = spheres3Text(r);
  writeDocuments(c, spheres3ReportJson(plan, r, result_files), text, json_out, text_out, html_out);
  return 0;
}

int diagnoseSpheres3Cli(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                        const std::vector<std::string>& result_files, double alpha, const std::string& json_out,
                        const std::string& text_out, const std::string& html_out) {
  DiagnosisOptions o;
  o.alpha = alpha;
  o.prior_sigma_um = plan.machine.probe.repeatability_um;
  std::string why;
  if (!o.validate(&why)) throw CLI::ValidationError("--alpha", why);
  Spheres3Diagnosis d;
  try {
    d = diagnoseSpheres3(plan, runs, o);
  } catch (const std::invalid_argument& e) {
    failFile(result_files.front(), e.what());
  }
  const std::string text = spheres3DiagnosisText(d);
  writeDocuments(c, spheres3DiagnosisJson(d), text, json_out, text_out, html_out);
  return 0;
}

}  // namespace rotacal
