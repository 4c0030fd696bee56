#include "cli/cmd_spaceframe.hpp"
#include "cli/output.hpp"

#include <stdexcept>

#include "core/json_io.hpp"
#include "core/spaceframe.hpp"

namespace rotacal {

int analyzeSpaceframeCommand(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                             const std::vector<std::string>& result_files, const std::string& json_out,
                             const std::string& text_out, const std::string& offsets_out, const std::string& html_out) {
  if (!offsets_out.empty())
    throw CLI::ValidationError("--offsets", "a spaceframe analysis is a performance test: it writes no offsets "
                                            "(calibrate with touch154 and use its offsets)");
  SpaceframeAnalysis a;
  try {
    a = analyzeSpaceframe(plan, runs);
  } catch (const std::invalid_argument& e) {
    failFile(result_files.front(), e.what());
  }
  const std::string text = spaceframeText(a, plan);
  writeDocuments(c, spaceframeReportJson(a, plan, result_files), text, json_out, text_out, html_out);
  if (a.summary.termination != "converged")
    std::fprintf(stderr, "rotacal: warning: spaceframe identification %s\n", a.summary.termination.c_str());
  return 0;
}

}  // namespace rotacal
