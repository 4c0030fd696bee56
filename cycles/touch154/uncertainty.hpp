#pragma once
// The uncertainty of the identified location errors by Monte Carlo simulation of the whole
// calibration chain (000 Sec. 5): in every run the contributors (core/contributors.hpp) are drawn,
// every trigger of the plan is simulated, and the location errors are identified. The standard
// uncertainty (k = 1) of a parameter is the standard deviation of (estimate - truth) over the
// runs, for all contributors together (000 Table 6) and for each contributor alone (000 Table 5,
// right-hand columns).
//
// Estimators (UncertaintyMethod), all fed by the same runs:
//  closed_form         000 Eqs. (14)-(19), corrected, with 000's pose pairs for Patterns 3
//                      (III -> VI; cycles/touch154/closed_form_map.hpp): the reproduction of 000 Table 6
//  closed_form_pooled  `analyze --method closed_form` (Patterns 3 pooled over three pose pairs)
//  least_squares       all points, one surface offset per target (form-immune) and the
//                      squareness S_xy S_xz S_yz of the linear axes fitted alongside:
//                      identify(LeastSquaresPerPoint) with the linear_axis_squareness extension
//                      (cycles/touch154/causes.hpp), as `diagnose` re-estimates them
//  lsq_per_point       `analyze`'s default: identify(LeastSquaresPerPoint), no extension
//  lsq_rigid_setup     `analyze --method lsq_rigid_setup`: the piece as one rigid body on the
//                      table (6 set-up parameters instead of one offset per target): not
//                      form-immune, so the faces' form is part of its deviation
// The closed forms need the poses of 000's 154-point plan; they are left out for other plans.
//
// Two evaluations of the same runs (same random numbers):
//  - exact: the exact simulator (core/simulation.hpp) of every point, then the estimators
//    themselves, each contributor alone in its own simulation;
//  - linearised (default, about 10^4 times faster): the chain to first order. Each estimator is
//    a fixed linear map of the triggers (G, 8 x points): the closed forms exactly (they are linear
//    in the measured coordinates), the least squares to first order (the rows of the
//    pseudo-inverse of the exact model's Jacobian for the location errors). The triggers are
//    linear in the drawn values, with sensitivities from the exact simulator on unit errors. A
//    run is deviation = G * (sum of the contributors' trigger changes), and each contributor
//    alone is its own term of that sum. tests/core/uncertainty_test.cpp compares both
//    evaluations run by run: the residual of the linearisation.
// Runs are split into blocks; run r draws from its own random streams (seed, r), so results do
// not depend on the number of threads.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/artefact.hpp"
#include "core/contributors.hpp"
#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/linear_axes.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"

namespace rotacal {

enum class UncertaintyMethod { ClosedForm = 0, ClosedFormPooled = 1, LeastSquares = 2, LsqPerPoint = 3, LsqRigidSetup = 4 };
constexpr int kNumUncertaintyMethods = 5;
// closed_form, closed_form_pooled, least_squares, lsq_per_point, lsq_rigid_setup
std::string_view uncertaintyMethodName(UncertaintyMethod m);
UncertaintyMethod uncertaintyMethodFromName(std::string_view name);  // throws std::invalid_argument
std::string_view uncertaintyMethodDescription(UncertaintyMethod m);  // one line, for reports

struct UncertaintyOptions {
  int runs = 1000;
  std::uint64_t seed = 1;
  bool combined_only = false;  // skip the per-contributor table
  bool exact = false;          // exact simulator + the estimators themselves in every run
  int threads = 0;             // 0: all cores (std::thread::hardware_concurrency)
  /// Estimators to evaluate; empty: all that apply to the plan.
  std::vector<UncertaintyMethod> methods;
  /// Location errors of the simulated machine (mm, rad); the chain runs around them.
  LocationErrors truth;
  /// Called after each finished block of runs with (runs done, runs in all); serialised.
  std::function<void(int done, int total)> progress;

