#pragma once
// The shared estimation engine: weighted Gauss-Newton with rank handling.
// A problem gives its whitened residuals r(x) = W^(1/2) (y - f(x)) and their Jacobian J_r_x;
// the engine scales the columns, takes the minimum-norm Gauss-Newton step through a truncated
// SVD (directions the data cannot see keep their starting value instead of blowing up), and
// returns the estimate with its covariance and a Summary, as Ceres' Solve() does.
#include <Eigen/Core>
#include <functional>
#include <string>

namespace rotacal {

struct LeastSquaresOptions {
  int max_iterations = 50;
  /// Converged when the scaled step is below this (the scale of each parameter is its column
  /// norm: a step of 1e-12 changes no residual by more than 1e-12 of a whitened unit).
  double step_tolerance = 1e-12;
  /// Converged too when a step changes the cost by less than this fraction of it (Ceres'
  /// function_tolerance, whose default is 1e-6): a fit with a residual stops at the rounding of
  /// its whitened residuals, about 1e-10 of the cost for mm-sized positions at um noise, far above
  /// step_tolerance. At 1e-9 the parameters are within about 1e-4 of their standard deviation of
  /// the minimum (cost change 0.5 d^T H d for a cost of the order of the residual count).
  double function_tolerance = 1e-9;
  /// A singular value below rank_tolerance x the largest is a direction the data cannot see.
  /// 1e-9: four decades above double rounding of a 1e-16-relative Jacobian squared, and far
  /// below the smallest ratio a designed plan has (1e-4).
  double rank_tolerance = 1e-9;
  /// A problem's own measure of convergence, asked after every step beside the tolerances above
  /// (Ceres' IterationCallback returning SOLVER_TERMINATE_SUCCESSFULLY): given x before and after
  /// the step, true stops the solve as converged. Empty: the tolerances alone decide.
  std::function<bool(const Eigen::VectorXd& before, const Eigen::VectorXd& after)> converged;
  /// False, and what is wrong naming the field, when invalid (Ceres' Options::IsValid).
  bool validate(std::string* why) const;
};

/// Why a fit stopped. The engine itself ends Converged, MaxIterations or InvalidInput; a
/// problem that needs every parameter it fits says RankDeficient when the data leave one unseen.
enum class Termination { Converged, MaxIterations, RankDeficient, InvalidInput };
std::string_view terminationName(Termination t);  // "converged", "max_iterations", "rank_deficient", "invalid_input"

/// What every fit reports (Ceres' Solver::Summary), the engine's and the problems' that wrap it:
/// the engine fills the counts, rank, condition and costs; a problem whose residuals are lengths
/// adds their rms and the a-posteriori noise, and may set its own dof and message.
struct FitSummary {
  Termination termination = Termination::InvalidInput;
  std::string message;          // why it stopped, or what is invalid
  int iterations = 0;
  int observations = 0;         // residuals
  int parameters = 0;
  int rank = 0;                 // of J_r_x at the solution, column-scaled
  double condition = 0.0;       // of the column-scaled J_r_x over its rank
  double initial_cost = 0.0;    // 0.5 |r|^2 at the start
  double cost = 0.0;            // 0.5 |r|^2 at the solution
  int dof = 0;                  // observations - parameters (a problem may count otherwise)
  double residual_rms_um = 0.0; // problems whose residuals are lengths
  double sigma_um = 0.0;        // a-posteriori noise sqrt(RSS / dof), the same
  bool usable() const { return termination == Termination::Converged; }
  std::string briefReport() const;
};

/// r(x) and, when J is not null, J_r_x (observations x parameters).
using ResidualFunction = std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J)>;

struct LeastSquaresResult {
  Eigen::VectorXd x;
  /// Covariance of x for whitened residuals of unit variance: the pseudo-inverse of J^T J
  /// (zero along the directions the data cannot see: those are fixed at their start, not estimated).
  Eigen::MatrixXd covariance;
  /// Columns: a basis of the directions of x the data cannot see (J v = 0), each of unit length
  /// in the scaled parameters and mapped back to parameter units.
  Eigen::MatrixXd null_space;
  FitSummary summary;
};

LeastSquaresResult solveLeastSquares(const ResidualFunction& residuals, const Eigen::VectorXd& x0,
                                     const LeastSquaresOptions& options = {});

}  // namespace rotacal
