#pragma once
// The trend document of a machine (format rotacal-history/1): its calibrations, the drift and
// step tests of each parameter (history/trend.hpp) and one figure per parameter (value with its
// uncertainty, the k = 2 band, the fitted trend) for the HTML report; and its text form.
#include <string>
#include <vector>

#include "core/json_io.hpp"
#include "history/store.hpp"
#include "history/trend.hpp"

namespace rotacal::history {

Json historyJson(const std::string& machine_id, const std::vector<Calibration>& calibrations, const TrendOptions& options);
std::string historyText(const Json& history);

}  // namespace rotacal::history
