#pragma once
// One judge for every cycle's diagnosis: does the baseline model explain the data
// within the DECLARED noise, which catalogued cause (if any) explains what it misses, and which
// causes this plan cannot tell apart. Cycle-free: it works on a linearised problem (the
// observations' deviations, their declared standard deviations, the baseline Jacobian and one
// Jacobian block per candidate cause), so every cycle calls the same code with the same rules.
//
// The rules, stated once (docs/diagnosis.md, "The judge"):
//  - Noise is what the user declares (MACHINE.json probe repeatability, the R-test's sensor
//    noise, a measured repeatability run), never the fit's own sigma: an unmodelled effect then
//    shows as a misfit instead of inflating the noise and hiding itself.
//  - Everything is whitened by the declared sigma_i. With m candidate causes, the adequacy test
//    and each cause's nested-model test are each run at alpha / (m + 1) (Bonferroni over the
//    m + 1 tests, the same level at every step of the forward selection): on data the baseline
//    explains, the chance of any false alarm (effect_found or model_inadequate) is at most alpha
//    by the union bound; the held-out condition only lowers it further.
//  - Adequacy: chi2 = |r0|^2 of the whitened baseline residual ~ chi2(n - rank J0).
//  - A cause is tested on what it adds beyond the current model (its principal directions
//    whose angle to the model's span exceeds the exact-confounding angle; k_eff of them):
//    Delta chi2 ~ chi2(k_eff) against the declared noise, AND the F form
//    (Delta chi2 / k_eff) / (chi2_ext / dof_ext) ~ F(k_eff, dof_ext), the extended model's own
//    residual as the noise. Both must pass (p = the larger p-value): under a correct declared
//    noise the two agree to within dof_ext's sampling; under an unmodelled effect or a noise
//    declared too small, the chi2 form alone would pass every cause that overlaps the misfit,
//    the F form does not. This is decided always, not only when adequacy fails, so the rule
//    has no switch that a borderline p-value flips.
//  - Held-out gain: leave one group out (groups given per observation: pose, repeat, cycle...),
//    exact for a linear model through the hat matrix, e_S = (I - H_SS)^-1 r_S, no refits. The
//    per-fold gains d_g = sum_S e_base^2 - sum_S e_cause^2 (whitened) give the mean gain and its
//    standard error sd(d)/sqrt(G); the cause passes when mean > margin x SE. A parameter only
//    the held-out group has data for (I - H_SS singular: one angular error per commanded angle)
//    is refitted on the group itself and the prediction error measured in the rest of it (the
//    pseudo-inverse of I - H_SS); a group with nothing left to predict is no fold. "Only the
//    group has data for" includes a direction the other groups pin with less than a stated
//    share of the full fit's information (kFoldInformation in judge.cpp): predicting it from
//    them would measure their near-singular refit, not the cause, and one such fold would
//    decide the mean gain by itself.
//  - Confounding from the Jacobians only: principal angles (whitened) between a cause's columns
//    and the current model's span, and between two causes once the model is projected out.
//    Below the exact angle: a `JudgeConfounded` entry naming the combination that absorbs it;
//    such a cause is never effect_found. Below the partial angle: the cause's separability
//    (sin of that angle) is reported as a lowered confidence.
//  - A significant signal along causes the plan cannot tell apart is a finding: when causes
//    that each pass both tests are exactly confounded with one another (beyond the model), the
//    one with the largest held-out gain extends the model like any cause, and its finding names
//    the others (`confounded_with`, with the entries that say what each is read as). A partner
//    is named only when it explains the signal as well (with it in the model, nothing of the
//    cause passes); otherwise the pair is withheld as before. Its gain is measured on held-out
//    data as any finding's; which of them it is, the plan cannot say.
//  - Verdicts: effect_found when causes were accepted AND the model with them passes the
//    adequacy test AND no significant signal is left that could only be read as confounded
//    causes; model_inadequate when the final model fails adequacy, or a significant signal can
//    only be read as a cause confounded with the model itself, or as confounded causes the
//    selection could no longer take (max_causes); no_significant_effect when the baseline passes
//    adequacy and nothing is accepted or left. "Explains the data within the declared noise"
//    is said only when the final model passes the adequacy test (`explainsData()`).
//  - Parameter u: from the declared noise, (B^T B)^-1 of the cause's whitened columns with the
//    rest of the final model projected out; multiplied by the Birge ratio sqrt(chi2/dof) only
//    when the final model fails adequacy (the data then refute the declared noise and that
//    ratio is the scatter the estimates inherit if the excess is white; when the test passes
//    the declared noise stands and rescaling would only add the ratio's own sampling noise).
//
// Design choices beyond the brief: the candidates' test uses max(p_chi2, p_F) always (see
// above); "where the
// misfit sits" is itself a nested test of each factor's columns (indicators of a categorical
// factor's levels, a quadratic in a continuous one) on the residual, so a factor's chi2 share
// never counts what the model already absorbs.
#include <Eigen/Core>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "core/json_io.hpp"

