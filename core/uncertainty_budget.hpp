#pragma once
// The uncertainty a report signs (issue 17), the same for every cycle: per parameter
//   u_A  what the data's own scatter says (Type A: the fit's covariance scaled by its residual,
//        or the scatter of the repeats' estimates when there are repeats, the larger);
//   u_B  the declared contributors the data cannot show (Type B: pre-travel, the linear axes,
//        set-up, form, the instrument), propagated by Monte Carlo through the cycle's own
//        estimator (GUM Supplement 1); contributors that act independently at every reading
//        (repeatability, roughness) are left to u_A, which measures them, so nothing is counted
//        twice;
//   u_c = sqrt(u_A^2 + u_B^2), U = k u_c with k = 2;
// the combined covariance (cov_A + cov_B) and its correlation matrix, and the budget: each
// contributor's share alone. Cycle-neutral: a cycle hands in the numbers (report units: um, mdeg,
// um/h, ...); this file combines and writes them. docs/uncertainty.md states the rules and the
// coverage measured.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/json_io.hpp"

namespace rotacal {

/// The coverage factor of every expanded uncertainty rotacal writes (about 95 %, normal).
constexpr double kCoverageFactor = 2.0;

/// Contributors drawn anew at every calibration: the artefact's set-up on the table, the R-test
/// sphere's mounting on the spindle, the laser's alignment, the thermal state of the cycle. The
/// others (the linear axes, the probe's pretravel, the artefact's form, the sensors' calibration)
/// belong to the machine and its instruments and repeat.
bool variesBetweenCalibrations(const ContributorInfo& contributor);

struct BudgetTerm {
  std::string contributor;  // a contributor id, or "data" for the Type A part
  Eigen::VectorXd u;        // its standard uncertainty alone, per parameter, report units
};

struct UncertaintyBudget {
  std::vector<std::string> names;  // parameters, in the report's order
  std::vector<std::string> units;  // their report units
  Eigen::MatrixXd cov_a;           // Type A covariance, report units squared
  Eigen::MatrixXd cov_b;           // Type B covariance (Monte Carlo); zero when not evaluated
  std::string type_a_source;       // one sentence: where u_A comes from
  bool type_b_evaluated = false;
  std::string type_b_source;       // one sentence: contributors, estimator, runs, seed; or why none
  std::vector<BudgetTerm> terms;   // "data" first, then each contributor alone (catalog order)
  int runs = 0;
  std::uint64_t seed = 0;

  int size() const { return static_cast<int>(names.size()); }
  Eigen::VectorXd uA() const;
  Eigen::VectorXd uB() const;
  Eigen::VectorXd uC() const;
  /// What differs between two calibrations of the same machine: u_A and the contributors drawn
  /// anew at every set-up (variesBetweenCalibrations), each alone from the budget's terms. The
  /// machine's own systematic errors (its linear axes, the artefact's form) are the same in every
  /// calibration and cancel in a comparison: history trends with this, not with u_c.
  Eigen::VectorXd uBetween() const;
  Eigen::VectorXd expanded() const { return kCoverageFactor * uC(); }
  Eigen::MatrixXd covariance() const { return cov_a + cov_b; }
  Eigen::MatrixXd correlation() const;  // 0 where a variance is 0
  bool validate(std::string* why) const;
  /// Parameters first..first+count-1 alone (their covariance blocks and budget terms).
  UncertaintyBudget slice(int first, int count) const;
};

/// The Monte Carlo settings of every cycle's budget (analyze --mc-runs, --mc-seed).
struct BudgetOptions {
  int runs = 2000;        // Monte Carlo runs with every contributor
  int alone_runs = 400;   // runs of each contributor alone (the budget table's shares)
  std::uint64_t seed = 1;
  int threads = 0;        // 0: all cores
  bool validate(std::string* why) const;
  void validateOrThrow() const;  // std::invalid_argument with the reason
};

/// u_B's sentence when the machine declares no contributors.
std::string typeBNotDeclared();

/// Repeats: a parameter whose repeats scatter more than cov_a says (drift between runs, a set-up
/// that moved) takes the variance of the repeats' mean instead, correlations kept by scaling.
/// `per_repeat` holds each repeat's own estimate (report units). Returns the clause for the
/// budget's type_a_source; cov_a is unchanged with fewer than two repeats (empty clause).
std::string raiseToRepeatScatter(Eigen::MatrixXd* cov_a, const std::vector<Eigen::VectorXd>& per_repeat);

/// Mean and covariance of Monte Carlo samples (one vector per run), accumulated in one pass.
class SampleMoments {
 public:
  explicit SampleMoments(int dimension);
  void add(const Eigen::VectorXd& sample);
  void merge(const SampleMoments& other);
  int count() const { return n_; }
  Eigen::VectorXd mean() const;
  Eigen::MatrixXd covariance() const;  // divisor n - 1; zero below two samples

 private:
  int n_ = 0;
  Eigen::VectorXd sum_;
  Eigen::MatrixXd sum_outer_;
};

/// A Monte Carlo of a cycle's estimator (GUM Supplement 1): run `run` of `seed` with every
/// contributor drawn (contributor = -1) or one alone (contributor = its index), returning
/// estimate - truth in report units. Each run draws from its own random streams (seed, run), so
/// results do not depend on threads.
struct MonteCarloProblem {
  int parameters = 0;
  std::vector<std::string> contributors;
  std::function<Eigen::VectorXd(std::uint64_t seed, int run, int contributor)> deviation;
};

struct MonteCarloResult {
  SampleMoments combined{0};
  std::vector<SampleMoments> alone;  // per contributor
};

/// Runs `runs` draws with every contributor and `alone_runs` draws of each contributor alone.
MonteCarloResult runMonteCarlo(const MonteCarloProblem& problem, int runs, int alone_runs, std::uint64_t seed,
                               int threads);

/// The Monte Carlo every cycle runs for u_B: `deviation(seed, run, contributor)` (estimate -
/// truth, report units; contributor -1 = all of type_b drawn, else that index alone) over
/// type_b's contributors, options.runs and options.alone_runs; fills cov_b, the terms and the
/// seed. The caller writes type_b_source (what was drawn, through what).
void runTypeB(UncertaintyBudget* budget, const ContributorSet& type_b, const BudgetOptions& options,
              const std::function<Eigen::VectorXd(std::uint64_t seed, int run, int contributor)>& deviation);
/// Where the declared contributors came from, for type_b_source: their file, or "the machine".
std::string contributorsSource(const ContributorSet& declared);

/// Fills cov_b and the contributor terms of `budget` from a Monte Carlo result.
void setTypeB(UncertaintyBudget* budget, const MonteCarloResult& mc, const std::vector<std::string>& contributors);

/// "uncertainty": {k, type_a, type_b, parameters: {name: {unit, u_a, u_b, u_c, U}}, covariance,
/// correlation, budget: {name: [{contributor, u}, ...] largest first]}}.
Json budgetJson(const UncertaintyBudget& budget, int top = 5);
/// Adds u_a, u_b, u_c, U and k to each entry of a parameters object ({name: {value, unit, u}})
/// whose name the budget has; `u` (contract.md: from the data) is left as it is.
void addBudgetFields(Json* parameters, const UncertaintyBudget& budget);
/// The readable table: value beside u_A u_B u_c U, then the largest contributors and the
/// strongest correlations.
std::string budgetText(const UncertaintyBudget& budget, const Eigen::VectorXd& values, int top = 3);

}  // namespace rotacal
