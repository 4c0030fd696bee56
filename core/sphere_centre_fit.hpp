#pragma once
// The centre of a sphere from probe triggers: each trigger is the probe-ball centre when the ball
// touched, so it lies at rho = R + r (sphere radius + ball radius) from the sphere centre. Exact
// geometry, Gauss-Newton on |t_i - c| - rho.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/require_valid.hpp"

namespace rotacal {

struct SphereFitOptions {
  double rho_mm = 0.0;       // nominal R + r; start value of the fitted radius
  bool fit_radius = true;    // fit rho too (4 triggers then fix it exactly; 5 leave one dof)
  int max_iterations = 50;
  bool validate(std::string* why) const {
    if (!(rho_mm > 0)) return invalidBecause(why, "rho_mm must be > 0");
    if (max_iterations < 1) return invalidBecause(why, "max_iterations must be >= 1");
    return true;
  }
};

struct SphereFit {
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();
  double rho_mm = 0.0;             // fitted (or held) R + r
  bool radius_fitted = false;
  double residual_rms_um = 0.0;
  double rss_mm2 = 0.0;            // sum of squared radial residuals
  int triggers = 0;
  int iterations = 0;
  int dof = 0;
  Eigen::Matrix3d cov_centre_per_sigma2 = Eigen::Matrix3d::Zero();  // (J^T J)^-1 block, mm^2 per mm^2 of noise
  bool converged = false;
};

/// Fits the sphere; start is a centre guess (the nominal centre). Throws std::invalid_argument
/// with fewer than 4 triggers or a layout that does not fix the unknowns.
SphereFit fitSphereCentre(const std::vector<Eigen::Vector3d>& triggers_mm, const Eigen::Vector3d& start_mm,
                          const SphereFitOptions& options);

/// The fit linearised at its solution, for uncertainty propagation: how the centre and the
/// residual move when each trigger moves by d s_j along its approach u_j (triggers pushed along
/// the approach, as pretravel, noise and axis errors move them). With J = [-n_j^T, -1] (n_j the
/// unit normal from the centre to trigger j; the -1 column only when the radius is fitted):
/// d centre = -pinv(J)_xyz diag(n.u) d s, d residual = (I - J pinv(J)) diag(n.u) d s.
struct SphereFitMap {
  Eigen::MatrixXd centre;    // 3 x triggers, mm per mm
  Eigen::MatrixXd residual;  // triggers x triggers
};
SphereFitMap linearSphereFit(const std::vector<Eigen::Vector3d>& triggers_mm,
                             const std::vector<Eigen::Vector3d>& approaches, const SphereFit& fit);

}  // namespace rotacal
