#pragma once
// The distributions every cycle's tests use, from Boost.Math (Debian libboost-math-dev): the
// field's maintained implementation, in place of the hand-written tails each cycle once had.
// Upper tails are computed directly (complement), so p-values far below 1e-16 keep their digits.

#include <vector>

namespace rotacal {

/// P(X > x) for X ~ chi-square with k degrees of freedom (k > 0). 1 for x <= 0.
double chiSquareSurvival(double x, double k);
/// The x with P(X > x) = p for chi-square with k degrees of freedom; p in (0, 1).
double chiSquareUpperQuantile(double p, double k);

/// A statistic's null as a scaled chi-square, scale x chi2(dof), from draws of it: the draws'
/// mean and variance matched (Satterthwaite). For a quadratic form of a scale mixture of normals
/// (the linear axes' nodes, one spacing per machine) whose upper tail chi2(rank) would read too
/// light. Needs >= 2 draws with positive mean and variance; otherwise draws = 0 and scale = 1.
struct ScaledChiSquare {
  int draws = 0;
  double scale = 1.0;
  double dof = 0.0;
};
ScaledChiSquare scaledChiSquareFromDraws(const std::vector<double>& values);
/// P(|T| > |t|) for Student's t with nu > 0 degrees of freedom.
double studentTwoSided(double t, double nu);
/// P(F > f) for Fisher's F with (d1, d2) degrees of freedom. 1 for f <= 0.
double fSurvival(double f, double d1, double d2);
/// The z with P(Z < z) = p for the standard normal; p in (0, 1).
double normalQuantile(double p);
/// The half-width q of the symmetric interval [-q, q] that holds the fraction p of X + E, where X
/// is given by Monte Carlo samples and E ~ N(0, sd^2) is independent of it: q solves
/// mean_j P(|x_j + E| <= q) = p (JCGM 101 Sec. 7.7 with the normal part convolved analytically).
/// sd = 0: the samples' own p-quantile of |x|. p in (0, 1), samples not empty, sd >= 0.
double coverageHalfWidth(const std::vector<double>& samples, double sd, double p);

}  // namespace rotacal
