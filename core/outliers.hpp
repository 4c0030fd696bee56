#pragma once
// Outlier touches: a touch that hit a chip or a dirty spot lies 5-50 um off in
// otherwise good data. Least squares would average it in; this screen finds it, names it by run
// and point, and leaves it out of the fit with the reason, never silently.
//
// The test: each fitted touch's residual against the DECLARED noise (the user's claim, never the
// fit's own sigma, which an outlier inflates): with the declared covariance of the touches, the
// generalized least squares deletion residual, what the touch reads beyond what every other touch
// predicts for it (core/declared_noise.hpp), N(0, 1) under the declaration; with a per-touch
// scatter alone, t = r / sigma (without the leverage factor sqrt(1 - h): conservative).
// Threshold: |t| > z with z the two-sided normal quantile at alpha / N (Bonferroni over the N
// fitted touches: clean data lose a touch in at most alpha of the runs), or, where the cycle
// gives the screen draws of the declared machine, the (1 - alpha) quantile of the largest |t| of
// the first fit in each draw when that is larger: the linear axes' random nodes, one spacing per
// machine, make the declared noise a scale mixture whose statistics have heavier tails than the
// normal the Bonferroni bound reads (machines drawn as declared lost a good reading in 5 % of
// runs where the bound says 1 %). Never below the Gaussian bound: the draws are finite. The worst touch beyond z
// is left out and the model refitted, until none is beyond z (worst first: a gross outlier, a
// value millimetres off, drags the first fit and puts many touches beyond z; left out, they come
// back). Still beyond after max_fraction of the touches is no longer a few chips but a model that
// does not fit (or a repeatability declared too small): then nothing is left out and the screen
// says so (too_many), so that the model's adequacy test (diagnose) sees the whole data; analyze
// then writes no offsets without --force.
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/json_io.hpp"
#include "core/least_squares.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct PointResidual {
  int run = 0;
  int point_id = 0;
  double residual_um = 0.0;  // measured - model, along the approach
  double t_h = 0.0;          // observation time, hours relative to the data's mean time
  bool held_out = false;     // predicted, not fitted
};

/// What the screen reads of a fit: whether it converged, and the residual of every touch (the
/// fitted ones and those held out). Every cycle's fit gives it, whatever else it estimates.
struct ScreenedFit {
  FitSummary summary;
  std::vector<PointResidual> residuals;
};

/// Which touches a fit leaves out: true for (run, point) held out.
using HoldOutRule = std::function<bool(int run, const ProbePoint& point)>;

struct OutlierOptions {
  double sigma_um = 0.7;      // declared per-touch scatter, k = 1, when `statistic` is empty
  double alpha = 0.01;        // family-wise rate of a clean run losing a touch
  double max_fraction = 0.05; // of the fitted touches; beyond it nothing is left out
  /// Each fitted touch's statistic (the fit's residuals not held out, in their order), N(0, 1)
  /// under the declared noise: core/declared_noise.hpp's deletionStatistics on the declared
  /// covariance, so that the linear axes' shared errors are not taken for chips. Empty:
  /// residual / sigma_um (the touches independent, with the per-touch scatter alone).
  std::function<Eigen::VectorXd(const ScreenedFit& fit)> statistic;
  /// What the statistic tests against, for the report ("declared: repeatability only ...").
  std::string declaration;
  /// Per draw of the declared machine, the largest |statistic| over the given fit's touches
  /// (screenNullMaxima), asked once, of the first fit; used from kMinScreenNullDraws draws on.
  /// Empty function or fewer draws: the Gaussian bound alone.
  std::function<Eigen::VectorXd(const ScreenedFit& first)> null_maxima;
  /// Per fitted touch of the given fit (its residuals not held out, in their order), what a gross
  /// error of 1 um there moves its statistic by (deletionSensitivity on the declared covariance,
  /// 1 / um; 0 where the fit takes the whole touch up), asked once, of the last fit: the screen's
  /// reach (OutlierScreen::reach). Empty: no reach is reported (r / sigma_um's depends on the
  /// touch's leverage, which the screen does not know).
  std::function<Eigen::VectorXd(const ScreenedFit& fit)> sensitivity;
  bool validate(std::string* why) const;
};

