#include "core/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace rotacal {
namespace {

// Errors as std::invalid_argument (core's rule), never Boost's own exception types or errno.
using Policy = boost::math::policies::policy<boost::math::policies::domain_error<boost::math::policies::throw_on_error>,
                                             boost::math::policies::overflow_error<boost::math::policies::throw_on_error>>;

template <class F>
double guarded(const char* what, F&& f) {
  try {
    return f();
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string(what) + ": " + e.what());
  }
}

}  // namespace

double chiSquareSurvival(double x, double k) {
  if (!(k > 0)) throw std::invalid_argument("chiSquareSurvival: k must be > 0");
  if (!(x > 0)) return 1.0;
  if (std::isinf(x)) return 0.0;
  return guarded("chiSquareSurvival",
                 [&] { return cdf(complement(boost::math::chi_squared_distribution<double, Policy>(k), x)); });
}

double chiSquareUpperQuantile(double p, double k) {
  if (!(k > 0) || !(p > 0 && p < 1)) throw std::invalid_argument("chiSquareUpperQuantile: k > 0 and p in (0, 1)");
  return guarded("chiSquareUpperQuantile",
                 [&] { return quantile(complement(boost::math::chi_squared_distribution<double, Policy>(k), p)); });
}

double studentTwoSided(double t, double nu) {
  if (!(nu > 0)) throw std::invalid_argument("studentTwoSided: nu must be > 0");
  if (std::isnan(t)) throw std::invalid_argument("studentTwoSided: t is not a number");
  if (std::isinf(t)) return 0.0;
  return guarded("studentTwoSided", [&] {
    return 2.0 * cdf(complement(boost::math::students_t_distribution<double, Policy>(nu), std::abs(t)));
  });
}

double fSurvival(double f, double d1, double d2) {
  if (!(d1 > 0) || !(d2 > 0)) throw std::invalid_argument("fSurvival: d1 and d2 must be > 0");
  if (!(f > 0)) return 1.0;
  if (std::isinf(f)) return 0.0;
  return guarded("fSurvival",
                 [&] { return cdf(complement(boost::math::fisher_f_distribution<double, Policy>(d1, d2), f)); });
}

double normalQuantile(double p) {
  if (!(p > 0 && p < 1)) throw std::invalid_argument("normalQuantile: p must be in (0, 1)");
  return guarded("normalQuantile", [&] { return quantile(boost::math::normal_distribution<double, Policy>(), p); });
}

double coverageHalfWidth(const std::vector<double>& samples, double sd, double p) {
  if (!(p > 0 && p < 1)) throw std::invalid_argument("coverageHalfWidth: p must be in (0, 1)");
  if (samples.empty()) throw std::invalid_argument("coverageHalfWidth: no samples");
  if (!(sd >= 0) || !std::isfinite(sd)) throw std::invalid_argument("coverageHalfWidth: sd must be finite and >= 0");
  double reach = 0.0;
  for (double x : samples) {
    if (!std::isfinite(x)) throw std::invalid_argument("coverageHalfWidth: a sample is not finite");
    reach = std::max(reach, std::abs(x));
  }
  const auto n = static_cast<double>(samples.size());
  if (sd == 0.0) {
    std::vector<double> a(samples.size());
    std::transform(samples.begin(), samples.end(), a.begin(), [](double x) { return std::abs(x); });
    const auto i = static_cast<size_t>(std::max(0.0, std::ceil(p * n) - 1.0));
    std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(i), a.end());
    return a[i];
  }
  // P(|x + E| <= q) = Phi((q - x)/sd) - Phi((-q - x)/sd), rising in q: bisection on the mean.
  const double s2 = sd * std::sqrt(2.0);
  const auto held = [&](double q) {
    double sum = 0.0;
    for (double x : samples) sum += 0.5 * (std::erfc((-q - x) / s2) - std::erfc((q - x) / s2));
    return sum / n;
  };
  double lo = 0.0, hi = reach + 10.0 * sd;
  for (int it = 0; it < 40 && hi - lo > 1e-9 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (held(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

ScaledChiSquare scaledChiSquareFromDraws(const std::vector<double>& c) {
  ScaledChiSquare out;
  if (c.size() < 2) return out;
  double mean = 0.0;
  for (double v : c) mean += v;
  mean /= static_cast<double>(c.size());
  double var = 0.0;
  for (double v : c) var += (v - mean) * (v - mean);
  var /= static_cast<double>(c.size() - 1);
  if (!(mean > 0 && var > 0)) return out;
  out.draws = static_cast<int>(c.size());
  out.scale = var / (2.0 * mean);
  out.dof = 2.0 * mean * mean / var;
  return out;
}

}  // namespace rotacal
