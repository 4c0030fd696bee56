#pragma once
// The uncertainty the rtest cycle signs for the eight location errors, on
// core/uncertainty_budget:
//   Type A  the per-reading scatter (sensor noise, rtest_sphere_form) through the location fit's
//           own map G, sigma^2 G G^T, with sigma from the residual less what the Type B
//           contributors leave in it, floored at the declared scatter;
//   Type B  the declared contributors the data cannot show (002 Sec. 2.2, 4.3, 4.4: sensor gain and
//           direction, the sphere's offset on the spindle, thermal drift over the cycle, the linear
//           axes), by Monte Carlo: each run draws them, simulates the cycle's readings on the exact
//           simulator (simulateRtest, full HTMs) around the identified errors, and runs them
//           through the same estimator (G: exact, the fit is linear in the readings).
// docs/uncertainty.md (rtest) states the rules and the coverage measured.
#include <array>
#include <cstdint>

#include "core/contributors.hpp"
#include "core/linear_axes.hpp"
#include "core/rng.hpp"
#include "core/uncertainty_budget.hpp"
#include "cycles/rtest/analyze.hpp"

namespace rotacal {

struct RtestBudgetOptions : BudgetOptions {};

/// Contributors that act independently at every reading: u_A measures them.
bool rtestTypeA(const ContributorInfo& c);
/// Contributors that act on every reading of the machine alike (drawRtest draws them): Type B.
bool rtestActsAsTypeB(const ContributorInfo& c);

/// One drawn realisation of the R-test's Type B contributors (internal units).
struct RtestDraw {
  Eigen::Matrix3d sensor_response = Eigen::Matrix3d::Identity();
  Eigen::Vector3d sphere_offset_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d cycle_drift_mm = Eigen::Vector3d::Zero();  // over one measuring cycle
  bool linear = false;
  LinearAxisErrors linear_errors;
};

/// Draws run `run` of `seed` from `set` (Type A contributors skipped); with `only` >= 0 every
/// contributor but set.items[only] is zero. The same (seed, run) draws the same values whether
/// alone or combined (one stream per contributor).
void drawRtest(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, int run, int only, RtestDraw* out);
/// Puts a draw on a truth (linear axes) and its extras (sensors, sphere, drift). The drift runs
/// linearly from 0 at the first cycle's start to cycle_drift at rtestCycleTime_s.
void applyRtestDraw(const ProbePlan& plan, const RtestDraw& d, Truth* truth, RtestTruthExtras* extras);
/// What a draw put on the machine, in report units (TRUTH.json's `drawn` of simulate --contributors).
Json rtestDrawJson(const RtestDraw& d);

/// The budget of the eight location errors (report units, order of locationParameters).
/// `contributors` null: u_B not evaluated (said in words). Not identifiable: empty budget.
UncertaintyBudget rtestBudget(const ProbePlan& plan, const RtestCycle& first, const RtestLocationFit& fit,
                              double sensor_sigma_um, const ContributorSet* contributors,
                              const RtestBudgetOptions& options);

/// The per-tilt errors of the first cycle (002 Eq. (6): what the R-test measures at each tilt),
/// 6 x tilts in report units (um, mdeg), order of rtestParameterIndices:
///   u_A  the per-tilt fit's own covariance (the per-reading scatter max(sensor noise, residual)
///        through that fit); it may hold the part of the linear axes' errors the six errors per
///        tilt cannot absorb a second time, which is conservative;
///   u_B  the declared contributors by Monte Carlo through analyzeRtest itself on the exact
///        simulator's first cycle (estimate with a draw minus estimate without).
/// dz and c at the reset's tilt are fixed to 0 by the reset (docs/rtest.md): their u is 0.
struct RtestTiltBudget {
  UncertaintyBudget budget;  // parameters "dx_BY@-60" ..., tilt-major
  int tilts = 0;
  /// Column i of a 6 x tilts matrix of u_A / u_B / u_c.
  Eigen::MatrixXd uA() const;
  Eigen::MatrixXd uB() const;
  Eigen::MatrixXd uC() const;
  Eigen::MatrixXd expanded() const;  // U per tilt: each parameter's own coverage factor
  Eigen::MatrixXd coverageFactors() const;
};
/// `first` is the first cycle's readings as measured (with or without its reset rows: the
/// simulated cycle is read the same way).
RtestTiltBudget rtestTiltBudget(const ProbePlan& plan, const RtestCycle& first, const RtestAnalysis& analysis,
                                const RtestFitOptions& fit_options, const ContributorSet* contributors,
                                const RtestBudgetOptions& options);
/// Adds u_a, u_b, u_c, U and k arrays beside the first cycle's per-tilt values in REPORT.json.
void addRtestTiltBudget(Json* report, const ProbePlan& plan, const RtestTiltBudget& b);

/// The drift rates across cycles (the weighted line per parameter and tilt, 002 Fig. 10):
///   u_A  the trend's own u (the cycles' u, widened by the scatter about the line);
///   u_B  the contributors that do not cancel in a rate: the sensors' gain and cross-talk
///        (rtest_sensor_gain, rtest_sensor_direction) scale what the sensors read of the drift.
///        Propagated to first order (GUM law of propagation) with the derivative of the rates
///        with respect to each entry of the sensors' response, by re-analysis of the measured
///        series with that entry perturbed. The linear axes, the sphere's offset and the drift
///        within a cycle are the same in every cycle and cancel in a rate: named, not counted.
/// Report units per hour (um/h, mdeg/h), 6 x tilts; empty matrices with fewer than 3 cycles.
struct RtestDriftBudget {
  Eigen::MatrixXd u_a, u_b;
  bool type_b_evaluated = false;
  std::string type_b_source;
  Eigen::MatrixXd uC() const { return (u_a.cwiseAbs2() + u_b.cwiseAbs2()).cwiseSqrt(); }
};
RtestDriftBudget rtestDriftBudget(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestAnalysis& analysis,
                                  const RtestFitOptions& fit_options, const ContributorSet* contributors);
/// Adds u_a, u_b, u_c, U and k arrays to REPORT.json's drift block, and its sources.
void addRtestDriftBudget(Json* report, const ProbePlan& plan, const RtestDriftBudget& b);

}  // namespace rotacal
