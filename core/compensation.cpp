#include "core/compensation.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/units.hpp"

namespace rotacal {

void CompensationOptions::validate() const {
  if (!(std::abs(tool_axis_m.norm() - 1.0) < 1e-9))
    throw std::invalid_argument("CompensationOptions: tool_axis_m must be a unit vector");
  if (max_iterations < 1) throw std::invalid_argument("CompensationOptions: max_iterations must be >= 1");
  if (!(step_tolerance_rad > 0)) throw std::invalid_argument("CompensationOptions: step_tolerance_rad must be > 0");
  if (!(singular_blend_deg > 0 && singular_blend_deg < 45))
    throw std::invalid_argument("CompensationOptions: singular_blend_deg must be in (0, 45) deg");
}

void SubdivisionOptions::validate() const {
  if (!(max_deviation_mm > 0)) throw std::invalid_argument("SubdivisionOptions: max_deviation_mm must be > 0");
  if (samples_per_piece < 1) throw std::invalid_argument("SubdivisionOptions: samples_per_piece must be >= 1");
  if (max_pieces < 1) throw std::invalid_argument("SubdivisionOptions: max_pieces must be >= 1");
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
  options.validate();
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
  const Eigen::Matrix2d D = lambda * lambda * v_weak * v_weak.transpose();

  CompensatedCommand out;
  out.pose = nominal_pose;
  // Gauss-Newton on min |t(q) - t0|^2 + lambda^2 (v_weak . (q - q_nominal))^2, q in rad.
  for (int it = 0; it < options.max_iterations; ++it) {
    const Eigen::Vector3d r = toolInWorkpiece(errors, out.pose, k) - t0;
    const Eigen::Matrix<double, 3, 2> J = J_t_q(errors, out.pose, k);
    const Eigen::Vector2d dq(degToRad(out.pose.*axes[0] - nominal_pose.*axes[0]),
                             degToRad(out.pose.*axes[1] - nominal_pose.*axes[1]));
    const Eigen::Matrix2d N = J.transpose() * J + D;
    const Eigen::Vector2d g = J.transpose() * r + D * dq;
    // Exactly at a singular pose without damping (a blend of 0 is refused, so only through
    // a degenerate J of the errors themselves) the pseudo-inverse keeps the step minimal.
    const Eigen::Vector2d step = N.completeOrthogonalDecomposition().solve(g);
    out.pose.*axes[0] -= radToDeg(step[0]);
    out.pose.*axes[1] -= radToDeg(step[1]);
    out.iterations = it + 1;
    if (step.cwiseAbs().maxCoeff() < options.step_tolerance_rad) break;
  }
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
  options.validate();
  subdivision.validate();
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
