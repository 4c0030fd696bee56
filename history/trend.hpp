#pragma once
// Trend of one parameter over a machine's calibrations: slow drift or a step change (crash,
// maintenance)? Each calibration gives a value v_i with its standard uncertainty u_i (k = 1,
// from the fit) at time t_i. Weighted least squares, weights 1/u_i^2, three nested models:
//   constant     v = a
//   drift        v = a + b t
//   drift + step v = a + b t + d [i > k]   (step between calibrations k and k+1)
// Drift is flagged when the line lowers chi^2 by more than the 1 - alpha quantile of chi^2(1)
// (the slope differs from 0 by more than its uncertainty allows). A step is flagged when the best
// split lowers chi^2 against the drift model by more than the 1 - alpha/m quantile of chi^2(1),
// m the number of splits tried (Bonferroni: the split is chosen from the data). A step therefore
// needs to beat a straight line: a slow drift is never called a step however large it grows.
#include <optional>
#include <string>
#include <vector>

namespace rotacal::history {

struct TrendOptions {
  double alpha = 1e-3;       // false-alarm rate of each test (per parameter)
  int min_before_step = 2;   // calibrations needed before a step (a line needs two)
  int min_after_step = 1;
  double u_floor = 1e-6;     // smallest u accepted (report units), so weights stay finite

  bool validate(std::string* why) const;
};

struct TrendPoint {
  double t_days = 0.0;  // time of the calibration, days from any origin
  double value = 0.0;
  double u = 0.0;       // standard uncertainty, k = 1, same unit as value
};

struct Trend {
  int n = 0;
  double mean = 0.0, chi2_constant = 0.0;                   // constant model
  double drift_per_day = 0.0, drift_u = 0.0, chi2_drift = 0.0;  // drift model
  bool drift = false;
  std::optional<int> step_after;  // index (0-based) of the last calibration before the step
  double step_size = 0.0, step_u = 0.0, chi2_step = 0.0;
  double step_drift_per_day = 0.0;  // slope of the drift + step model
  bool step = false;
  std::string verdict;  // "step", "drift", "stable", or "too few calibrations"
};

/// The tests above on points in time order. Needs n >= 3 for drift, n >= min_before + min_after
/// (and one more than the drift model's 2 parameters) for a step.
Trend analyzeTrend(const std::vector<TrendPoint>& points, const TrendOptions& options);

/// The x with P(chi^2(k) > x) = p (bisection on chiSquareSurvival).
double chiSquareQuantileUpper(double p, double k);

}  // namespace rotacal::history
