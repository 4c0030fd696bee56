#include "core/least_squares.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <cmath>

#include "core/require_valid.hpp"

namespace rotacal {

bool LeastSquaresOptions::validate(std::string* why) const {
  if (max_iterations < 1) return invalidBecause(why, "max_iterations must be >= 1");
  if (!(step_tolerance > 0)) return invalidBecause(why, "step_tolerance must be > 0");
  if (!(function_tolerance >= 0 && function_tolerance < 1)) return invalidBecause(why, "function_tolerance must be in [0, 1)");
  if (!(rank_tolerance > 0 && rank_tolerance < 1)) return invalidBecause(why, "rank_tolerance must be in (0, 1)");
  return true;
}

std::string_view terminationName(Termination t) {
  static constexpr std::string_view kNames[] = {"converged", "max_iterations", "rank_deficient", "invalid_input"};
  return kNames[static_cast<int>(t)];
}

std::string FitSummary::briefReport() const {
  return fmt::format("{}: {} iterations, {} residuals, {} parameters, rank {}, cost {:.6g} -> {:.6g}{}{}",
                     terminationName(termination), iterations, observations, parameters, rank, initial_cost,
                     cost, message.empty() ? "" : ": ", message);
}

namespace {

// Column scale: the norm of each column, so that a rank decision does not depend on whether a
// parameter is in mm or rad. A column of zeros keeps scale 1 (and is then in the null space).
Eigen::VectorXd columnScale(const Eigen::MatrixXd& J) {
  Eigen::VectorXd s(J.cols());
  for (Eigen::Index j = 0; j < J.cols(); ++j) {
    const double n = J.col(j).norm();
    s[j] = n > 0 ? n : 1.0;
  }
  return s;
}

}  // namespace

LeastSquaresResult solveLeastSquares(const ResidualFunction& f, const Eigen::VectorXd& x0,
                                     const LeastSquaresOptions& o) {
  LeastSquaresResult out;
  out.x = x0;
  out.summary.parameters = static_cast<int>(x0.size());
  if (std::string bad; !o.validate(&bad)) {
    out.summary.message = bad;
    return out;
  }
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  f(out.x, r, &J);
  out.summary.observations = static_cast<int>(r.size());
  if (J.rows() != r.size() || J.cols() != x0.size()) {
    out.summary.message = fmt::format("the Jacobian is {}x{}, expected {}x{}", J.rows(), J.cols(), r.size(), x0.size());
    return out;
  }
  if (!r.allFinite() || !J.allFinite()) {
    out.summary.message = "the residuals or the Jacobian are not finite at the start";
    return out;
  }
  out.summary.initial_cost = 0.5 * r.squaredNorm();
  out.summary.termination = Termination::MaxIterations;
  Eigen::VectorXd s;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd;
  for (int it = 1; it <= o.max_iterations; ++it) {
    s = columnScale(J);
    svd.compute(J * s.cwiseInverse().asDiagonal(), Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(o.rank_tolerance);
    // Gauss-Newton: J dx = -r, minimum norm in the scaled parameters.
    const Eigen::VectorXd step_scaled = svd.solve(-r);
    const Eigen::VectorXd before = out.x;
    out.x += s.cwiseInverse().asDiagonal() * step_scaled;
    out.summary.iterations = it;
    const double cost_before = 0.5 * r.squaredNorm();
    f(out.x, r, &J);
    if (!r.allFinite() || !J.allFinite()) {
      out.summary.termination = Termination::InvalidInput;
      out.summary.message = fmt::format("the residuals became non-finite at iteration {}", it);
      return out;
    }
    const double cost = 0.5 * r.squaredNorm();
    if (step_scaled.norm() < o.step_tolerance || std::abs(cost_before - cost) <= o.function_tolerance * cost_before ||
        (o.converged && o.converged(before, out.x))) {
      out.summary.termination = Termination::Converged;
      break;
    }
  }
  out.summary.cost = 0.5 * r.squaredNorm();
  s = columnScale(J);
  Eigen::JacobiSVD<Eigen::MatrixXd> fin(J * s.cwiseInverse().asDiagonal(), Eigen::ComputeFullV);
  fin.setThreshold(o.rank_tolerance);
  const int rank = static_cast<int>(fin.rank());
  out.summary.rank = rank;
  const Eigen::Index n = x0.size();
  const Eigen::VectorXd& sv = fin.singularValues();
  out.summary.condition = rank > 0 ? sv[0] / sv[rank - 1] : INFINITY;
  out.summary.dof = out.summary.observations - out.summary.parameters;
  const Eigen::MatrixXd& V = fin.matrixV();
  Eigen::MatrixXd cov_scaled = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < rank; ++k) cov_scaled += V.col(k) * V.col(k).transpose() / (sv[k] * sv[k]);
  const auto Sinv = s.cwiseInverse().asDiagonal();
  out.covariance = Sinv * cov_scaled * Sinv;
  out.null_space.resize(n, n - rank);
  for (Eigen::Index k = rank; k < n; ++k) out.null_space.col(k - rank) = Sinv * V.col(k);
  if (out.summary.termination == Termination::MaxIterations)
    out.summary.message = fmt::format("the step did not fall below {} in {} iterations", o.step_tolerance, o.max_iterations);
  return out;
}

}  // namespace rotacal
