#include "core/sphere_centre_fit.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "core/least_squares.hpp"
#include "core/require_valid.hpp"

namespace rotacal {

SphereFit fitSphereCentre(const std::vector<Eigen::Vector3d>& t, const Eigen::Vector3d& start,
                          const SphereFitOptions& o) {
  requireValid(o, "sphere fit");
  const bool fit_r = o.fit_radius;  // 4 triggers in 3 directions fix centre and radius
  const int np = fit_r ? 4 : 3;
  if (static_cast<int>(t.size()) < 4)
    throw std::invalid_argument(fmt::format("sphere fit needs at least 4 triggers, got {}", t.size()));
  const int n = static_cast<int>(t.size());
  SphereFit f;
  // The shared engine (core/least_squares) over the centre (and the radius), r = |t - c| - rho;
  // converged when a step moves them by less than 1e-13 mm, the engine's own tolerances off.
  const auto unpack = [&](const Eigen::VectorXd& x, Eigen::Vector3d* c, double* rho) {
    *c = x.head<3>();
    *rho = fit_r ? x[3] : o.rho_mm;
  };
  const ResidualFunction radial = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    Eigen::Vector3d c;
    double rho = 0.0;
    unpack(x, &c, &rho);
    r.resize(n);
    if (J) J->resize(n, np);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d d = t[static_cast<size_t>(i)] - c;
      r[i] = d.norm() - rho;
      if (!J) continue;
      J->row(i).head<3>() = -d.transpose() / d.norm();  // d(|t - c|)/dc
      if (fit_r) (*J)(i, 3) = -1.0;
    }
  };
  Eigen::VectorXd x0(np);
  x0.head<3>() = start;
  if (fit_r) x0[3] = o.rho_mm;
  {
    Eigen::VectorXd r;
    Eigen::MatrixXd J;
    radial(x0, r, &J);
    if (Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(J).rank() < np)
      throw std::invalid_argument("sphere fit: the triggers do not fix the centre (singular layout)");
  }
  LeastSquaresOptions lo;
  lo.max_iterations = o.max_iterations;
  lo.step_tolerance = std::numeric_limits<double>::min();
  lo.function_tolerance = 0.0;
  lo.converged = [](const Eigen::VectorXd& before, const Eigen::VectorXd& after) { return (after - before).norm() < 1e-13; };
  const LeastSquaresResult solved = solveLeastSquares(radial, x0, lo);
  if (solved.summary.rank < np) throw std::invalid_argument("sphere fit: the triggers do not fix the centre (singular layout)");
  f.iterations = solved.summary.iterations;
  f.converged = solved.summary.usable();
  Eigen::Vector3d c;
  double rho = 0.0;
  unpack(solved.x, &c, &rho);
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  radial(solved.x, r, &J);
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
