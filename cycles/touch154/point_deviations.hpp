#pragma once
// Per-touch deviations for the report's views of 000 Figs. 7-9: where each touch triggered
// against where a perfect machine would have triggered, along the face's outward normal, raw
// (Fig. 7: includes the test piece's setup and form) and relative to the same target at pose I
// (000 Eq. (21), Figs. 8-9: setup and form cancel, the rotary axes' errors remain).
#include <vector>

#include "cycles/touch154/identification.hpp"
#include "core/json_io.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// REPORT.json "points": one entry per trigger of every run, in run then plan order:
/// {"run", "point", "pose_name", "pose": {"A","B","C"} (deg), "face", "target", "t_s" (s or null),
///  "contact_m_mm": nominal contact on a perfect machine (mm), "normal_m": outward normal there,
///  "dev_um": (measured - nominal) . normal_m, "rel_dev_um": dev_um minus the same target's dev_um
///  at the plan's first pose in the same run (null where that pose lacks the target),
///  "residual_um": measured - fitted model along the approach (null when not fitted)}.
Json pointDeviationsJson(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                         const IdentificationResult& fit);

}  // namespace rotacal
