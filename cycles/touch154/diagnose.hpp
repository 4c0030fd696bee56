#pragma once
// What the touch154 model gets wrong (issues 6 and 16), decided by the one judge
// (core/judge.hpp, rules in docs/diagnosis.md "The judge"):
//  - the baseline is the identification engine's lsq_per_point fit (8 location errors + one
//    surface offset per target point), linearised at its solution (lineariseAtBaseline): y = its
//    residuals, J0 = its Jacobian, each catalogued cause's columns those of its model extension
//    (cycles/touch154/causes.hpp) at zero, from the exact model;
//  - the noise is the DECLARED one, never the fit's own: an unmodelled effect then shows as a
//    misfit instead of hiding in an inflated noise. With the machine's contributors it is their
//    covariance of the touches (per touch: repeatability and roughness; shared: the linear axes,
//    pretravel, set-up and form, to first order), the machine the uncertainty budget describes;
//    without, the probe repeatability of MACHINE.json;
//  - groups = poses (leave one pose out, every repeat of it); factors = time, pose, approach,
//    face, repeat, X/Y/Z position of the trigger;
//  - confounding comes from the Jacobians on this plan (the judge's principal angles), never a
//    list; each accepted cause is then refitted with the exact model for the location errors
//    and the residual figures.
#include <string>
#include <vector>

#include "cycles/touch154/identification.hpp"
#include "core/judge.hpp"
#include "core/json_io.hpp"
#include "cycles/touch154/model_extension.hpp"
#include "cycles/touch154/declared.hpp"

namespace rotacal {

struct Touch154DiagnosisOptions {
  JudgeOptions judge;                    // alpha from the CLI's --alpha
  double sigma_um = 0.7;                 // declared probe repeatability (MACHINE.json), k = 1
  /// The declared noise the tests read (cycles/touch154/declared.hpp): its white part replaces
  /// sigma_um, its structured part makes the judge whiten by the full covariance. Null: sigma_um.
  const Touch154Noise* noise = nullptr;
  std::vector<ExtensionPtr> candidates;  // empty: catalogFor(plan, runs)

  bool validate(std::string* why) const;
};

struct Touch154Finding {
  ExtensionPtr extension;
  std::string judge_name;     // the JudgeCause name (unique per candidate)
  IdentificationResult fit;   // exact refit with this and every earlier accepted cause
};

struct Touch154Diagnosis {
  Linearisation lin;                  // the baseline fit and its linearisation
  std::vector<ExtensionPtr> candidates;
  std::vector<std::string> judge_names;  // per candidate
  JudgeSummary judged;
  std::vector<Touch154Finding> findings;  // in order of acceptance
};

/// The judge's problem for a linearised baseline and candidates (exposed for the tests).
JudgeProblem touch154JudgeProblem(const ProbePlan& plan, const Linearisation& lin,
                                  const std::vector<ExtensionPtr>& candidates, double sigma_um,
                                  const Touch154Noise* noise = nullptr);

/// Throws std::invalid_argument for invalid options. A baseline that does not converge gives
/// lin.ok == false and no judgement.
Touch154Diagnosis diagnoseTouch154(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                   const Touch154DiagnosisOptions& options);

Json touch154DiagnosisJson(const Touch154Diagnosis& d, const ProbePlan& plan);
std::string touch154DiagnosisText(const Touch154Diagnosis& d);

}  // namespace rotacal