namespace rotacal {

/// A named parameter: `unit` is its own unit; a Jacobian column is d(observation) / d(param) in
/// the observation's unit per this unit.
struct JudgeParameter {
  std::string name;
  std::string unit;
};

/// A candidate cause: a family of parameters tested jointly (all drift slopes, all harmonics).
struct JudgeCause {
  std::string name;         // "thermal_drift", "pivot_length", ...
  std::string description;  // one line, for the text report
  Eigen::MatrixXd J;        // n x k
  std::vector<JudgeParameter> parameters;  // k
};

/// A label per observation, to say where a misfit sits. Either categorical (`levels`, one label
/// per observation: angle, repeat, approach, sphere) or continuous (`values`: time, position),
/// never both. A continuous factor is tested as a quadratic in its value.
struct JudgeFactor {
  std::string name;
  std::vector<std::string> levels;
  std::vector<double> values;
  std::string unit;  // of `values`
};

struct JudgeProblem {
  /// Observations' deviations from the nominal (or the baseline's own residual, with J0 at the
  /// baseline's solution: the linear fit then returns the same residual and each cause is judged
  /// by one Gauss-Newton step from it).
  Eigen::VectorXd y;
  /// Declared standard deviation per observation (> 0), in y's unit: never the fit's own.
  Eigen::VectorXd sigma;
  /// The declared covariance of the observations (y's unit squared) when they are correlated:
  /// the structured part the declared contributors leave (core/declared_noise.hpp). Empty: the
  /// observations are independent with `sigma`. Given, it replaces `sigma` (which may be left
  /// empty) and everything is whitened by its symmetric inverse root; the raw-unit figures
  /// (rms, held-out rms, excess) then take sqrt(diag) as each observation's sigma.
  Eigen::MatrixXd covariance;
  /// Draws of the declared noise (observations x draws, y's unit; DeclaredNoise::nullDraws), with
  /// `covariance` only: from kMinNullDraws of them on, every adequacy test reads its null from
  /// them (each draw's chi2 through the same whitened projector, read as the scaled chi-square
  /// of their mean and variance), as analyze's test against the declaration does: the linear
  /// axes' random nodes, one spacing per machine, give the declared machine's chi2 a heavier
  /// upper tail than chi2(dof). Empty: chi2(dof).
  Eigen::MatrixXd null_draws;
  /// What the noise declaration is, named in every verdict ("declared: repeatability only ...").
  std::string declaration;
  std::string unit = "um";  // of y and sigma
  Eigen::MatrixXd J0;       // n x p, may be rank deficient
  std::vector<JudgeParameter> baseline_parameters;  // p
  std::vector<JudgeCause> causes;
  /// Cross-validation group per observation (leave one group out); empty: each observation.
  std::vector<int> groups;
  std::string group_name = "observation";  // what a group is: "pose", "repeat", "cycle"
  std::vector<JudgeFactor> factors;
};

struct JudgeOptions {
  double alpha = 0.01;            // family-wise false-alarm rate over adequacy + all causes
  double holdout_margin = 2.0;    // held-out gain must exceed this many of its standard errors
  double exact_angle_deg = 0.1;   // principal angle below which two spans are the same signal
  double partial_angle_deg = 20;  // below this a cause is reported with lowered confidence
  int max_causes = 2;             // forward selection stops after this many accepted causes