  bool validate(std::string* why) const;
};

using IdentificationMap = Eigen::Matrix<double, kNumLocationErrors, Eigen::Dynamic>;

/// Columns of LinearChain::S: the drawn values whose effect on the triggers is a fixed vector.
namespace fixed_var {
constexpr int kPretravel = 0;    // 6: approach along +X -X +Y -Y +Z -Z
constexpr int kScale = 6;        // 3: E_xx,lin E_yy,lin E_zz,lin
constexpr int kSquareness = 9;   // 3: S_xy S_xz S_yz
constexpr int kSetupT = 12;      // 3: translation x y z
constexpr int kSetupR = 15;      // 3: rotation about x y z
constexpr int kForm = 18;        // 15: face f: offset, tilt_u, tilt_v at 18 + 3 f
constexpr int kCount = 33;
}  // namespace fixed_var

/// The chain of a plan to first order around a machine's location errors.
struct LinearChain {
  int points = 0;
  std::array<bool, kNumUncertaintyMethods> has{};  // the estimator applies to the plan
  std::string closed_form_why;                      // why the closed forms do not, when not
  std::string least_squares_why;                    // why least_squares does not, when not
  std::array<IdentificationMap, kNumUncertaintyMethods> G;           // mm or rad per mm of trigger
  std::array<ErrorVector, kNumUncertaintyMethods> bias;              // estimate - truth with no contributor
  Eigen::Matrix<double, Eigen::Dynamic, 3> dsdE;      // trigger change per constant linear-axis error x y z
  Eigen::Matrix<double, Eigen::Dynamic, 3> coord;     // trigger positions, machine frame (node look-up)
  Eigen::MatrixXd S;                                  // points x fixed_var::kCount
  std::array<Eigen::Matrix<double, kNumLocationErrors, fixed_var::kCount>, kNumUncertaintyMethods> GS;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // coordinate span
  /// Orthonormal basis of the lsq_per_point model's column space (points x parameters): the
  /// residual of a trigger change s is s - range_lp range_lp^T s.
  Eigen::MatrixXd range_lp;
  Eigen::MatrixXd range_rs;  // the same for lsq_rigid_setup
  std::string rigid_setup_why;  // why lsq_rigid_setup does not apply, when not
};

/// Builds the linear chain from the exact simulator and the estimators. Throws
/// std::invalid_argument when the plan cannot identify the location errors by least squares.
LinearChain lineariseChain(const ProbePlan& plan, const LocationErrors& truth);

/// The values drawn in one run (internal units), scaled by the contributors' uncertainties.
struct RunDraw {
  Eigen::VectorXd repeat_mm;   // per point, along the approach
  Eigen::VectorXd rough_mm;    // per point, surface height along its outward normal
  std::array<double, 6> pretravel_mm{};  // +X -X +Y -Y +Z -Z
  LinearAxisErrors linear;
  SetupError setup;
  std::array<FaceForm, 5> form{};
};

/// The contributors' uncertainties as the draw needs them (looked up once, not per run).
struct DrawModel {
  double repeat_mm = 0.0, pretravel_mm = 0.0, rough_mm = 0.0;
  LinearAxisModel linear;
  Eigen::Vector3d setup_mm = Eigen::Vector3d::Zero(), setup_rad = Eigen::Vector3d::Zero();
  double form_offset_mm = 0.0, form_tilt_rad = 0.0;
  std::vector<const ContributorInfo*> present;  // the contributors of the set, catalog order
};
DrawModel drawModel(const ContributorSet& contributors);

/// Draws run `run` of seed `seed`. Each group of values has its own random stream (seed, run,
/// group), so a run's values do not depend on other runs, on threads, or on which other
/// contributors are present. Reuses out's storage.
void drawRun(const DrawModel& model, const LinearChain& chain, std::uint64_t seed, int run, RunDraw* out);

/// The drawn values of one contributor alone (all others zero).
RunDraw onlyContributor(const RunDraw& draw, const ContributorInfo& contributor);

/// Which estimators a run evaluates.
using MethodMask = std::array<bool, kNumUncertaintyMethods>;

/// The triggers' change (mm along each approach, plan order) that one draw makes, to first order:
/// what linearisedDeviation maps through every estimator. Its draws are the declared machine a
/// test of the data holds the data against (declared.cpp).
Eigen::VectorXd linearisedTriggerChange(const LinearChain& chain, const RunDraw& draw);

/// Deviation (estimate - truth) of each estimator in `active` for one draw (others: zero):
/// linearised, or through the exact simulator and the estimators. `ok` (exact only) is false
/// when a least-squares identification did not converge.
std::array<ErrorVector, kNumUncertaintyMethods> linearisedDeviation(const LinearChain& chain, const MethodMask& active,
                                                                      const RunDraw& draw);
std::array<ErrorVector, kNumUncertaintyMethods> exactDeviation(const ProbePlan& plan, const LinearChain& chain,
                                                                 const MethodMask& active, const LocationErrors& truth,
                                                                 const RunDraw& draw, bool* ok);

/// The exact model of one draw as a Truth for simulate() (pre-travel and linear axes included;
/// per-touch repeatability and roughness are added to the triggers, see exactDeviation).
Truth truthOfDraw(const LocationErrors& truth, const RunDraw& draw);

/// Covariance (points x points, mm^2) of the triggers' changes caused by the contributors, to
/// first order: the same model as the linearised Monte Carlo, propagated analytically (the node
/// grid's random spacing is integrated numerically). For plan design and as an independent check
/// of the Monte Carlo.
Eigen::MatrixXd triggerCovariance(const LinearChain& chain, const ContributorSet& contributors);

/// Standard uncertainty (k = 1) of an estimator from the trigger covariance: sqrt(diag(G C G^T)).
ErrorVector propagatedUncertainty(const LinearChain& chain, UncertaintyMethod method, const Eigen::MatrixXd& covariance);

struct UncertaintyStat {
  ErrorVector u = ErrorVector::Zero();     // standard deviation over the runs (k = 1), mm / rad
  ErrorVector mean = ErrorVector::Zero();  // mean deviation (bias), mm / rad
};

struct MethodUncertainty {
  UncertaintyMethod method = UncertaintyMethod::LeastSquares;
  std::string description;
  UncertaintyStat combined;
  std::vector<std::pair<std::string, UncertaintyStat>> contributors;  // catalog order
};

struct UncertaintySummary {
  Kinematics kinematics = Kinematics::TableAC;  // names of the parameters
  int runs = 0;
  std::uint64_t seed = 0;
  bool exact = false;
  int threads = 1;
  int points = 0;
  int poses = 0;
  double machine_time_s = 0.0;     // the plan's estimated duration
  double setup_seconds = 0.0;      // building the linear chain
  double run_seconds = 0.0;        // the runs
  int failed = 0;                  // exact: identifications that did not converge (still counted)
  std::string closed_form_why;     // when the closed forms do not apply to the plan
  std::string least_squares_why;   // when least_squares (with squareness) does not
  std::vector<MethodUncertainty> methods;
};

UncertaintySummary runUncertainty(const ProbePlan& plan, const ContributorSet& contributors,
                                  const UncertaintyOptions& options);
/// The same with a prepared chain (benchmarks: the chain is built once per plan).
UncertaintySummary runUncertainty(const ProbePlan& plan, const LinearChain& chain, const ContributorSet& contributors,
                                  const UncertaintyOptions& options);

/// OUT.json of contract.md ("rotacal-uncertainty/1"), with the reference (if any) beside it.
Json uncertaintyToJson(const UncertaintySummary& summary, const ContributorSet& contributors,
                       const std::string& plan_file);
/// The readable tables: per contributor and combined, per method, next to the reference.
std::string uncertaintyText(const UncertaintySummary& summary, const ContributorSet& contributors);

}  // namespace rotacal
