#pragma once
// The geometric errors to compensate, read from one or several REPORT.json of `analyze`
// (contract.md): what a post-processor author calls before compensatePose / compensateMove.
//
// A report is taken by what it holds, never by its cycle's name:
//  - `location_errors` naming every location error of the machine's kinematics (the touch-probe
//    and R-test cycles): the location errors, with `uncertainty.covariance` when it is there;
//  - `location_errors` named by the ISO 230-7 location of one rotary axis at the other's zero
//    (X0C Y0C A0C B0C: the three-sphere cycle): the C axis's location. Alone it gives the
//    kinematics' errors that act at the tilt axis's zero (A/C: dx_AY, dy_CA, a_AY, b_CA; B/C:
//    dx_CB, dy_CB, a_CB, b_BY), the others zero: exact where that cycle measured (tilt 0), and
//    said so. Beside a full report it is a cross-check: the difference is noted with both u;
//  - `component_errors` (EXC ... ECC at sampled angles): the component errors of that axis.
// A covariance may be larger than the location errors' (a fit with more parameters): each
// location error's row is found under its name or the fit's name its entry gives ('parameter').
// Each kind may come from one report only. Every value must be plausible as a correction
// (the offsets writers' limit: 0.5 mm, 100 mdeg) unless `force`.
#include <string>
#include <vector>

#include "core/geometric_errors.hpp"
#include "core/json_io.hpp"

namespace rotacal {

struct ReportErrors {
  GeometricErrors errors;
  /// One line per report: what was taken from it (for the compensated program's header).
  std::vector<std::string> sources;
  /// What the combination could not decide or found: cross-checks, errors assumed zero.
  std::vector<std::string> notes;
};

/// `held_by_controller`: component errors (ISO names, e.g. ECC) a compensation table on the
/// control already holds; they are left out, so that each error is compensated once.
/// A residual report (`analyze --compensated-with`) is refused: it holds what a compensation
/// left, not the machine's errors.
/// Throws InputError(report file, line, why) naming the report and the entry.
ReportErrors errorsFromReports(const std::vector<JsonDoc>& reports, Kinematics kinematics, bool force,
                               const std::vector<std::string>& held_by_controller = {});

/// The errors of one report (errorsFromReports of that report alone).
GeometricErrors errorsFromReport(const JsonDoc& report, Kinematics kinematics, bool force);

}  // namespace rotacal
