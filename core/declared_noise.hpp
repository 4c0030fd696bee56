#pragma once
// The declaration every test of a cycle's data is made against: the covariance of the readings
// that the machine's declared contributors produce, the same declaration its uncertainty reads.
// Two parts:
//   white       the per-reading scatter, independent at every touch (probe repeatability and
//               surface roughness; repeatability alone when nothing else is declared);
//   structured  what the declared systematic contributors (the linear axes' scale, squareness and
//               random node errors of 000 Eqs. (22)-(23), the probe's pretravel by direction, the
//               artefact's set-up and form) move the readings by, to first order, shared between
//               readings: two touches a few millimetres apart read almost the same linear-axis
//               error. It is the same machine in every repeat of a plan, so repeats share it.
// A test that takes the white part alone for the whole noise tests a machine that the product's
// own budget says does not exist: the linear axes of 000 Table 5 leave several micrometres in the
// residual of 000's 154-touch cycle where the probe declares 1.2 um. Tests therefore work on whitened residuals
// (generalized least squares, Sigma^-1/2), so their null hypothesis is the declared machine.
// A third part, for readings taken relative to a zero read once per run (a laser that is
// zeroed on a reading of each sweep's zero pose, which has its own scatter):
//   per run     shared by the readings of one run only: every reading of a sweep carries minus
//               that run's zero error, and the next run zeroes anew. Declared as shared by every
//               run (structured), repeats would agree better than the data do; left out, a
//               sweep's readings would move together more than declared. Cycles without a
//               per-run zero leave it empty.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/contributors.hpp"
#include "core/json_io.hpp"

namespace rotacal {

struct DeclaredNoise {
  double white_um2 = 0.0;          // per-reading variance, um^2
  Eigen::MatrixXd structured_um2;  // readings x readings of ONE run (plan order), um^2; empty: none
  /// One phrase naming what was declared and where it came from, for every verdict that tests
  /// against it ("declared: repeatability only (0.700 um, MACHINE.json)").
  std::string declaration;
  bool repeatability_only = true;  // no contributor beyond the probe's repeatability
  /// Draws of the shared part from the declared contributors' own draw: ONE run's readings (plan
  /// order, um) x draws; empty: none. The covariance above summarises them to second order; the
  /// whole-residual test takes its null from them (testAgainstDeclared), because the linear axes'
  /// random node spacing makes their errors a scale mixture whose chi2 has a heavier upper tail
  /// than a Gaussian of the same covariance.
  Eigen::MatrixXd structured_draws_um;
  /// The part shared by the readings of ONE run only (readings x readings of one run, plan order,
  /// um^2; symmetric, positive semi-definite; empty: none): covariance() adds it between readings
  /// of the same run, nullDraws() draws it afresh for each run.
  Eigen::MatrixXd per_run_um2;

