#include "core/compensation.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "core/least_squares.hpp"
#include "core/require_valid.hpp"
#include "core/units.hpp"

namespace rotacal {

bool CompensationOptions::validate(std::string* why) const {
  if (!(std::abs(tool_axis_m.norm() - 1.0) < 1e-9)) return invalidBecause(why, "tool_axis_m must be a unit vector");
  if (max_iterations < 1) return invalidBecause(why, "max_iterations must be >= 1");
  if (!(step_tolerance_rad > 0)) return invalidBecause(why, "step_tolerance_rad must be > 0");
  if (!(singular_blend_deg > 0 && singular_blend_deg < 45)) return invalidBecause(why, "singular_blend_deg must be in (0, 45) deg");
  return true;
}

bool SubdivisionOptions::validate(std::string* why) const {
  if (!(max_deviation_mm > 0)) return invalidBecause(why, "max_deviation_mm must be > 0");
  if (samples_per_piece < 1) return invalidBecause(why, "samples_per_piece must be >= 1");
  if (max_pieces < 1) return invalidBecause(why, "max_pieces must be >= 1");
  return true;
}

namespace {

// The two rotary axes a kinematics moves, as pointers into Pose.
std::array<double Pose::*, 2> rotaryMembers(Kinematics k) {
  if (k == Kinematics::TableAC) return {&Pose::A, &Pose::C};
  if (k == Kinematics::TableAB) return {&Pose::B, &Pose::A};
  return {&Pose::B, &Pose::C};
}

// Tool direction in the workpiece frame: R_m_w^T k.
Eigen::Vector3d toolInWorkpiece(const GeometricErrors& e, const Pose& q, const Eigen::Vector3d& k) {
  return T_m_w(e, q).linear().transpose() * k;
}

// J_t_q: derivative of the tool direction in the workpiece frame with respect to the two rotary
// angles (per rad), central differences of the exact model.
Eigen::Matrix<double, 3, 2> J_t_q(const GeometricErrors& e, const Pose& q, const Eigen::Vector3d& k) {
  const auto axes = rotaryMembers(e.kinematics());
  constexpr double h_deg = 1e-4;
  Eigen::Matrix<double, 3, 2> J;
  for (int j = 0; j < 2; ++j) {
    Pose plus = q, minus = q;
    plus.*axes[j] += h_deg;
    minus.*axes[j] -= h_deg;
    J.col(j) = (toolInWorkpiece(e, plus, k) - toolInWorkpiece(e, minus, k)) / degToRad(2 * h_deg);
  }
  return J;
}

Pose lerp(const Pose& a, const Pose& b, double s) {
  return Pose{a.A + s * (b.A - a.A), a.B + s * (b.B - a.B), a.C + s * (b.C - a.C)};
}

MachineCommand lerp(const MachineCommand& a, const MachineCommand& b, double s) {
  return MachineCommand{a.x_m_mm + s * (b.x_m_mm - a.x_m_mm), lerp(a.pose, b.pose, s)};
}

}  // namespace

double toolDirectionError(const GeometricErrors& errors, const Pose& pose, const Pose& nominal_pose,
                          const Eigen::Vector3d& k) {
  const GeometricErrors nominal(LocationErrors{errors.kinematics(), ErrorVector::Zero()});
  const Eigen::Vector3d t = toolInWorkpiece(errors, pose, k);
  const Eigen::Vector3d t0 = toolInWorkpiece(nominal, nominal_pose, k);
  return std::atan2(t.cross(t0).norm(), t.dot(t0));
}

CompensatedCommand compensatePose(const GeometricErrors& errors, const Pose& nominal_pose,
                                  const CompensationOptions& options) {
  requireValid(options, "CompensationOptions");
  const GeometricErrors nominal(LocationErrors{errors.kinematics(), ErrorVector::Zero()});
  const Eigen::Vector3d& k = options.tool_axis_m;
  const Eigen::Vector3d t0 = toolInWorkpiece(nominal, nominal_pose, k);
  const auto axes = rotaryMembers(errors.kinematics());
  // The damping of the weak direction, from the nominal machine at the nominal pose only: it
  // varies smoothly along a path, so the command does too.
  Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd0(J_t_q(nominal, nominal_pose, k), Eigen::ComputeFullV);
  const double s_min = svd0.singularValues()[1];
  const double s1 = std::sin(degToRad(options.singular_blend_deg));
  const double x = s_min / s1;
  const double lambda = x < 1.0 ? s1 * (1.0 - x * x) * (1.0 - x * x) : 0.0;
  const Eigen::Vector2d v_weak = svd0.matrixV().col(1);

  // min |t(q) - t0|^2 + lambda^2 (v_weak . dq)^2 over dq = q - q_nominal (rad) by the shared
  // engine: the damping is one more residual row. Converged on the angle update itself (the
  // cost does not vanish where the damped axis leaves a direction error).
  const Eigen::RowVector2d damping_row = lambda * v_weak.transpose();
  auto poseAt = [&](const Eigen::VectorXd& dq) {
    Pose q = nominal_pose;
    q.*axes[0] += radToDeg(dq[0]);
    q.*axes[1] += radToDeg(dq[1]);
    return q;
  };
  const ResidualFunction residuals = [&](const Eigen::VectorXd& dq, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    const Pose q = poseAt(dq);
    r.resize(4);
    r.head<3>() = toolInWorkpiece(errors, q, k) - t0;
    r[3] = damping_row.dot(dq.head<2>());
    if (J) {
      J->resize(4, 2);
      J->topRows<3>() = J_t_q(errors, q, k);
      J->row(3) = damping_row;
    }
  };
  LeastSquaresOptions solver;
  solver.max_iterations = options.max_iterations;
  solver.function_tolerance = 0.0;
  solver.step_tolerance = std::numeric_limits<double>::min();
  solver.converged = [&](const Eigen::VectorXd& before, const Eigen::VectorXd& after) {
    return (after - before).cwiseAbs().maxCoeff() < options.step_tolerance_rad;
  };
  const LeastSquaresResult solved = solveLeastSquares(residuals, Eigen::Vector2d::Zero(), solver);

  CompensatedCommand out;
  out.pose = poseAt(solved.x);
  out.iterations = solved.summary.iterations;
  out.direction_residual_rad = toolDirectionError(errors, out.pose, nominal_pose, k);
  return out;
}

Eigen::Vector3d compensatedPosition(const GeometricErrors& errors, const Pose& nominal_pose,
                                    const Eigen::Vector3d& x_nominal, const Pose& commanded_pose) {
  const Eigen::Vector3d p_w = T_m_w_nominal(errors.kinematics(), nominal_pose).inverse() * x_nominal;
  return T_m_w(errors, commanded_pose) * p_w;
}

double pieceDeviation(const GeometricErrors& errors, const MachineCommand& from, const MachineCommand& to, double s0,
                      double s1, const MachineCommand& c0, const MachineCommand& c1, int samples) {
  double worst = 0.0;
  for (int i = 1; i <= samples; ++i) {
    const double sigma = static_cast<double>(i) / static_cast<double>(samples + 1);
    const MachineCommand nominal = lerp(from, to, s0 + sigma * (s1 - s0));
    const MachineCommand actual = lerp(c0, c1, sigma);
    const Eigen::Vector3d p_nominal = T_m_w_nominal(errors.kinematics(), nominal.pose).inverse() * nominal.x_m_mm;
    const Eigen::Vector3d p_actual = T_m_w(errors, actual.pose).inverse() * actual.x_m_mm;
    worst = std::max(worst, (p_actual - p_nominal).norm());
  }
  return worst;
}

CompensatedMove compensateMove(const GeometricErrors& errors, const MachineCommand& from, const MachineCommand& to,
                               const CompensationOptions& options, const SubdivisionOptions& subdivision,
                               const PoseRounding& rounding) {
  requireValid(options, "CompensationOptions");
  requireValid(subdivision, "SubdivisionOptions");
  auto endAt = [&](double s, double* residual) {
    const MachineCommand nominal = lerp(from, to, s);
    const CompensatedCommand cc = compensatePose(errors, nominal.pose, options);
    const Pose q = rounding ? rounding(cc.pose) : cc.pose;
    if (residual) *residual = toolDirectionError(errors, q, nominal.pose, options.tool_axis_m);
    return MachineCommand{compensatedPosition(errors, nominal.pose, nominal.x_m_mm, q), q};
  };
  const MachineCommand c_from = endAt(0.0, nullptr);
  double residual_to = 0.0;
  const MachineCommand c_to = endAt(1.0, &residual_to);
  auto evaluate = [&](int n, CompensatedMove* move) {
    CompensatedMove m;
    MachineCommand previous = c_from;
    for (int i = 1; i <= n; ++i) {
      const double s0 = static_cast<double>(i - 1) / n, s1 = static_cast<double>(i) / n;
      double residual = residual_to;
      const MachineCommand end = i == n ? c_to : endAt(s1, &residual);
      m.max_deviation_mm = std::max(
          m.max_deviation_mm, pieceDeviation(errors, from, to, s0, s1, previous, end, subdivision.samples_per_piece));
      m.s.push_back(s1);
      m.ends.push_back(end);
      m.direction_residual_rad.push_back(residual);
      previous = end;
    }
    *move = std::move(m);
    return move->max_deviation_mm <= subdivision.max_deviation_mm;
  };
  CompensatedMove move;
  if (evaluate(1, &move)) {
    move.unsplit_deviation_mm = move.max_deviation_mm;
    return move;
  }
  const double unsplit = move.max_deviation_mm;
  // The deviation of a piece falls as the square of its length: start from that guess, then
  // add pieces until every one is within the tolerance.
  int n = std::max(2, static_cast<int>(std::ceil(std::sqrt(unsplit / subdivision.max_deviation_mm))));
  while (n <= subdivision.max_pieces) {
    if (evaluate(n, &move)) {
      move.unsplit_deviation_mm = unsplit;
      return move;
    }
    ++n;
  }
  throw std::runtime_error(fmt::format("the move needs more than {} pieces to stay within {:.3f} um of the nominal path "
                                       "(one piece leaves {:.3f} um)",
                                       subdivision.max_pieces, mmToUm(subdivision.max_deviation_mm), mmToUm(unsplit)));
}

}  // namespace rotacal
