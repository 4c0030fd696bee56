#pragma once
// `rotacal analyze` and `rotacal diagnose` for the spheres3 cycle (001): the touch-cycle and
// diagnose commands hand a spheres3 plan over to these.
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

int analyzeSpheres3(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                    const std::vector<std::string>& result_files, const std::string& json_out,
                    const std::string& text_out, const std::string& offsets_out, const std::string& html_out);

/// `diagnose` for a spheres3 plan: writes DIAGNOSIS.json (contract) and the summary.
int diagnoseSpheres3Cli(const Common& c, const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                        const std::vector<std::string>& result_files, double alpha, const std::string& json_out,
                        const std::string& text_out, const std::string& html_out);

}  // namespace rotacal
