#pragma once
// What every document a cycle writes shares (REPORT.json, DIAGNOSIS.json: contract.md): the
// envelope that names the format, the cycle, the machine and the files it came from, the
// location errors in report units, and the rounding of the numbers it carries. Each cycle fills
// the rest.
#include <string>
#include <string_view>
#include <vector>

#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/least_squares.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// Numbers in documents: 1e-6 of their report unit (um, mdeg), far below any uncertainty and
/// enough that a document read back reproduces the printed tables.
double round6(double v);

/// {format, cycle, machine, machine_model, results}. `machine_model` makes the document
/// self-contained for `compensate` and the history (they never need the plan again).
/// A fit's summary as every report states it: termination, message, iterations, observations,
/// parameters, rank, condition (null when infinite), dof, sigma_um, residual_rms_um.
Json fitSummaryJson(const FitSummary& s);

Json documentEnvelope(std::string_view format, const ProbePlan& plan, const std::vector<std::string>& result_files);

/// The location errors in report units (um, mdeg) with their standard uncertainty (k = 1) and
/// ISO 230-7 names.
/// The location errors as plain values in the report's units (um, mdeg), by name: what a
/// simulation injected, to be compared with what a report identified.
Json locationErrorValues(const LocationErrors& e);

Json locationErrorsJson(const LocationErrors& estimate, const ErrorVector& u);

}  // namespace rotacal