  /// The covariance (um^2) of the readings kept[k] = (run, index in the run's plan order), in that
  /// order: the structured part between any two (the same machine in every run), the per-run part
  /// between two of the same run and the white part on the diagonal. Throws std::invalid_argument
  /// when an index is beyond a part's plan or per_run_um2 is not square.
  Eigen::MatrixXd covariance(const std::vector<std::pair<int, int>>& kept) const;
  /// Draws of the readings kept[k] (as covariance()): columns of structured_draws_um (the same
  /// machine in every run) plus the white part drawn per reading and the per-run part drawn per
  /// run and draw (its symmetric root times standard normals), both from `seed`; readings x
  /// draws, empty when no structured draws are held.
  Eigen::MatrixXd nullDraws(const std::vector<std::pair<int, int>>& kept, std::uint64_t seed) const;
  /// rms of sqrt(diag): the declared scatter of one reading, white, structured and per run together.
  double rmsSigmaUm(int readings) const;
};

/// The declaration of a probe whose repeatability alone is known (no contributors file).
DeclaredNoise repeatabilityOnly(double repeatability_um, const std::string& source);

/// The white part a probe cycle declares: the per-touch contributors (probe_repeatability,
/// surface_roughness) of `declared`, or MACHINE.json's probe repeatability when `declared` is null
/// or names no probe_repeatability (the declaration says which). Throws std::invalid_argument
/// naming the field when its probe_repeatability contradicts MACHINE.json's
/// by more than 1 % (two declarations of one quantity: neither is silently preferred).
DeclaredNoise perTouchDeclaration(const ContributorSet* declared, double machine_repeatability_um);

/// The draws of the declared machine a declaration holds (structured_draws_um) where the cycle does
/// not set its own, and their seed: fixed, so that one data set gets one verdict.
constexpr int kDeclaredNullDraws = 2000;
constexpr std::uint64_t kDeclaredNullSeed = 0x6e756c6c;

/// The shared part of a probe cycle's touches, read at trigger_m_mm along approach_m (plan order):
/// the declared pretravel and linear axes to first order (contributor_draw.hpp's
/// probeAxesCovariance), each touch's displacement along its approach times scale[i] (the touch's
/// reading per unit of it: 1, or n . u on a sphere; empty: 1). Sets `noise`'s structured part
/// and its draws (probeAxesDraws, kDeclaredNullDraws) and names the contributors in its
/// declaration; leaves it unchanged when none is declared.
void addProbeAxesPart(const ContributorSet& declared, const std::vector<Eigen::Vector3d>& trigger_m_mm,
                      const std::vector<Eigen::Vector3d>& approach_m, const Eigen::VectorXd& scale, DeclaredNoise* noise);

/// Sigma^-1/2 by its eigen-decomposition (the symmetric root: each whitened reading stays tied to
/// its own touch, unlike a Cholesky factor, so "where the misfit sits" still reads by touch).
/// Eigenvalues below 1e-12 of the largest are floored there. Throws std::invalid_argument when
/// the matrix is not square, not finite or not positive on its diagonal.
Eigen::MatrixXd inverseSquareRoot(const Eigen::MatrixXd& covariance);
/// The same, and the square root S^1/2 (its inverse) from the one eigen-decomposition.
void squareRoots(const Eigen::MatrixXd& covariance, Eigen::MatrixXd* inverse_root, Eigen::MatrixXd* root);

/// The outlier statistic of each reading under correlated declared noise: the standardized
/// residual of reading i predicted from all the others (the generalized least squares deletion
/// residual, the score test of a mean shift at i). With P = S^-1 - S^-1 J (J^T S^-1 J)^+ J^T S^-1,
/// t_i = (P y)_i / sqrt(P_ii), N(0, 1) under the declaration for every i. It depends on J's column
/// span alone, and P y = P r for any fit's residual r = y - J b, so `residual` may come from any
/// fit of the same linear model. For S = sigma^2 I it is r_i / (sigma sqrt(1 - h_ii)).
/// J: readings x parameters (may be rank deficient); S: the declared covariance.
Eigen::VectorXd deletionStatistics(const Eigen::VectorXd& residual, const Eigen::MatrixXd& J,
                                   const Eigen::MatrixXd& covariance);

/// deletionStatistics of several residual vectors at once (the columns of `residuals`, e.g. draws
/// of the declared noise), from one decomposition: readings x columns.
Eigen::MatrixXd deletionStatisticsColumns(const Eigen::MatrixXd& residuals, const Eigen::MatrixXd& J,
                                          const Eigen::MatrixXd& covariance);

/// What a gross error at each reading moves its own deletion statistic by, per um: sqrt(P_ii)
/// (P as above), so that an error c at reading i shifts t_i by c sqrt(P_ii). 0 where the model
/// takes up the whole reading (P_ii below 1e-14 of the reading's own weight, as
/// deletionStatistics treats it): a gross error there moves the fit, never the screen. For
/// S = sigma^2 I it is sqrt(1 - h_ii) / sigma.
Eigen::VectorXd deletionSensitivity(const Eigen::MatrixXd& J, const Eigen::MatrixXd& covariance);

/// The level below which the data's test against the declaration holds the offsets back
/// (`analyze --offsets` writes them only with --force): offsets from a model that does not explain
/// the machine would move it by what the model misreads. One machine in a thousand that is as
/// declared is held back: a refusal costs a re-measurement, so it is rarer than the judge's 1 %.
constexpr double kOffsetsAdequacyAlpha = 1e-3;

/// The data against the declaration as a whole: chi2 = r^T P r (the whitened residual's sum of
/// squares, P as above), chi2(dof) with dof = readings - rank J under the declaration.
struct DeclaredNoiseTest {
  double chi2 = 0.0;
  int dof = 0;
  double p_value = 1.0;
  /// The null p_value reads: chi2(dof), or, from draws of the declared machine, null_scale x
  /// chi2(null_dof) with the draws' mean and variance of chi2 (Satterthwaite's moment match).
  int null_draws = 0;
  double null_scale = 1.0;
  double null_dof = 0.0;
  double ratio = 0.0;  // sqrt(chi2 / dof): 1 when the data scatter as declared
  /// In the readings' unit: the model's ordinary residual rms per degree of freedom, and the
  /// declared scatter left in it (sqrt(tr(M S M) / dof), M its projector): the shared part the
  /// model absorbs (a set-up, a face's offset) counts in neither.
  double residual_rms = 0.0;
  double declared_rms = 0.0;
};
DeclaredNoiseTest testAgainstDeclared(const Eigen::VectorXd& residual, const Eigen::MatrixXd& J,
                                      const Eigen::MatrixXd& covariance);
/// The same with its null from `null_draws` (readings x draws of the declared noise, e.g.
/// DeclaredNoise::nullDraws): each draw's chi2 through the same whitened projector, and the data's
/// chi2 read against the scaled chi2 of the draws' mean and variance. Fewer than
/// kMinNullDraws draws: chi2(dof), as without them.
constexpr int kMinNullDraws = 200;
DeclaredNoiseTest testAgainstDeclared(const Eigen::VectorXd& residual, const Eigen::MatrixXd& J,
                                      const Eigen::MatrixXd& covariance, const Eigen::MatrixXd& null_draws);

/// Why analyze holds the offsets back (p < kOffsetsAdequacyAlpha), or "" when the data are
/// within the declaration.
std::string offsetsHeldBack(const DeclaredNoise& noise, const DeclaredNoiseTest& test);

/// REPORT.json's `declared_noise`: what was declared, and by how much the data exceed it.
Json declaredNoiseJson(const DeclaredNoise& noise, const DeclaredNoiseTest& test);

}  // namespace rotacal