  bool validate(std::string* why) const;
};

enum class JudgeVerdict { EffectFound, ModelInadequate, NoSignificantEffect };
const char* judgeVerdictName(JudgeVerdict v);  // "effect_found", ...

/// The part of a residual a factor carries: the nested test of its columns on that residual.
struct JudgeFactorShare {
  std::string factor;
  double chi2 = 0.0;     // whitened residual's sum of squares along the factor's added columns
  int dof = 0;           // k_eff of the factor's columns beyond the model
  double p_value = 1.0;  // chi2(dof) survival (a measure of structure, not a decision)
  double share = 0.0;    // chi2 / the residual's total chi2
  std::string detail;    // the largest level mean, or the fitted curve's range
};

struct JudgeAdequacy {
  double chi2 = 0.0;
  int dof = 0;
  double p_value = 1.0;
  double threshold = 0.0;  // alpha / (m + 1)
  bool passes = true;
  double rms_residual = 0.0;     // rms of the raw residual, in y's unit
  double excess_rms = 0.0;       // extra white scatter that would make chi2 = dof, in y's unit
  /// The null p_value reads: chi2(dof), or null_scale x chi2(null_dof) from null_draws draws.
  int null_draws = 0;
  double null_scale = 1.0, null_dof = 0.0;
  std::vector<JudgeFactorShare> factors;  // smallest p first
};

struct JudgeEstimate {
  std::string name, unit;
  double value = 0.0;
  double u = 0.0;  // NaN when not identifiable
  bool identifiable = true;
};

struct JudgeCandidate {
  std::string cause;
  int step = 0;  // forward-selection step (0: against the baseline)
  int k = 0, k_eff = 0;
  double delta_chi2 = 0.0;
  double p_chi2 = 1.0, f = 0.0, p_f = 1.0, p_value = 1.0;  // p_value = max(p_chi2, p_f)
  double threshold = 0.0;
  bool test_passes = false;
  int folds = 0;  // held-out folds used
  double holdout_rms_model = 0.0, holdout_rms_cause = 0.0;  // y's unit
  double gain = 0.0;     // mean per-fold whitened gain
  double gain_se = 0.0;  // its standard error
  bool holdout_passes = false;
  double angle_deg = 90.0;  // smallest principal angle to the current model
  double separability = 1.0;  // sin of the smallest angle to the model or a passing cause
  std::vector<std::string> overlaps;  // what it is partly read as (angle below the partial one)
  bool accepted = false;
  std::string reason;  // "accepted", or why not
};

struct JudgeTerm {
  std::string name;  // "cause.param" or a baseline parameter
  double coefficient = 0.0;
  std::string unit;
};

struct JudgeConfounded {
  std::string cause;
  std::vector<std::string> with;       // baseline parameters, accepted causes or another cause
  bool with_model = true;              // false: with another candidate cause
  double angle_deg = 0.0;
  std::vector<JudgeTerm> cause_terms;  // this combination of the cause's parameters ...
  std::vector<JudgeTerm> with_terms;   // ... moves the data as this one does
  bool signal = false;                 // the shared signal passes the cause's tests and the final model leaves it
  std::string finding;                 // the finding that carries the shared signal (its cause), if one does
  std::string why;
};

struct JudgeFinding {
  std::string cause;  // the cause whose columns extend the model
  std::string description;
  /// Other causes that explain the same significant signal exactly as `cause` does on this plan
  /// (principal angle below the exact one, beyond the model): the finding is that signal, read as
  /// `cause`; the data cannot say which of them it is. Empty: `cause` alone.
  std::vector<std::string> confounded_with;
  /// The entries that tie `cause` to each of them (what one is read as in the other's terms).
  std::vector<JudgeConfounded> confounding;
  int step = 0;
  std::vector<JudgeEstimate> parameters;  // from the final model
  double delta_chi2 = 0.0, p_value = 1.0;
  double holdout_rms_model = 0.0, holdout_rms_cause = 0.0, gain = 0.0, gain_se = 0.0;
  double separability = 1.0;
  std::vector<std::string> overlaps;
  std::string confidence;  // "full", or why lowered

