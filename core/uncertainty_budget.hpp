#pragma once
// The uncertainty a report signs, the same for every cycle: per parameter
//   u_A  what the data's own scatter says (Type A: the fit's covariance scaled by its residual,
//        or the scatter of the repeats' estimates when there are repeats, the larger);
//   u_B  the declared contributors the data cannot show (Type B: pre-travel, the linear axes,
//        set-up, form, the instrument), propagated by Monte Carlo through the cycle's own
//        estimator (GUM Supplement 1); contributors that act independently at every reading
//        (repeatability, roughness) are left to u_A, which measures them, so nothing is counted
//        twice;
//   u_c = sqrt(u_A^2 + u_B^2), U = k u_c with k read off the propagated distribution for 95.45 %
//   (JCGM 101 7.7; k = 2, the normal value, when there is no Monte Carlo to read it from);
//   u_c is what a REPORT.json's `u` is, in every cycle (setUncertaintyFields);
// the combined covariance (cov_A + cov_B) and its correlation matrix, and the budget: each
// contributor's share alone. Cycle-neutral: a cycle hands in the numbers (report units: um, mdeg,
// um/h, ...); this file combines and writes them. docs/uncertainty.md states the rules and the
// coverage measured.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "core/contributors.hpp"
#include "core/json_io.hpp"

namespace rotacal {

/// The coverage probability every expanded uncertainty U rotacal writes stands for: that of
/// k = 2 for a normal distribution, P(|Z| <= 2) = 95.45 %.
constexpr double kCoverageProbability = 0.954499736103642;
/// The coverage factor when the distribution is taken as normal: no Monte Carlo (u_B not
/// evaluated, or evaluated to first order), or too few runs for its tail (below).
constexpr double kCoverageFactor = 2.0;
/// Monte Carlo runs from which the coverage factor is read off the propagated distribution
/// (JCGM 101 Sec. 7.7): with 1000 runs, 45 lie beyond the 95.45 % point, and k's relative
/// standard error is about 3 % for a normal distribution. Fewer runs: kCoverageFactor.
constexpr int kMinRunsForCoverageFactor = 1000;

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
  /// Per parameter: U = k u_c holds kCoverageProbability of the combined distribution, the Monte
  /// Carlo's deviations (bias included) convolved with the normal Type A part (setTypeB). A
  /// distribution with lighter tails than a normal's (a bounded or mixed contributor) gets k < 2,
  /// heavier tails k > 2. Empty: kCoverageFactor for every parameter.
  Eigen::VectorXd coverage_factor;

