#pragma once
// The curves of a touch154 diagnosis for the HTML report (`figures`, docs/reports.md): the
// baseline's residuals against time and against the C angle, beside those of the model refitted
// with each finding, so that the reader sees the disagreement and what the named cause removes.
#include "core/json_io.hpp"
#include "core/probe_plan.hpp"
#include "cycles/touch154/diagnose.hpp"

namespace rotacal {

Json touch154DiagnosisFigures(const Touch154Diagnosis& d, const ProbePlan& plan);

}  // namespace rotacal
