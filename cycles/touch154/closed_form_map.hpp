#pragma once
// The closed form of 000 (cycles/touch154/closed_form.hpp) as what it is: a fixed linear map of the
// triggers. Every pattern value is a mean of relative displacements (000 Eq. (21)), linear in the
// measured coordinates and zero at the nominal triggers, and the eight pattern equations are
// solved with constant (nominal, first-order) coefficients, so
//
//     estimate = G s,   s = trigger displacements along the approach from the nominal triggers.
//
// Which A = 0 -> A = -90 pose pairs feed Patterns 3-a, 3-b and 3-c is a choice the printed paper
// leaves to its missing Figs. 2(e)-(g) and 5:
//  - tiltPairsPooled(): II->V, III->VI, IV->VII, what `analyze --method closed_form` does
//    (core/closed_form.cpp);
//  - tiltPairs000(): III->VI only (the piece above the A axis at A = -90). This is the reading
//    that reproduces 000 Table 5: S_xy enters b_AY as 0.875 S_xy = 1.50 mdeg (Table 5: 1.5) and
//    S_yz enters dy_AY as (150 mm + 200 mm) / 2 S_yz = 5.3 um (Table 5: 5.5), where the pooled
//    pairs give 2.3 mdeg and 3.6 um (docs/uncertainty.md).
// Patterns 1, 2-a, 2-b, 2-c and 4 are the same in both. The map is built from touch154Patterns
// itself (unit perturbations of each trigger) for those, and for Patterns 3 from the relative
// displacements directly; tests/core/closed_form_map_test.cpp checks that the pooled map equals
// the closed form of core/closed_form.cpp on data.
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "core/error_model.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

using TiltPairs = std::vector<std::pair<std::string, std::string>>;
const TiltPairs& tiltPairsPooled();
const TiltPairs& tiltPairs000();

using ClosedFormMatrix = Eigen::Matrix<double, kNumLocationErrors, Eigen::Dynamic>;

/// G (8 x points, mm or rad per mm of trigger displacement). Throws std::invalid_argument when the
/// plan lacks what a pattern needs (as touch154Patterns does).
ClosedFormMatrix closedFormMap(const ProbePlan& plan, const TiltPairs& pairs);

/// J_s_e: derivative of every trigger (along its approach, mm) with respect to the eight location
/// errors (mm/mm, mm/rad) at the given errors, by central differences of the exact simulator
/// (steps 0.1 um and 1 urad: truncation below 1e-9 relative).
Eigen::MatrixXd J_s_e(const ProbePlan& plan, const LocationErrors& at);

/// Value map of one Pattern 3 over the given pairs: its value is map * s. `pattern` is "3-a",
/// "3-b" or "3-c". Also returns the number of point pairs (0: the pattern has no points).
Eigen::RowVectorXd pattern3Map(const ProbePlan& plan, const std::string& pattern, const TiltPairs& pairs, int* count);

}  // namespace rotacal
