#include "core/sphere_centre_fit.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace rotacal {

SphereFit fitSphereCentre(const std::vector<Eigen::Vector3d>& t, const Eigen::Vector3d& start,
                          const SphereFitOptions& o) {
  if (!o.validate()) throw std::invalid_argument("sphere fit: rho_mm must be positive");
  const bool fit_r = o.fit_radius;  // 4 triggers in 3 directions fix centre and radius
  const int np = fit_r ? 4 : 3;
  if (static_cast<int>(t.size()) < 4)
    throw std::invalid_argument(fmt::format("sphere fit needs at least 4 triggers, got {}", t.size()));
  const int n = static_cast<int>(t.size());
  Eigen::Vector3d c = start;
  double rho = o.rho_mm;
  SphereFit f;
  Eigen::MatrixXd J(n, np);
  Eigen::VectorXd r(n);
  for (int it = 0; it < o.max_iterations; ++it) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d d = t[i] - c;
      const double dn = d.norm();
      r[i] = dn - rho;
      J.row(i).head<3>() = -d.transpose() / dn;  // d(|t - c|)/dc
      if (fit_r) J(i, 3) = -1.0;
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
    if (qr.rank() < np) throw std::invalid_argument("sphere fit: the triggers do not fix the centre (singular layout)");
    const Eigen::VectorXd step = qr.solve(-r);
    c += step.head<3>();
    if (fit_r) rho += step[3];
    f.iterations = it + 1;
    if (step.norm() < 1e-13) {
      f.converged = true;
      break;
    }
  }
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = t[i] - c;
    r[i] = d.norm() - rho;
    J.row(i).head<3>() = -d.transpose() / d.norm();
    if (fit_r) J(i, 3) = -1.0;
  }
  f.centre_mm = c;
  f.rho_mm = rho;
  f.radius_fitted = fit_r;
  f.triggers = n;
  f.dof = n - np;
  f.rss_mm2 = r.squaredNorm();
  f.residual_rms_um = 1e3 * std::sqrt(f.rss_mm2 / n);
  const Eigen::MatrixXd N = J.transpose() * J;
  f.cov_centre_per_sigma2 = N.inverse().topLeftCorner<3, 3>();
  return f;
}

SphereFitMap linearSphereFit(const std::vector<Eigen::Vector3d>& triggers, const std::vector<Eigen::Vector3d>& approaches,
                             const SphereFit& fit) {
  const int n = static_cast<int>(triggers.size());
  const int cols = fit.radius_fitted ? 4 : 3;
  Eigen::MatrixXd J(n, cols);
  Eigen::VectorXd nu(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d nj = (triggers[static_cast<size_t>(j)] - fit.centre_mm).normalized();
    J.block(j, 0, 1, 3) = -nj.transpose();
    if (fit.radius_fitted) J(j, 3) = -1.0;
    nu[j] = nj.dot(approaches[static_cast<size_t>(j)]);
  }
  const Eigen::MatrixXd pinv = J.completeOrthogonalDecomposition().pseudoInverse();
  SphereFitMap m;
  m.centre = -pinv.topRows(3) * nu.asDiagonal();
  m.residual = (Eigen::MatrixXd::Identity(n, n) - J * pinv) * nu.asDiagonal();
  return m;
}

}  // namespace rotacal
