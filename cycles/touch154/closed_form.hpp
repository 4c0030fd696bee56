#pragma once
// The closed-form identification of 000 Sec. 3.2 / 4.3 for 000's 154-point plan.
//
// Each probing pattern (000 Fig. 2) becomes one linear equation in the eight location errors,
// built from the relative displacements of Eq. (21), dp = p(pose) - D_a(-A) D_c(-C) p(I), each
// pattern's value being the mean over its points. The coefficients are the full first-order
// ones, computed from the nominal machine coordinates of the points; for the bundled (centred,
// symmetric) layout they reduce to the printed Eqs. (6)-(13), and solving the eight equations
// is Eqs. (14)-(19). Corrections to the printed equations, each checked against the exact
// simulator in tests/core/closed_form_test.cpp:
//  * Eq. (17) lacks a factor 1/2: dy_CA = (y2b + y1b + 2 z2b a_AY) / 2 - dy_AY.
//  * Eqs. (6), (9), (11), (12) omit terms that vanish only when the points are centred on the
//    rotary axis in machine X (or Y): Pattern 1 has -2 x~ (b_AY + b_CA), Pattern 2-c has
//    -2 y~ a_AY, Pattern 3-b has -(b_AY + c_AY) x~ and Pattern 3-c has (c_AY - b_AY) x~. At
//    A = -90 the reachable points are not centred (x~ = -200 mm at C = 90), so these terms are
//    kept; averaging the poses V and VII cancels them only when both see the same points.
//  * Pattern 4's "angle_z" is the least-squares slope of the relative y displacements against
//    machine X at the two A = -90 poses V and VII (their a_AY terms cancel in the sum, Eq. (13)).
#include <string>
#include <vector>

#include "cycles/touch154/identification.hpp"
#include "core/error_model.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct PatternEquation {
  std::string name;        // "1", "2-a", ... "4"
  std::string equation;    // the printed form, for the report
  double value_mm = 0.0;   // the measured left-hand side (mean over points); rad for Pattern 4
  ErrorVector row = ErrorVector::Zero();  // first-order coefficients on the eight errors
  int points = 0;
};

/// The eight pattern equations of one run. Throws std::invalid_argument when the plan or the
/// run lacks a pose or point a pattern needs.
std::vector<PatternEquation> touch154Patterns(const ProbePlan& plan, const MeasurementRun& run);

/// Solves the pattern equations (000 Eqs. (14)-(19), corrected) for the eight errors.
LocationErrors solvePatterns(const std::vector<PatternEquation>& patterns);

/// 000's estimator over repeats: the closed form of each run, averaged; u propagates the
/// probe's repeatability (um, k = 1) through the (linear) closed form. Never throws: the
/// summary says why when the plan lacks a pattern.
IdentificationResult identifyClosedForm(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                        double prior_sigma_um);
/// identify() for this cycle's plans: the closed form when asked, else the shared least squares.
IdentificationResult identifyTouch154(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                      const IdentificationOptions& options);

}  // namespace rotacal
