#pragma once
// Plan design: given a probe budget (a number of touches), choose the poses and the points of a
// touch cycle on the square-column piece that minimise the uncertainty of the location errors
// identified by the least squares (`least_squares` of cycles/touch154/uncertainty.hpp: one surface offset
// per target, the squareness of the linear axes fitted alongside).
//
// The criterion is not the textbook white-noise one: the uncertainty that matters comes mostly
// from the linear axes (000 Table 5), which are correlated between touches. For a set of points S
// the estimator is the least squares restricted to S, and its covariance is the sandwich
//     Cov(S) = M^-1 (J~^T C_SS J~ + L P L) M^-1,   M = J~^T J~ + L,
// with J~ the Jacobian of the location errors and the squareness with the per-target offsets
// eliminated, C the trigger covariance of the contributors (triggerCovariance: the same
// first-order model as the Monte Carlo), L a vanishing ridge and P the prior covariance (1 mm,
// 10 mrad, 1 mm/m): together they charge a parameter the subset cannot identify yet its prior
// variance, which keeps the first steps of the search defined. A-optimal: minimise
// sum_p (u_p / r_p)^2 over the location errors, r_p the reference uncertainties of the
// contributors file (000 Table 6) or 1 um / 1 mdeg, plus 0.01 x the squareness variances in
// (1 um/100mm)^2 (it must stay identifiable: least_squares fits it). D-optimal: minimise log det
// of the covariance of all eleven in the same scaled units. The search is
// greedy forward selection, then exchange passes (swap a chosen point for a candidate while the
// criterion improves).
//
// Candidates: the poses A x C of the options (A/C table) that fit the strokes, and on each face
// of the piece a grid of targets; a target is a candidate at a pose when a vertical stylus
// reaches it by the rule of the touch154 plan (cycles/touch154/plan.hpp: no face pointing down; on a
// face not facing up the probe body, stylus_length above the ball, clears the piece's top by
// body_clearance) and its probing moves stay within the strokes.
#include <functional>
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/error_model.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct DesignOptions {
  int points = 77;  // the probe budget
  std::vector<double> a_deg{0.0, -90.0};
  std::vector<double> c_deg{0.0, 90.0, 180.0, 270.0};
  std::vector<double> side_offsets_mm{-40, -20, 0, 20, 40};  // along each side face, from its centre
  std::vector<double> side_depths_mm{10, 30};                // below the top
  std::vector<double> top_offsets_mm{-40, -20, 0, 20, 40};   // grid on the top, from its centre
  enum class Criterion { A, D } criterion = Criterion::A;
  int exchange_passes = 2;
  /// Called after each slot of each exchange pass with (slots done, slots in all); may be empty.
  std::function<void(int done, int total)> progress;

  bool validate(std::string* why) const;
};

struct DesignResult {
  ProbePlan plan;                      // ids in probing order, times estimated
  int candidates = 0;                  // candidate touches (pose x target) considered
  std::vector<std::string> notes;      // e.g. poses left out and why
  ErrorVector predicted_u = ErrorVector::Zero();  // sqrt(diag Cov(S)), mm / rad (first order)
  double criterion = 0.0;              // final value (A: sum of squared ratios; D: log det)
  int exchanges = 0;                   // swaps made by the exchange passes
};

/// Designs a plan for an A/C table with a square-column artefact. Throws std::invalid_argument
/// on bad options, a machine without the artefact, or too few reachable candidates.
DesignResult designPlan(const MachineModel& machine, const ContributorSet& contributors, const DesignOptions& options);

/// The candidate touches (every reachable pose x target) as one plan, for inspection and tests.
ProbePlan designCandidates(const MachineModel& machine, const DesignOptions& options, std::vector<std::string>* notes);

}  // namespace rotacal
