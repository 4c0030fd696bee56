#pragma once
// The declaration the tooltip cycle's readings are tested against (core/declared_noise.hpp): the
// same contributors, and the same model, that its uncertainty budget (budget.hpp) propagates.
//   white       the per-reading contributors the budget counts as Type A (the laser's own error,
//               the sphere's form, lateral coupling: 004 Sec. VII), and the plan's laser_noise_um
//               where the contributors do not declare laser_resolution (the budget's rule); the
//               plan's laser_noise_um alone when no contributor is declared;
//   structured  what the budget's Type B contributors move the readings by, to first order,
//               shared between readings: the linear axes carry the pivot (a reading is the axes'
//               error at its pivot command, read along its beam, less the same at its sweep's
//               zero pose: exact, the readings are linear in it), and the beams' alignment (a
//               tilt reads the other in-plane component of the deviation: tilt x deviation, so
//               linear in the tilt about the deviations the readings show, zero about the
//               nominal head).
//   per run     the laser's zero: it is set on a reading of the sweep's zero pose, which has the
//               same per-reading scatter as any other (white above), so every later value of the
//               sweep, in the same read direction, carries minus that run's zero error. It is
//               shared by one run's values and drawn anew by the next (a new zero): white_um2
//               between two values of one sweep and direction, 0 elsewhere.
// A reading value is indexed 2 k + c: k the plan point, c = 0 the transverse component (Y for an
// A sweep, X for B), c = 1 Z. The zero readings' rows are zero (the laser is zeroed there).
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "core/probe_plan.hpp"
#include "cycles/tooltip/plan.hpp"

namespace rotacal {

/// The declaration of `plan`'s readings from `contributors` (null: laser_noise_um alone).
/// `about`: the deviations the alignment's first-order term is taken about (one run of the plan,
/// NaN read as 0); null: the nominal head, where the alignment moves nothing to first order.
DeclaredNoise tooltipDeclaredNoise(const ProbePlan& plan, const ContributorSet* contributors,
                                   const TooltipRun* about = nullptr);

/// The structured part (um^2) of several plans read on one machine (diagnose's tool lengths): one
/// matrix over every plan's 2 x points values in turn. The linear axes are the same between plans;
/// the beams are aligned anew for each plan (no alignment term between plans). `about[p]` may be null.
Eigen::MatrixXd tooltipStructuredUm2(const std::vector<const ProbePlan*>& plans, const ContributorSet& contributors,
                                     const std::vector<const TooltipRun*>& about);

/// The per-run part (um^2) of `plan`'s 2 x points values for a per-reading variance `white_um2`:
/// white_um2 between two values that read the same direction relative to the same zero reading,
/// 0 elsewhere and in the zero readings' own rows. Throws std::invalid_argument when white_um2
/// is negative or not finite.
Eigen::MatrixXd tooltipPerRunUm2(const ProbePlan& plan, double white_um2);

/// The values (run, 2 k + c) of `runs` that are read (finite) and not a zero reading, in the fit's
/// order (run by run, plan order, transverse before Z): what the declaration's covariance is taken over.
std::vector<std::pair<int, int>> tooltipReadValues(const ProbePlan& plan, const std::vector<TooltipRun>& runs);

}  // namespace rotacal
