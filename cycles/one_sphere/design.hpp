#pragma once
// The one-sphere cycle's measurement equation and its pose design.
//
// One touch, ball centre read at t (machine frame) at pose q:
//   r = |t + E_S(t) - X(p, q)| - (R + r_ball + dR),
//   E_S(t) = (S_xy t_y + S_xz t_z, S_yz t_z, 0)            (000 Eq. (23), core/linear_axes.hpp)
// X the sphere centre of the five-axis model (core/kinematic_model.hpp). The linear axes'
// squareness is fitted alongside when the layout asks (option fit_squareness, default on): a
// shear of the linear axes reads as a tilt of the rotary axes wherever the sphere's positions do
// not span it, and 000 Table 5's squareness is the largest contributor to the angles otherwise
// (S_yz 0.83 of a_AY's 0.99 mdeg on the bundled A/C machine). Only its symmetric part is seen:
// the antisymmetric part is a rotation of the whole machine, which the location errors carry.
//
// The pose design picks n poses of a candidate grid for the largest determinant of the fit's
// information (D-optimal, core/pose_design.hpp), from the touches each pose gets, every touch
// weighted alike (the probe's repeatability): what a plan with option `poses` does.
#include <Eigen/Core>
#include <array>
#include <vector>

#include "core/identifiability.hpp"
#include "core/kinematic_model.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

/// The fit's parameters: the model's, then dR, then S_xy S_xz S_yz when squareness is fitted.
std::vector<IdentifiabilityParameter> sphereFitParameters(const KinematicModel& m, bool squareness);

/// One touch's residual and (when row is not null) its row of J_r_x, for x laid out as
/// sphereFitParameters. rho = R + r_ball (mm).
double sphereTouchResidual(const KinematicModel& m, bool squareness, const Eigen::VectorXd& x, const Pose& pose,
                           const Eigen::Vector3d& t_m_mm, double rho, Eigen::RowVectorXd* row);

/// The fit's lost-motion terms (option backlash, core/rotary_backlash.hpp): each rotary axis
/// the plan moves stops d b / 2 short of its command, d the way it last moved, b its lost motion
/// (rad, at x[lost_motion[k]]); the touches the plan reaches before it has moved an axis come
/// from wherever the machine stood, so that axis's offset there is a parameter of its own
/// (rad, at x[lead_in[k]]). k = 0, 1, 2 for A, B, C; -1: no such term.
struct SphereBacklashTerms {
  std::array<Eigen::Index, 3> lost_motion{{-1, -1, -1}};
  std::array<Eigen::Index, 3> lead_in{{-1, -1, -1}};
};

/// The terms the plan's order of touches (directions per point, rotaryApproachDirections with
/// from_start = false) supports, appended to `names` as backlash_A .. and lead_in_A .. (angles).
SphereBacklashTerms appendBacklashParameters(const MachineModel& machine, const std::vector<Eigen::Vector3d>& directions,
                                             std::vector<IdentifiabilityParameter>* names);

/// The commanded pose moved as the terms say for a touch reached in `direction`.
Pose backlashPose(const SphereBacklashTerms& terms, const Eigen::VectorXd& x, const Pose& commanded,
                  const Eigen::Vector3d& direction);

/// sphereTouchResidual at the pose the axes really reach, with the lost-motion terms' columns
/// of the row (the residual's slope in each rotary angle by central differences: 1e-4 deg
/// leaves a truncation error below 1e-12 of it on these smooth models).
double sphereTouchResidual(const KinematicModel& m, bool squareness, const SphereBacklashTerms& terms,
                           const Eigen::VectorXd& x, const Pose& pose, const Eigen::Vector3d& direction,
                           const Eigen::Vector3d& t_m_mm, double rho, Eigen::RowVectorXd* row);

/// The contact normal of that touch (from the fitted centre to the corrected trigger).
Eigen::Vector3d sphereTouchNormal(const KinematicModel& m, bool squareness, const Eigen::VectorXd& x, const Pose& pose,
                                  const Eigen::Vector3d& t_m_mm);

}  // namespace rotacal
