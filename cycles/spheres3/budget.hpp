#pragma once
// The uncertainty the spheres3 cycle signs (core/uncertainty_budget.hpp) for its four
// location errors (Oxc Oyc Sxc Syc = X0C Y0C A0C B0C) and its component errors at the sampled
// angles:
//   Type A  the per-touch scatter (probe repeatability, surface roughness / the sphere's form
//           under the ball: the table turns, so every touch meets another point of the sphere)
//           through the estimator's linear map G, sigma^2 G G^T / repeats, with
//           sigma^2 = max(declared, s^2 - E[s_sys^2]): s the stage-1 touch noise (the sphere fits'
//           residual), E[s_sys^2] what the Type B contributors leave in it; repeats that scatter
//           more raise a parameter to the scatter of their mean;
//   Type B  the declared contributors that act on three spheres touched from +-X, +-Y, -Z
//           (probe pretravel per direction, the linear axes' scale, random and squareness errors),
//           by Monte Carlo: every run draws them, simulates the 180 triggers on the exact
//           simulator (full HTMs, exact ball-on-sphere contact) around the identified errors and
//           runs the triggers' deviation through the estimator linearised at the identified
//           errors (stage 1 and stage 2 by their own least-squares maps; the test
//           Spheres3Budget.LinearisedDeviationMatchesTheExactEstimator compares it with
//           identifySpheres3 run by run). Deviation = estimate - truth, bias counted.
// Contributors of a cube (set-up, form_error of faces) and of the R-test do not act on spheres:
// the report names them as left out. docs/uncertainty.md (spheres3) states the coverage measured.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/contributor_draw.hpp"
#include "core/contributors.hpp"
#include "core/linear_axes.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "core/uncertainty_budget.hpp"
#include "cycles/spheres3/analyze.hpp"

namespace rotacal {

struct Spheres3BudgetOptions : BudgetOptions {};

/// Contributors that act independently at every touch: the sphere fits' residual measures them.
bool spheres3TypeA(const ContributorInfo& contributor);
/// Contributors that act on the three-sphere cycle as Type B.
bool spheres3TypeB(const ContributorInfo& contributor);

/// The estimator linearised at an identification: d theta = G d s, theta = [Oxc Oyc Sxc Syc |
/// spheres | series terms] (mm, rad), s the trigger of each plan point (plan order) along its
/// approach (mm), for one run. Built from the exact simulator's triggers at the identified errors.
struct Spheres3LinearMap {
  Eigen::MatrixXd G;               // parameters x plan points
  Eigen::MatrixXd values;          // component errors at the sampled angles: (6 a + k) x plan points
  Eigen::MatrixXd residual;        // stage-1 sphere-fit residuals from d s (touches x plan points)
  int stage1_dof = 0;              // per run
  Eigen::VectorXd ideal_s_mm;      // the ideal triggers along the approach (identified truth)
};

/// The truth of the identified errors: the table of the stage-2 model, the fitted spheres.
Truth spheres3IdentifiedTruth(const ProbePlan& plan, const Spheres3Result& result);
Spheres3LinearMap linearSpheres3(const ProbePlan& plan, const Spheres3Result& result);

/// One drawn realisation of the Type B contributors (pretravel, the linear axes) as a truth modifier.
using Spheres3Draw = ProbeAxesDraw;
/// Draws run `run` of `seed` from `set` (only the spheres3TypeB contributors); with `only` >= 0
/// every contributor but set.items[only] is zero. One random stream per contributor, so a
/// contributor draws the same values alone and combined.
void drawSpheres3(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, int run, int only,
                  Spheres3Draw* out);
void applySpheres3Draw(const Spheres3Draw& draw, Truth* truth);

struct Spheres3Budget {
  UncertaintyBudget location;                // Oxc Oyc Sxc Syc, report units (um, mdeg)
  /// Component errors at the sampled angles (rows) x EXC..ECC, report units.
  Eigen::MatrixXd component_u_a, component_u_b, component_u_c;
  Eigen::MatrixXd component_k;  // each one's coverage factor (UncertaintyBudget::coverage_factor)
  std::string coverage_source;  // coverageFactorSource of the whole budget
  Eigen::MatrixXd componentExpanded() const { return component_k.cwiseProduct(component_u_c); }
};

/// The budget of `result` (identified from per_run.size() repeats, or one run when per_run is
/// empty). `contributors` null: u_B not evaluated (said in words).
Spheres3Budget spheres3Budget(const ProbePlan& plan, const Spheres3Result& result,
                              const std::vector<Spheres3Result>& per_run, const ContributorSet* contributors,
                              const Spheres3BudgetOptions& options);

/// Adds u_a, u_b, u_c, U and k to REPORT.json's `location_errors` and `component_errors`, and the
/// `uncertainty` block.
void addSpheres3Budget(Json* report, const Spheres3Budget& budget);

}  // namespace rotacal
