#pragma once
// The R-test cycle (002) behind simulate and analyze: its readings are the sensor nest's, not
// the controller's, so its results file is the neutral CSV of contract.md whatever the dialect.
#include <cstdint>
#include <string>
#include <vector>

#include "cli/command.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

int rtestSimulate(const Common& c, const ProbePlan& plan, const std::string& truth_file, double noise_um, bool noise_given,
                  std::uint64_t seed, double start_s, const std::string& out);
int rtestAnalyze(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results,
                 const std::string& json_out, const std::string& text_out, const std::string& offsets_out, const std::string& html_out);
int rtestDiagnose(const Common& c, const ProbePlan& plan, const std::vector<std::string>& results,
                  const std::string& json_out, const std::string& text_out, double alpha, const std::string& html_out);

}  // namespace rotacal
