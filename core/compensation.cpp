#include "core/compensation.hpp"

#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/units.hpp"

namespace rotacal {

void CompensationOptions::validate() const {
  if (!(std::abs(tool_axis_m.norm() - 1.0) < 1e-9))
    throw std::invalid_argument("CompensationOptions: tool_axis_m must be a unit vector");
  if (max_iterations < 1) throw std::invalid_argument("CompensationOptions: max_iterations must be >= 1");
  if (!(step_tolerance_rad > 0)) throw std::invalid_argument("CompensationOptions: step_tolerance_rad must be > 0");
  if (!(max_rotary_change_deg > 0))
    throw std::invalid_argument("CompensationOptions: max_rotary_change_deg must be > 0");
}

namespace {

// The two rotary axes a kinematics moves, as pointers into Pose.
std::array<double Pose::*, 2> rotaryMembers(Kinematics k) {
  if (k == Kinematics::TableAC) return {&Pose::A, &Pose::C};
  return {&Pose::B, &Pose::C};
}

// Tool direction in the workpiece frame: R_m_w^T k.
Eigen::Vector3d toolInWorkpiece(const LocationErrors& e, const Pose& q, const Eigen::Vector3d& k) {
  return T_m_w(e, q).linear().transpose() * k;
}

}  // namespace

double toolDirectionError(const LocationErrors& errors, const Pose& pose, const Pose& nominal_pose,
                          const Eigen::Vector3d& k) {
  LocationErrors nominal;
  nominal.kinematics = errors.kinematics;
  const Eigen::Vector3d t = toolInWorkpiece(errors, pose, k);
  const Eigen::Vector3d t0 = toolInWorkpiece(nominal, nominal_pose, k);
  return std::atan2(t.cross(t0).norm(), t.dot(t0));
}

CompensatedCommand compensatePose(const LocationErrors& errors, const Pose& nominal_pose,
                                  const CompensationOptions& options) {
  options.validate();
  LocationErrors nominal;
  nominal.kinematics = errors.kinematics;
  const Eigen::Vector3d& k = options.tool_axis_m;
  const Eigen::Vector3d t0 = toolInWorkpiece(nominal, nominal_pose, k);
  const auto axes = rotaryMembers(errors.kinematics);
  CompensatedCommand out;
  out.pose = nominal_pose;
  // Gauss-Newton on r(q) = t(q) - t0 with a central-difference Jacobian J_r_q (3 x 2, per deg).
  // Near a pose where one axis is parallel to the tool J loses rank: the pseudo-inverse with a
  // relative cut gives the minimum-norm step, which leaves that axis where it was.
  const double h_deg = 1e-4;
  for (int it = 0; it < options.max_iterations; ++it) {
    const Eigen::Vector3d r = toolInWorkpiece(errors, out.pose, k) - t0;
    Eigen::Matrix<double, 3, 2> J_r_q;
    for (int j = 0; j < 2; ++j) {
      Pose plus = out.pose, minus = out.pose;
      plus.*axes[j] += h_deg;
      minus.*axes[j] -= h_deg;
      J_r_q.col(j) = (toolInWorkpiece(errors, plus, k) - toolInWorkpiece(errors, minus, k)) / (2 * h_deg);
    }
    Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd(J_r_q, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector2d s = svd.singularValues();
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    const Eigen::Vector3d ut_r = svd.matrixU().transpose() * r;
    for (int j = 0; j < 2; ++j) {
      if (!(s[j] > 1e-12)) continue;
      const double c = ut_r[j] / s[j];
      if (std::abs(c) > options.max_rotary_change_deg) continue;  // near-singular: leave this tilt
      step += svd.matrixV().col(j) * c;
    }
    out.pose.*axes[0] -= step[0];
    out.pose.*axes[1] -= step[1];
    out.iterations = it + 1;
    if (degToRad(step.cwiseAbs().maxCoeff()) < options.step_tolerance_rad) break;
  }
  for (double Pose::*axis : axes)
    if (std::abs(out.pose.*axis - nominal_pose.*axis) > options.max_rotary_change_deg) out.pose.*axis = nominal_pose.*axis;
  out.direction_residual_rad = toolDirectionError(errors, out.pose, nominal_pose, k);
  return out;
}

Eigen::Vector3d compensatedPosition(const LocationErrors& errors, const Pose& nominal_pose,
                                    const Eigen::Vector3d& x_nominal, const Pose& commanded_pose) {
  const Eigen::Vector3d p_w = T_m_w_nominal(errors.kinematics, nominal_pose).inverse() * x_nominal;
  return T_m_w(errors, commanded_pose) * p_w;
}

}  // namespace rotacal