/// The probability with which OutlierScreen::reach's size is caught (Baarda's power, 80 %): a
/// gross error shifts its touch's statistic by c x sensitivity, so one of (threshold +
/// z(power)) / sensitivity lies beyond the threshold with this probability under the declared
/// noise (the minimal detectable bias of geodesy's reliability theory).
constexpr double kScreenReachPower = 0.8;

/// The smallest gross error at one touch that the screen catches with kScreenReachPower, in um
/// along the touch's reading: +inf where the model takes the whole reading up (no screen of this
/// plan can see an error there; it moves the estimate instead).
struct TouchReach {
  int run = 0;
  int point_id = 0;
  double detectable_um = 0.0;
  /// How the report names it; empty: "point <id>" (and " of run <n>" beyond the first). A cycle
  /// whose screened values are not plan points names them after the screen.
  std::string name;
};

/// Draws of the declared machine the screen needs before it reads its threshold from them: at
/// alpha = 0.01 the quantile then rests on at least 10 draws beyond it.
constexpr int kMinScreenNullDraws = 1000;

/// The largest |t| of each column of `t_draws` (statistics x draws) over the rows `screened`
/// marks (all when empty): what OutlierOptions::null_maxima returns, per screened fit; a cycle that
/// screens several fits at once (one per cycle of a series) takes the larger per draw.
Eigen::VectorXd screenNullMaxima(const Eigen::MatrixXd& t_draws, const std::vector<bool>& screened = {});

struct ExcludedTouch {
  int run = 0;
  int point_id = 0;
  double residual_um = 0.0;  // measured - model of the fit that left it out
  double t = 0.0;            // residual_um / sigma_um, in the fit where it was the worst
};

struct OutlierScreen {
  std::vector<ExcludedTouch> excluded;
  double threshold_t = 0.0;
  double gaussian_t = 0.0;  // the Bonferroni bound under a normal statistic
  int null_draws = 0;       // draws of the declared machine the threshold read (0: the bound alone)
  int touches = 0;          // fitted touches of the first fit
  bool too_many = false;    // still beyond after max_fraction left out: none excluded
  int beyond = 0;           // touches beyond the threshold in the last fit, when too_many
  std::string declaration;  // OutlierOptions::declaration
  /// Per fitted touch of the last fit, with OutlierOptions::sensitivity (empty without it, or when
  /// the screen gave up).
  std::vector<TouchReach> reach;
  /// The hold-out rule of a fit for the excluded touches (null when none).
  HoldOutRule holdOut() const;
  std::string text() const;  // one line for the report
  /// One line on the reach: the median and the largest detectable error, the touches the screen
  /// cannot see (empty without a reach). `counted` names them ("touches", "values").
  std::string reachText(const std::string& counted = "touches") const;
  /// reachText() as a line ending in a newline; empty without a reach.
  std::string reachLine(const std::string& counted = "touches") const;
  /// text() and reachLine(), each a line ending in a newline: the report's lines.
  std::string lines() const;
};

/// The touches a fit held out, as (run, point id) sorted: the key by which a screen's caller
/// keeps the fit it made for each hold-out rule.
std::vector<std::pair<int, int>> heldOutTouches(const std::vector<PointResidual>& residuals);

/// Runs `fit` (an identification with the given hold-out rule) repeatedly; returns the screen.
/// `fit` is called with a null rule first.
OutlierScreen screenOutliers(const std::function<ScreenedFit(const HoldOutRule&)>& fit, const OutlierOptions& options);

/// The screen as REPORT.json's `outliers` block.
Json outlierScreenJson(const OutlierScreen& screen, const OutlierOptions& options);

/// The fields every screen's REPORT.json block shares (what was tested and against what, the
/// threshold, how many beyond, the excluded list the cycle describes in its own terms): one form
/// for the touch cycles' screen and the readings' screens of the other instruments. `counted` names
/// what the screen counts ("touches", "values").
Json screenJson(const OutlierScreen& screen, const OutlierOptions& options, const std::string& test,
                const std::string& counted, Json excluded, const std::string& summary);

}  // namespace rotacal
