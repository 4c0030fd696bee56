#include "cli/spaceframe_diagnose_cli.hpp"
#include "cli/output.hpp"

#include <stdexcept>

#include "core/json_io.hpp"
#include "core/spaceframe_diagnosis.hpp"

namespace rotacal {

int diagnoseSpaceframeCli(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                          const std::vector<std::string>& result_files, double alpha, const std::string& json_out,
                          const std::string& text_out, const std::string& html_out) {
  DiagnosisOptions o;
  o.alpha = alpha;
  o.prior_sigma_um = plan.machine.probe.repeatability_um;
  std::string why;
  if (!o.validate(&why)) throw CLI::ValidationError("--alpha", why);
  SpaceframeDiagnosis d;
  try {
    d = diagnoseSpaceframe(plan, runs, o);
  } catch (const std::invalid_argument& e) {
    failFile(result_files.front(), e.what());
  }
  if (!d.baseline.converged || !d.candidate.converged)
    failFile(result_files.front(), "spaceframe diagnosis: a model fit did not converge");
  const std::string text = spaceframeDiagnosisText(d);
  writeDocuments(c, spaceframeDiagnosisJson(d, plan), text, json_out, text_out, html_out);
  return 0;
}

}  // namespace rotacal
