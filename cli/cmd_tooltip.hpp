#pragma once
// The tooltip cycle (004) through simulate, analyze and diagnose: its results come from the
// laser system, not the controller, so they are the neutral file `angle_deg,dy_um,dz_um`
// whatever --dialect says.
#include <cstdint>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

int simulateTooltipCmd(const Common& c, const ProbePlan& plan, const std::string& truth_file, double noise_um,
                       bool noise_given, std::uint64_t seed, const std::string& out);
int analyzeTooltipCmd(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results,
                      const std::string& json_out, const std::string& text_out, const std::string& html_out);
int diagnoseTooltipCmd(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results, double alpha,
                       const std::string& json_out, const std::string& text_out, const std::string& html_out);

}  // namespace rotacal