  int size() const { return static_cast<int>(names.size()); }
  Eigen::VectorXd uA() const;
  Eigen::VectorXd uB() const;
  Eigen::VectorXd uC() const;
  /// u_c of the parameter named `name`, or `otherwise` when the budget has none of that name
  /// (a text headline prints what REPORT.json's u holds).
  double uCOr(std::string_view name, double otherwise) const;
  /// What differs between two calibrations of the same machine: u_A and the contributors drawn
  /// anew at every set-up (variesBetweenCalibrations), each alone from the budget's terms. The
  /// machine's own systematic errors (its linear axes, the artefact's form) are the same in every
  /// calibration and cancel in a comparison: history trends with this, not with u_c.
  Eigen::VectorXd uBetween() const;
  Eigen::VectorXd coverageFactors() const;
  Eigen::VectorXd expanded() const { return coverageFactors().cwiseProduct(uC()); }
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

/// The significance level at which the data's residual is taken to show a per-reading scatter
/// larger than the declared one (readingScatter). 5 %, not the judge's 1 %: here a missed excess
/// costs coverage, a false one only a slightly wider U.
constexpr double kScatterExcessAlpha = 0.05;

/// The per-reading variance u_A rests on, in um^2, and one clause saying why.
struct ReadingScatter {
  double variance_um2 = 0.0;
  double p_value = 1.0;  // of the residual under the declared scatter plus the contributors' residual
  std::string why;
};
/// The rule every cycle's u_A follows. The fit's residual variance `observed_um2` (dof degrees of
/// freedom) holds the per-reading scatter and the part of the Type B contributors the model
/// cannot absorb (u_B counts that part). Under "the declared scatter is right" it is
/// declared chi^2_dof / dof plus a systematic share whose distribution `systematic_um2` samples
/// (the residual variance of noise-free simulations with the contributors drawn, through the
/// same fit; empty when none act). p = mean_j P(declared chi^2_dof / dof >= observed - s_j).
/// p >= kScatterExcessAlpha: the declared scatter. Else the residual less the contributors' mean
/// share, never below the declared. (Taking that difference always, floored, gave every machine
/// whose own linear-axis draw left a residual above the mean a larger u_A: 4 times too large
/// for the R-test's dx_CB.)
ReadingScatter readingScatter(double declared_um2, double observed_um2, int dof, const std::vector<double>& systematic_um2);

/// readingScatter's contributor samples: the residual variance (um^2 per reading) that each of
/// `draws` noise-free draws of the Type B contributors leaves in the cycle's own fit.
/// `residual_um2` gets the draw's seed (a stream of its own, apart from the Monte Carlo's draws
/// under the same budget seed) and the draw's index.
std::vector<double> contributorResidualVariances(int draws, std::uint64_t budget_seed,
                                                 const std::function<double(std::uint64_t seed, int draw)>& residual_um2);

/// u_B's sentence when the machine declares no contributors.
std::string typeBNotDeclared();

/// The two ways a budget has no Monte Carlo to run: no contributor declared (u_B not evaluated:
/// typeBNotDeclared()) or none of them acting on `acts_on` as Type B (evaluated, u_B = 0; `note`
/// is appended to the sentence). Fills type_b_source and returns false in both; true: run it.
bool typeBToRun(UncertaintyBudget* budget, bool declared, bool any_acting, std::string_view acts_on,
                std::string_view note = {});

/// Repeats: a parameter whose repeats scatter significantly more than cov_a says (chi-square at
/// kScatterExcessAlpha: drift between runs, a set-up that moved) takes the variance of the
/// repeats' mean instead, correlations kept by scaling.
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
  Eigen::MatrixXd deviations;        // parameters x runs: every run with all contributors, in run order
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
/// type_b_source's note on the declared contributors that do not act on `acts_on` (what the cycle
/// reads) and were left out: "; not acting on <acts_on> and left out: a, b", "" when none was.
std::string leftOutNote(std::string_view acts_on, const std::vector<std::string>& left_out);
/// type_b_source of a cycle's Monte Carlo: "<n> declared contributors (from <file>) drawn on
/// <how>, <runs> runs, seed <seed><note>", `how` saying on what they were drawn and through which
/// estimator.
std::string typeBDrawnSource(size_t n, const ContributorSet& declared, std::string_view how, const BudgetOptions& options,
                             std::string_view note);

/// Fills cov_b, the contributor terms and the coverage factors of `budget` from a Monte Carlo
/// result. cov_a must already hold the Type A part: the coverage factor convolves it in.
void setTypeB(UncertaintyBudget* budget, const MonteCarloResult& mc, const std::vector<std::string>& contributors);

/// One sentence: where the coverage factors come from (the Monte Carlo's distribution, or k = 2).
std::string coverageFactorSource(const UncertaintyBudget& budget);

/// "uncertainty": {coverage_probability, coverage_factor (its source), type_a, type_b, parameters:
/// {name: {unit, u_a, u_b, u_c, U, k}}, covariance, correlation, budget: {name: [{contributor, u},
/// ...] largest first]}}. `values` (report units, the budget's order), when given, adds each
/// parameter's value beside its uncertainty.
Json budgetJson(const UncertaintyBudget& budget, const Eigen::VectorXd& values = Eigen::VectorXd(), int top = 5);
/// The one meaning of `u` in every REPORT.json (contract.md: the standard uncertainty, k = 1):
/// u = u_c = sqrt(u_a^2 + u_b^2), written beside u_a (the data's part), u_b (the declared
/// contributors'), u_c, U = k u_c and k, and u_between when it is given (>= 0). Every number a
/// cycle signs goes through here, so the fields cannot disagree between cycles.
void setUncertaintyFields(Json* entry, double u_a, double u_b, double k, double u_between = -1.0);
/// The same for an entry that holds a value per angle or tilt: each field an array, element by
/// element (u_a, u_b and k of equal length).
void setUncertaintyArrays(Json* entry, const Eigen::VectorXd& u_a, const Eigen::VectorXd& u_b, const Eigen::VectorXd& k);
/// A number for which no Type B is evaluated (the cycle declares none for it): u = u_c = u_a,
/// u_b = 0 and U = kCoverageFactor u_c. The report must say in words that u_B was not evaluated.
void setTypeAOnlyFields(Json* entry, double u_a);
/// Adds u_a, u_b, u_c, u_between, U and k to each entry of a parameters object ({name: {value,
/// unit, u}}) whose name the budget has, and sets its `u` to u_c (setUncertaintyFields).
void addBudgetFields(Json* parameters, const UncertaintyBudget& budget);
/// The readable table: value beside u_A u_B u_c U, then the largest contributors and the
/// strongest correlations.
std::string budgetText(const UncertaintyBudget& budget, const Eigen::VectorXd& values, int top = 3);

}  // namespace rotacal
