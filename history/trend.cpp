#include "history/trend.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "core/statistics.hpp"  // chiSquareSurvival

namespace rotacal::history {

bool TrendOptions::validate(std::string* why) const {
  auto bad = [&](const char* w) {
    if (why) *why = w;
    return false;
  };
  if (!(alpha > 0 && alpha < 0.5)) return bad("alpha must be in (0, 0.5)");
  if (min_before_step < 2) return bad("min_before_step must be >= 2");
  if (min_after_step < 1) return bad("min_after_step must be >= 1");
  if (!(u_floor > 0)) return bad("u_floor must be > 0");
  return true;
}

double chiSquareQuantileUpper(double p, double k) {
  double lo = 0.0, hi = 1.0;
  while (chiSquareSurvival(hi, k) > p) hi *= 2;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chiSquareSurvival(mid, k) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

struct Fit {
  Eigen::VectorXd x;
  Eigen::MatrixXd cov;
  double chi2 = 0.0;
};

/// Weighted least squares of v on the columns of A (weights 1/u^2), by QR of the whitened system.
Fit wls(const Eigen::MatrixXd& A, const std::vector<TrendPoint>& p, double u_floor) {
  const Eigen::Index n = A.rows();
  Eigen::MatrixXd Aw = A;
  Eigen::VectorXd vw(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double w = 1.0 / std::max(p[static_cast<size_t>(i)].u, u_floor);
    Aw.row(i) *= w;
    vw[i] = p[static_cast<size_t>(i)].value * w;
  }
  Fit f;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Aw);
  f.x = qr.solve(vw);
  f.chi2 = (Aw * f.x - vw).squaredNorm();
  f.cov = (Aw.transpose() * Aw).inverse();
  return f;
}

}  // namespace

Trend analyzeTrend(const std::vector<TrendPoint>& p, const TrendOptions& o) {
  Trend t;
  t.n = static_cast<int>(p.size());
  if (t.n < 3) {
    t.verdict = "too few calibrations";
    if (t.n >= 1) t.mean = p.back().value;
    return t;
  }
  const Eigen::Index n = t.n;
  // Times relative to the first, so that the intercept is well conditioned.
  const double t0 = p.front().t_days;
  Eigen::MatrixXd A0 = Eigen::MatrixXd::Ones(n, 1);
  Eigen::MatrixXd A1(n, 2);
  for (Eigen::Index i = 0; i < n; ++i) A1.row(i) << 1.0, p[static_cast<size_t>(i)].t_days - t0;
  const Fit c = wls(A0, p, o.u_floor);
  const Fit d = wls(A1, p, o.u_floor);
  t.mean = c.x[0];
  t.chi2_constant = c.chi2;
  t.drift_per_day = d.x[1];
  t.drift_u = std::sqrt(d.cov(1, 1));
  t.chi2_drift = d.chi2;
  const double q1 = chiSquareQuantileUpper(o.alpha, 1);
  t.drift = c.chi2 - d.chi2 > q1;

  const int first = o.min_before_step - 1, last = t.n - 1 - o.min_after_step;
  const int splits = last - first + 1;
  if (splits >= 1 && t.n >= 4) {
    Fit best;
    int best_k = -1;
    for (int k = first; k <= last; ++k) {
      Eigen::MatrixXd A2(n, 3);
      A2.leftCols(2) = A1;
      for (Eigen::Index i = 0; i < n; ++i) A2(i, 2) = i > k ? 1.0 : 0.0;
      const Fit s = wls(A2, p, o.u_floor);
      if (best_k < 0 || s.chi2 < best.chi2) {
        best = s;
        best_k = k;
      }
    }
    t.chi2_step = best.chi2;
    t.step_size = best.x[2];
    t.step_u = std::sqrt(best.cov(2, 2));
    t.step_drift_per_day = best.x[1];
    t.step = d.chi2 - best.chi2 > chiSquareQuantileUpper(o.alpha / splits, 1);
    if (t.step) {
      t.step_after = best_k;
      // With the step explained, is there a drift besides it? Same test, inside the step model.
      Eigen::MatrixXd As(n, 2);
      for (Eigen::Index i = 0; i < n; ++i) As.row(i) << 1.0, i > best_k ? 1.0 : 0.0;
      const Fit s0 = wls(As, p, o.u_floor);
      t.drift = s0.chi2 - best.chi2 > q1;
      // The slope beside the step (the straight line alone is the wrong model now).
      t.drift_per_day = best.x[1];
      t.drift_u = std::sqrt(best.cov(1, 1));
    }
  }
  t.verdict = t.step ? (t.drift ? "step + drift" : "step") : (t.drift ? "drift" : "stable");
  return t;
}

}  // namespace rotacal::history
