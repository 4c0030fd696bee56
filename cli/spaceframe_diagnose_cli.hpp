#pragma once
// `rotacal diagnose` for a spaceframe plan (003): linear-axis scale errors beyond the location
// errors and the frame's setup (core/spaceframe_diagnosis.hpp).
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

int diagnoseSpaceframeCli(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                          const std::vector<std::string>& result_files, double alpha, const std::string& json_out,
                          const std::string& text_out, const std::string& html_out);

}  // namespace rotacal