  /// The estimate of the named parameter (nullptr when the cause has none of that name).
  const JudgeEstimate* parameter(std::string_view name) const;
  /// `cause`, or "cause or other or ..." when the plan cannot tell them apart.
  std::string label() const;
};

struct JudgeSummary {
  JudgeVerdict verdict = JudgeVerdict::NoSignificantEffect;
  std::string message;  // one sentence, true whatever the verdict
  std::string unit;
  std::string group_name;
  int observations = 0, groups = 0, baseline_rank = 0, candidates = 0;
  double alpha = 0.0, per_test_alpha = 0.0, holdout_margin = 0.0;
  double exact_angle_deg = 0.0, partial_angle_deg = 0.0;
  /// rms of the declared sigma_i; with a full covariance, the declared scatter the baseline leaves
  /// in its ordinary residual per degree of freedom (what rms_residual is compared with)
  double declared_sigma_rms = 0.0;
  std::string declaration;          // JudgeProblem::declaration
  bool correlated = false;          // tested against a full declared covariance
  JudgeAdequacy baseline;
  JudgeAdequacy final_model;  // after the accepted causes (== baseline when none)
  double baseline_holdout_rms = 0.0;
  std::vector<JudgeEstimate> baseline_estimates;
  std::vector<JudgeEstimate> final_estimates;  // baseline parameters with the causes in
  std::vector<std::string> unidentifiable;     // baseline parameters J0 cannot fix
  std::vector<JudgeCandidate> candidate_tests;  // every cause at every step
  std::vector<JudgeFinding> findings;          // in order of acceptance
  std::vector<JudgeConfounded> confounded;

  bool effectFound() const { return verdict == JudgeVerdict::EffectFound; }
  /// The finding of the named cause (nullptr when it was not accepted).
  const JudgeFinding* finding(std::string_view cause) const;
  /// True only when the final model passes the adequacy test against the declared noise.
  bool explainsData() const { return final_model.passes && verdict != JudgeVerdict::ModelInadequate; }
};

/// Throws std::invalid_argument for invalid options or a problem whose sizes disagree, a
/// sigma <= 0 or a non-finite entry ("expected N, got M").
JudgeSummary judge(const JudgeProblem& problem, const JudgeOptions& options = {});

/// The contract's `confounded` entries (contract.md: `causes`, `why`, `separate_with`) with the
/// judge's own fields of each entry: one form for every cycle. `causes` is the cause followed by
/// what absorbs it (baseline parameters, accepted causes or another cause); `separate_with` is
/// the cycle's advice for the entry: what plan or instrument tells them apart.
Json confoundedJson(const JudgeSummary& summary, const std::function<std::string(const JudgeConfounded&)>& separate_with);
/// What tells a confounded finding's causes apart: the cycle's advice for each of its entries,
/// distinct sentences joined by "; " (empty without advice or when the finding names one cause).
std::string findingSeparateWith(const JudgeFinding& f,
                                const std::function<std::string(const JudgeConfounded&)>& separate_with);
/// The document's `confounded` (confoundedJson) and, on each entry of its `findings` (in the
/// summary's order) that names causes this plan cannot tell apart, `confounded_with` and
/// `separate_with`: the one place a cycle's advice reaches both.
void writeConfounded(Json& doc, const JudgeSummary& summary,
                     const std::function<std::string(const JudgeConfounded&)>& separate_with);
Json judgeToJson(const JudgeSummary& s);
/// The summary as text; `separate_with` (the cycle's advice, may be empty) completes the line of
/// a finding whose causes this plan cannot tell apart.
std::string judgeText(const JudgeSummary& s, const std::function<std::string(const JudgeConfounded&)>& separate_with = {});

}  // namespace rotacal
