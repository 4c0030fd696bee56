#pragma once
// `rotacal analyze` on a spaceframe plan (003): lengths, verdict, identification, REPORT.json.
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

int analyzeSpaceframeCommand(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                             const std::vector<std::string>& result_files, const std::string& json_out,
                             const std::string& text_out, const std::string& offsets_out, const std::string& html_out);

}  // namespace rotacal
