#pragma once
// Five-axis kinematics with the ISO 230-7 location errors of both rotary axes: the
// model the one-sphere cycle identifies, for any of the six configurations
//   table_ac    A tilting table carrying a C table            (000's machine)
//   table_bc    B tilting table carrying a C table            (002's machine)
//   table_ab    B axis on the bed carrying an A table          (LinuxCNC's xyzab_tdr_kins)
//   head_table  a B (or A) spindle head over a C table        (the most common shop machine)
//   head_ab     an A head carrying a B head, fixed table      (004's machine)
//   head_cb     a C head carrying a B head, fixed table        (LinuxCNC's 5axiskins bridge mill)
// Every rotary axis k carries, in the frame of the axis it rides on (the machine for the first),
//   T_perp1 T_perp2 R_perp1 R_perp2 R_k(zero) R_k(-+theta_k)
// e.g. the C axis: Dx(X0C) Dy(Y0C) Da(A0C) Db(B0C) Dc(C0C) Dc(-C). Table axes turn by -theta
// and head axes by +theta (ISO 841: the same relative motion of tool and workpiece). The outer
// axis's errors are relative to the inner axis at zero pose, as 000's dy_CA and b_CA are.
// Beyond the axes: the sphere's position on the table (set-up: dX_S dY_S dZ_S from the nominal)
// and, where a head carries the tool, the pivot-to-ball length and the ball's offset from the
// spindle axis (dL, dX_T, dY_T).
//
// The observable is what a probe reads on a sphere: the linear-axis position X at which the
// probe-ball centre is at the sphere centre,
//   X(theta) = T_m_w(theta) (p_S + d_S) - T_c_t(theta) 0,
// T_m_w the table chain, T_c_t the head chain from the carriage to the ball centre. The machine
// frame's origin is the nominal intersection of the rotary axes (docs/conventions.md) and, for
// a head, the nominal pivot at zero carriage position. Exact HTM products; nothing small-angle.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <string_view>
#include <vector>

#include "core/error_model.hpp"
#include "core/transforms.hpp"

namespace rotacal {

/// One parameter of a kinematic model: its symbol (ISO 230-7 for an axis's location error),
/// its kind and what it is.
struct ModelParameter {
  std::string name;
  ParamKind kind;
  std::string description;
};

/// A factor of a chain: an elementary motion whose value is a parameter (index into
/// KinematicModel::parameters) or a rotary axis's commanded angle with its sign.
struct ModelFactor {
  Motion motion;
  int parameter = -1;  // >= 0: value = parameters[parameter]
  char axis = 0;       // 'A', 'B', 'C' when parameter < 0
  double sign = 1.0;   // the value is sign x (parameter or angle)
};

struct KinematicModel {
  std::string name;              // table_ac, table_bc, table_ab, head_table, head_ab, head_cb
  std::vector<char> table_axes;  // from the bed outwards (A then C for table_ac, B then A for table_ab)
  std::vector<char> head_axes;   // from the carriage outwards (A then B for head_ab, C then B for head_cb)
  std::vector<ModelParameter> parameters;
  std::vector<ModelFactor> table_chain;  // machine -> workpiece, ends with the sphere's set-up
  std::vector<ModelFactor> head_chain;   // carriage -> probe-ball centre
  Eigen::Vector3d sphere_mm = Eigen::Vector3d::Zero();  // p_S: nominal sphere centre on the table, workpiece frame
  double pivot_to_ball_mm = 0.0;  // L: nominal, head kinematics only (the ball at -L along the spindle from the pivot)

  int parameterIndex(std::string_view name) const;  // -1 when unknown
  int size() const { return static_cast<int>(parameters.size()); }
};

/// The model of a configuration. head_axis selects the head of head_table ('B' or 'A'); the
/// others ignore it. Throws std::invalid_argument naming the configuration or the axis.
KinematicModel kinematicModel(std::string_view configuration, const Eigen::Vector3d& sphere_mm,
                              double pivot_to_ball_mm = 0.0, char head_axis = 'B');
/// The configurations kinematicModel() accepts, in the order the docs list them.
const std::vector<std::string>& kinematicConfigurations();

/// Exact chains: the workpiece frame in the machine frame (ending at the sphere's set-up) and the
/// probe-ball frame in the carriage frame. p: the model's parameters (mm, rad).
Eigen::Isometry3d T_m_w(const KinematicModel& model, const Eigen::VectorXd& p, const Pose& pose);
Eigen::Isometry3d T_c_t(const KinematicModel& model, const Eigen::VectorXd& p, const Pose& pose);

/// X: the linear-axis position at which the probe-ball centre is at the sphere centre (mm).
Eigen::Vector3d sphereCentreInAxes(const KinematicModel& model, const Eigen::VectorXd& p, const Pose& pose);

/// J_X_p: the exact derivative of sphereCentreInAxes with respect to the parameters (mm/mm, mm/rad).
Eigen::Matrix<double, 3, Eigen::Dynamic> J_X_p(const KinematicModel& model, const Eigen::VectorXd& p, const Pose& pose);

}  // namespace rotacal
