#pragma once
// The judge's probe-like design (a table's 8 angles, 6 repeats, 5 points per angle), its three
// catalogued causes and its synthetic data: the judge test asserts on it and the judge bench
// prints its rates, on the same problem.
#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/judge.hpp"
#include "core/rng.hpp"

namespace rotacal::test {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// A probe-like cycle: 8 table angles, 6 repeats 0.5 h apart (the cycle takes 0.4 h), 5 points
// per angle along a local position u in [-1, 1] (units of 100 mm). One deviation per point.
struct ProbeDesign {
  std::vector<double> theta, t_h, u;
  std::vector<int> angle, repeat;
  int n() const { return static_cast<int>(theta.size()); }
};

inline ProbeDesign probeDesign(int repeats = 6) {
  ProbeDesign d;
  for (int r = 0; r < repeats; ++r)
    for (int a = 0; a < 8; ++a)
      for (int k = 0; k < 5; ++k) {
        d.theta.push_back(a * kPi / 4);
        d.t_h.push_back(0.5 * r + 0.05 * a);
        d.u.push_back(-1.0 + 0.5 * k);
        d.angle.push_back(a);
        d.repeat.push_back(r);
      }
  return d;
}

inline Eigen::MatrixXd probeBaseline(const ProbeDesign& d) {
  Eigen::MatrixXd J(d.n(), 4);
  for (int i = 0; i < d.n(); ++i) J.row(i) << 1.0, std::cos(d.theta[i]), std::sin(d.theta[i]), d.u[i];
  return J;
}

inline JudgeCause driftCause(const ProbeDesign& d) {
  JudgeCause c{"thermal_drift", "the table's position drifts linearly with time", Eigen::MatrixXd(d.n(), 3),
               {{"dz/h", "um/h"}, {"dx/h", "um/h"}, {"dy/h", "um/h"}}};
  for (int i = 0; i < d.n(); ++i) c.J.row(i) << d.t_h[i], d.t_h[i] * std::cos(d.theta[i]), d.t_h[i] * std::sin(d.theta[i]);
  return c;
}

inline JudgeCause harmonicCause(const ProbeDesign& d) {
  JudgeCause c{"rotary_error_motion", "the axis's centre moves twice per turn", Eigen::MatrixXd(d.n(), 2),
               {{"cos2C", "um"}, {"sin2C", "um"}}};
  for (int i = 0; i < d.n(); ++i) c.J.row(i) << std::cos(2 * d.theta[i]), std::sin(2 * d.theta[i]);
  return c;
}

inline JudgeCause scaleCause(const ProbeDesign& d) {
  JudgeCause c{"linear_axis_scale", "the X axis positions with a scale error", Eigen::MatrixXd(d.n(), 1),
               {{"s", "um/100mm"}}};
  for (int i = 0; i < d.n(); ++i) c.J(i, 0) = d.u[i] * std::cos(d.theta[i]);
  return c;
}

inline JudgeProblem probeProblem(const ProbeDesign& d, const Eigen::VectorXd& y, double sigma_declared) {
  JudgeProblem p;
  p.y = y;
  p.sigma = Eigen::VectorXd::Constant(d.n(), sigma_declared);
  p.J0 = probeBaseline(d);
  p.baseline_parameters = {{"dz", "um"}, {"dx", "um"}, {"dy", "um"}, {"tilt", "um/100mm"}};
  p.causes = {driftCause(d), harmonicCause(d), scaleCause(d)};
  p.group_name = "pose x repeat";
  JudgeFactor angle{"angle", {}, {}, ""}, repeat{"repeat", {}, {}, ""}, u{"u", {}, d.u, "100 mm"},
      time{"time", {}, d.t_h, "h"};
  for (int i = 0; i < d.n(); ++i) {
    p.groups.push_back(100 * d.repeat[i] + d.angle[i]);
    angle.levels.push_back(std::to_string(45 * d.angle[i]));
    repeat.levels.push_back(std::to_string(d.repeat[i] + 1));
  }
  p.factors = {angle, repeat, u, time};
  return p;
}

/// Deviations: baseline errors drawn per seed, an optional injected effect, Gaussian noise.
inline Eigen::VectorXd probeData(const ProbeDesign& d, std::uint64_t seed, double sigma_actual,
                          const Eigen::VectorXd& effect = Eigen::VectorXd()) {
  Rng rng(seed, 16);
  Eigen::Vector4d beta;
  for (int j = 0; j < 4; ++j) beta[j] = rng.uniform(-20.0, 20.0);
  Eigen::VectorXd y = probeBaseline(d) * beta;
  if (effect.size()) y += effect;
  for (int i = 0; i < d.n(); ++i) y[i] += sigma_actual * rng.normal();
  return y;
}

}  // namespace rotacal::test
