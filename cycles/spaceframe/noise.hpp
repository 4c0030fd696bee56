#pragma once
// The declaration the space-frame cycle tests its data against (core/declared_noise.hpp), and at
// which level it applies.
//
// The touches are what the probe reads, so the declaration is made there: per plan point, the
// trigger's displacement along its approach (um), white per touch (perTouchDeclaration: probe
// repeatability and roughness, or MACHINE.json's repeatability when none is declared) and
// structured between touches (addProbeAxesPart: the probe's pretravel by direction and the linear
// axes of 000 Eqs. (22)-(23) to first order, the same machine in every repeat). Every spaceframe
// touch approaches the sphere's centre along a machine axis, so n . u = -1 on every touch and the
// reading is the displacement itself.
//
// What the identification fits and the judge reads are the sphere centres (3 per centre). Each
// sphere fit maps its touches' displacements linearly onto its centre (core/sphere_centre_fit.hpp
// linearSphereFit, the fitted radius absorbing what moves all touches in or out alike), so the
// centres' declared covariance is M C M^T: C the touches' covariance (the repeats' mean: the
// structured part once, the white part / repeats), M the fits' maps at the plan's nominal
// geometry (a property of the plan, not of the data). The outlier screen works on the touches
// themselves (cycles/spaceframe/screen.hpp): a chip is one touch, and a centre fitted from 4
// touches has no residual of its own to show it.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <vector>

#include "core/contributors.hpp"
#include "core/declared_noise.hpp"
#include "core/probe_plan.hpp"
#include "cycles/spaceframe/analyze.hpp"

namespace rotacal {

struct SpaceframeNoise {
  DeclaredNoise touch;            // per plan point (plan order), displacement along the approach, um
  std::map<int, int> index_of_id; // plan point id -> plan index
};

/// Throws std::invalid_argument when the contributors' probe_repeatability contradicts
/// MACHINE.json's (perTouchDeclaration).
SpaceframeNoise spaceframeDeclaredNoise(const ProbePlan& plan, const ContributorSet* declared);

/// The sphere fit of one centre linearised at the plan's nominal triggers: d centre (mm) per mm
/// of each of the point's touches (p.point_ids' order) along its approach. 3 x touches.
Eigen::MatrixXd spaceframeCentreMap(const ProbePlan& plan, const FramePoint& p);

/// The declared covariance (um^2) of the centres of `points` (3 rows each, their order), each the
/// mean of `runs` repeats: M (structured + white / runs) M^T.
Eigen::MatrixXd spaceframeCentreCovariance(const ProbePlan& plan, const std::vector<FramePoint>& points,
                                           const SpaceframeNoise& noise, int runs);

/// Draws of the same centres under the declared machine (3 x centres rows, um, one column per
/// draw; DeclaredNoise::nullDraws of the touches, their mean over the `runs` repeats, through the
/// same maps), from `seed`; no columns when the declaration holds no draws. The tests' null: the
/// linear axes' node spacing, one per machine, makes the centres a scale mixture whose chi2 has a
/// heavier tail than a normal of their covariance.
Eigen::MatrixXd spaceframeCentreNullDraws(const ProbePlan& plan, const std::vector<FramePoint>& points,
                                          const SpaceframeNoise& noise, int runs, std::uint64_t seed);

/// The identification as the declaration's test reads it: the centres' residual after the fit
/// (um), the fit's Jacobian there (um per report unit, the analysis' active parameters) and the
/// centres' declared covariance (um^2) with its null draws (spaceframeCentreNullDraws).
struct SpaceframeCentreProblem {
  Eigen::VectorXd residual_um;
  Eigen::MatrixXd J;
  Eigen::MatrixXd covariance_um2;
  Eigen::MatrixXd null_draws_um;
};
SpaceframeCentreProblem spaceframeCentreProblem(const ProbePlan& plan, const SpaceframeAnalysis& analysis,
                                                const SpaceframeNoise& noise);

/// The data against the declaration, for REPORT.json's `declared_noise` (declaredNoiseJson, with
/// the test said at the centres' level).
Json spaceframeDeclaredNoiseJson(const SpaceframeNoise& noise, const DeclaredNoiseTest& test);

}  // namespace rotacal
