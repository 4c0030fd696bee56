#pragma once
// Positioning errors of the linear axes as 000 Sec. 5 models them (Eq. (22)-(23)), drawn for one
// Monte Carlo run. For the moving axis a in {X, Y, Z} at its read position q (machine frame, mm):
//
//   E_aa(q) = E_aa,lin * q + interpolate(Q_i, E_aa,rand(Q_i), q)      (positioning, Eq. (22))
//   E_ba(q) = S_ba * q     + interpolate(Q_i, E_ba,rand(Q_i), q)      (b != a: straightness, and
//                                                                      squareness for S_xy S_xz S_yz,
//                                                                      Eq. (23))
// with nodes Q_i = p_a * i (i integer, so Q_0 is the machine origin: the rotary-axis
// intersection), the node spacing p_a uniform in [p_min, p_max] (000: [20, 50] mm) per axis and run,
// node values independent N(0, u), and linear interpolation between nodes. Only the squareness
// terms S_xy (X error along Y), S_xz (X error along Z) and S_yz (Y error along Z) exist: the other
// three are the same squareness seen from the other axis. Angular errors of the linear axes are
// neglected, as in 000.
//
// The total error at a read position c is the sum over the three axes, each evaluated at its own
// coordinate: E(c) = sum_a E_.a(c_a). It is "actual ball centre minus read position" as a function
// of the read position: the sign convention of Truth::linear_axis_error (core/simulation.hpp).
#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "core/rng.hpp"

namespace rotacal {

/// Interpolated node values of one axis for the three error directions.
struct AxisNodes {
  double spacing_mm = 0.0;                 // p_a; 0: no random part
  double inv_spacing = 0.0;                // 1 / p_a when set by drawAxisNodes (0: computed)
  int first = 0;                           // index i of the first stored node (at p_a * first)
  std::array<std::vector<double>, 3> mm;   // node values per error direction (x, y, z), mm

  /// Random part at coordinate q (mm): linear interpolation; constant beyond the drawn nodes.
  Eigen::Vector3d at(double q) const;
  /// Node k and weight t so that value = (1 - t) v[k] + t v[k + 1] (k, k + 1 are stored indices).
  void locate(double q, int* k, double* t) const;
};

/// One drawn realisation of the linear axes' errors (lengths in mm, slopes in mm/mm).
struct LinearAxisErrors {
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();  // E_xx,lin E_yy,lin E_zz,lin
  double S_xy = 0.0, S_xz = 0.0, S_yz = 0.0;        // squareness
  std::array<AxisNodes, 3> nodes;                   // random parts of the X, Y, Z axes

  /// Actual ball centre minus read position at the read position c (machine frame).
  Eigen::Vector3d error(const Eigen::Vector3d& c_m) const;
  /// The same as a function for Truth::linear_axis_error (copies this realisation).
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> asFunction() const;
};

/// The standard uncertainties (k = 1) of 000 Table 5 for the linear axes, internal units.
struct LinearAxisModel {
  Eigen::Vector3d u_scale = Eigen::Vector3d::Zero();  // per axis, mm/mm
  Eigen::Matrix3d u_rand = Eigen::Matrix3d::Zero();   // (direction, axis), mm: u_rand(1, 0) = E_yx,rand
  double u_S_xy = 0.0, u_S_xz = 0.0, u_S_yz = 0.0;    // mm/mm
  double spacing_min_mm = 20.0, spacing_max_mm = 50.0;

  bool validate(std::string* why) const;
};

/// The correlation of one axis's random part at coordinates x and y (mm): E_p[sum_k phi_k(x)
/// phi_k(y)] for the hat functions on the nodes p k, p uniform in [spacing_min, spacing_max] as
/// drawAxisNodes draws it (000 Eq. (22)); by the midpoint rule over p (256 intervals: the
/// integrand is piecewise smooth in p; error below 1e-3). u_ba^2 times it is the covariance.
double nodeCorrelation(double x_mm, double y_mm, double spacing_min_mm, double spacing_max_mm);

/// Draws the node spacing and the node values of one axis covering [lo, hi] with one node to
/// spare on each side (interpolation never leaves the drawn nodes for positions within um of the
/// range). An axis whose three random uncertainties are zero draws nothing (spacing 0).
void drawAxisNodes(const LinearAxisModel& model, int axis, double lo_mm, double hi_mm, Rng& rng, AxisNodes* out);

/// A full realisation: scale and squareness from `rng_fixed` (6 normal variates, always drawn),
/// axis a's nodes from rng_axis[a], covering the coordinate ranges lo..hi (machine frame).
/// Reuses out's storage (no allocation once sized).
void drawLinearAxisErrors(const LinearAxisModel& model, const Eigen::Vector3d& lo_mm, const Eigen::Vector3d& hi_mm,
                          Rng& rng_fixed, const std::array<Rng*, 3>& rng_axis, LinearAxisErrors* out);

}  // namespace rotacal
