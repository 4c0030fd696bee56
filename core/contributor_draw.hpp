#pragma once
// One Monte Carlo draw of the declared contributors that every probing cycle shares:
// the probe's pretravel per approach direction and the linear axes' errors (000 Sec. 5,
// core/linear_axes.hpp), as a modifier of the simulator's Truth. The cycles' budgets draw their
// own instruments (R-test sensors, laser) beside it. Random streams: one per contributor (its
// catalog index) and per run, so a contributor draws the same values alone and combined, whatever
// the thread count.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/linear_axes.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"

namespace rotacal {

/// Pretravel along the approach u (unit) from six directional values (+X -X +Y -Y +Z -Z):
/// sum_k u_k^2 v(k, sign u_k). Exact for axis-parallel approaches; a smooth blend for oblique
/// ones (the weights sum to 1).
double pretravelAlong(const std::array<double, 6>& v, const Eigen::Vector3d& u);

/// The random stream of a contributor in run `run`: its catalog index beside the run's bits.
std::uint64_t contributorStream(const ContributorInfo& info, int run);

/// The linear axes' contributors: scale, random, squareness.
bool isLinearAxisContributor(const ContributorInfo& info);
/// What acts independently at every touch of a probe (repeatability, roughness): Type A.
bool isPerTouchContributor(const ContributorInfo& info);
/// What a probe cycle on spheres can be drawn with here: pretravel and the linear axes.
bool isProbeAxesContributor(const ContributorInfo& info);

/// A declared set split for one cycle's budget: the per-reading variance its data measure (Type
/// A, mm^2), the Type B contributors (file and node spacing kept) and the ids that do not act.
struct ContributorSplit {
  double per_reading_mm2 = 0.0;
  ContributorSet type_b;
  std::vector<std::string> left_out;
};
ContributorSplit splitContributors(const ContributorSet& declared, const std::function<bool(const ContributorInfo&)>& type_a,
                                   const std::function<bool(const ContributorInfo&)>& type_b);

/// Draws the linear axes' errors of run `run` from the linear-axis contributors of `set` (only
/// set.items[only] when only >= 0) over the read positions lo..hi (machine frame, mm). Returns
/// false, drawing nothing, when none is declared. Its streams lie beyond every catalog index.
bool drawLinearAxes(const ContributorSet& set, int only, const Eigen::Vector3d& lo_mm, const Eigen::Vector3d& hi_mm,
                    std::uint64_t seed, int run, LinearAxisErrors* out);

/// Every plan point's trigger on `truth` (exact simulator, no noise) as its distance along the
/// approach (identification.hpp alongApproach), mm, plan order: what a draw moves.
Eigen::VectorXd triggersAlong(const ProbePlan& plan, const Truth& truth);

/// The span of a plan's nominal triggers (machine frame): where a probing cycle reads the axes.
void triggerSpan(const ProbePlan& plan, Eigen::Vector3d* lo_mm, Eigen::Vector3d* hi_mm);

/// The probe's pretravel and the linear axes, drawn for one run.
struct ProbeAxesDraw {
  std::array<double, 6> pretravel_mm{};  // +X -X +Y -Y +Z -Z
  bool linear = false;
  LinearAxisErrors linear_errors;
};

/// Draws run `run` of `seed` from the contributors of `set` that `acts` accepts (pretravel and the
/// linear axes; any other kind accepted is an error of the caller); with `only` >= 0 every
/// contributor but set.items[only] is zero. The linear axes cover the plan's trigger span.
void drawProbeAxes(const ProbePlan& plan, const ContributorSet& set, const std::function<bool(const ContributorInfo&)>& acts,
                   std::uint64_t seed, int run, int only, ProbeAxesDraw* out);
/// The covariance (mm^2) of the triggers' displacements along their approaches that drawProbeAxes
/// draws from the contributors `acts` accepts, to first order: touch i read at trigger_m_mm[i]
/// (machine frame) approaching along approach_m[i] (unit). The pretravel by pretravelAlong's
/// weights; the linear axes' scale, squareness and random parts (nodeCorrelation); and, where
/// `acts` accepts them, the per-touch contributors (repeatability, roughness) on the diagonal.
/// What a design weighs a plan's touches by; checked against a Monte Carlo of drawProbeAxes.
Eigen::MatrixXd probeAxesCovariance(const ContributorSet& set, const std::function<bool(const ContributorInfo&)>& acts,
                                    const std::vector<Eigen::Vector3d>& trigger_m_mm,
                                    const std::vector<Eigen::Vector3d>& approach_m);

/// Draws of what probeAxesCovariance summarises (mm): column d is draw d of the same first-order
/// model (touch i reads the pretravel along approach_m[i] plus the linear axes' error at
/// trigger_m_mm[i] read along it, and the per-touch contributors where `acts` accepts them), each
/// draw its own node spacing per axis, as drawLinearAxes draws a machine. The covariance is the
/// second moment of a mixture over the spacing; a test whose null is the declared machine reads
/// its tails from these draws, not from a Gaussian of that covariance.
Eigen::MatrixXd probeAxesDraws(const ContributorSet& set, const std::function<bool(const ContributorInfo&)>& acts,
                               const std::vector<Eigen::Vector3d>& trigger_m_mm, const std::vector<Eigen::Vector3d>& approach_m,
                               int draws, std::uint64_t seed);

/// Adds a draw to a truth (to its linear_axis_error and pretravel, if it has them).
void applyProbeAxesDraw(const ProbeAxesDraw& draw, Truth* truth);

/// What was drawn of the linear axes, in report units (um/m, um), for a drawn machine's truth
/// record: scale, squareness and each axis's random nodes.
Json linearAxesRecord(const LinearAxisErrors& errors);

/// A whole machine as its declared contributors make it, for the exact simulator (`simulate
/// --contributors`): on top of `truth` (its location errors, anything else it sets), the probe's
/// pretravel by direction and the linear axes of 000 Eqs. (22)-(23) over the plan's trigger span
/// (drawProbeAxes, run 0 of `seed`), the test piece's set-up and form, and the per-touch scatter
/// (repeatability and roughness) as the truth's noise, replacing the truth file's. Contributors of other instruments (the
/// R-test's, the laser's) are named in `left_out`. `record` is what was drawn, in report units.
struct DrawnMachine {
  Json record;
  std::vector<std::string> left_out;
};
DrawnMachine drawMachine(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, Truth* truth);

}  // namespace rotacal
