#pragma once
// The curves of a diagnosis for the HTML report (`figures`, docs/reports.md): the baseline's
// residuals against time and against the C angle, beside those of the model extended with each
// finding, so that the reader sees the disagreement and what the named cause removes.
#include "core/diagnosis.hpp"
#include "core/json_io.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

Json diagnosisFigures(const Diagnosis& d, const ProbePlan& plan);

}  // namespace rotacal
