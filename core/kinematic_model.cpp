#include "core/kinematic_model.hpp"

#include <stdexcept>

#include "core/units.hpp"

namespace rotacal {

namespace {

using M = Motion;

struct AxisGeometry {
  Motion own;
  Motion perp_t[2];
  Motion perp_r[2];
  char perp_names[2];  // ISO 230-7: the axis letters of the perpendicular directions
};

AxisGeometry axisGeometry(char axis) {
  switch (axis) {
    case 'A': return {M::Rx, {M::Ty, M::Tz}, {M::Ry, M::Rz}, {'Y', 'Z'}};
    case 'B': return {M::Ry, {M::Tx, M::Tz}, {M::Rx, M::Rz}, {'X', 'Z'}};
    case 'C': return {M::Rz, {M::Tx, M::Ty}, {M::Rx, M::Ry}, {'X', 'Y'}};
    default: break;
  }
  throw std::invalid_argument(std::string("no rotary axis '") + axis + "' (expected A, B or C)");
}

char rotationLetter(char linear) { return linear == 'X' ? 'A' : (linear == 'Y' ? 'B' : 'C'); }

int addParameter(KinematicModel& m, std::string name, ParamKind kind, std::string description) {
  m.parameters.push_back({std::move(name), kind, std::move(description)});
  return m.size() - 1;
}

// The five ISO 230-7 location errors of one axis, then the axis's own motion.
void addAxis(KinematicModel& m, std::vector<ModelFactor>& chain, char axis, double sign, const char* carrier) {
  const AxisGeometry g = axisGeometry(axis);
  const std::string a(1, axis);
  for (int k = 0; k < 2; ++k) {
    const std::string name = std::string(1, g.perp_names[k]) + "0" + a;
    chain.push_back({g.perp_t[k], addParameter(m, name, ParamKind::Length,
                                               "position of the " + a + " axis in " + g.perp_names[k] + " (relative to " +
                                                   carrier + ")"),
                     0, 1.0});
  }
  for (int k = 0; k < 2; ++k) {
    const std::string name = std::string(1, rotationLetter(g.perp_names[k])) + "0" + a;
    chain.push_back({g.perp_r[k], addParameter(m, name, ParamKind::Angle,
                                               "orientation of the " + a + " axis about " + g.perp_names[k] +
                                                   " (relative to " + carrier + ")"),
                     0, 1.0});
  }
  chain.push_back({g.own, addParameter(m, a + "0" + a, ParamKind::Angle, "zero position of the " + a + " axis"), 0, 1.0});
  chain.push_back({g.own, -1, axis, sign});
}

double factorValue(const ModelFactor& f, const Eigen::VectorXd& p, const Pose& pose) {
  if (f.parameter >= 0) return f.sign * p[f.parameter];
  const double deg = pose.angle(f.axis);
  return f.sign * degToRad(deg);
}

Eigen::Isometry3d chainProduct(const std::vector<ModelFactor>& chain, const Eigen::VectorXd& p, const Pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (const auto& f : chain) T = T * elementary(f.motion, factorValue(f, p, pose));
  return T;
}

// Adds sign * d(T_chain point)/dp to J.
void addChainDerivative(const std::vector<ModelFactor>& chain, const Eigen::VectorXd& p, const Pose& pose,
                        const Eigen::Vector3d& point, double sign, Eigen::Matrix<double, 3, Eigen::Dynamic>& J) {
  std::vector<ChainFactorValue> values;
  for (const auto& f : chain) values.push_back({f.motion, factorValue(f, p, pose)});
  const auto D = chainPointDerivatives(values, point);
  for (size_t i = 0; i < chain.size(); ++i)
    if (chain[i].parameter >= 0) J.col(chain[i].parameter) += sign * chain[i].sign * D.col(static_cast<Eigen::Index>(i));
}

Eigen::Vector3d ballInTool(const KinematicModel& m) { return {0.0, 0.0, -m.pivot_to_ball_mm}; }

}  // namespace

const std::vector<std::string>& kinematicConfigurations() {
  static const std::vector<std::string> names = {"table_ac", "table_bc", "table_ab", "head_table", "head_ab", "head_cb"};
  return names;
}

int KinematicModel::parameterIndex(std::string_view n) const {
  for (size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].name == n) return static_cast<int>(i);
  return -1;
}

KinematicModel kinematicModel(std::string_view configuration, const Eigen::Vector3d& sphere_mm, double pivot_to_ball_mm,
                              char head_axis) {
  KinematicModel m;
  m.name = std::string(configuration);
  m.sphere_mm = sphere_mm;
  if (configuration == "table_ac") {
    m.table_axes = {'A', 'C'};
  } else if (configuration == "table_bc") {
    m.table_axes = {'B', 'C'};
  } else if (configuration == "table_ab") {
    m.table_axes = {'B', 'A'};
  } else if (configuration == "head_table") {
    if (head_axis != 'A' && head_axis != 'B')
      throw std::invalid_argument(std::string("head_table: the head axis must be A or B, not '") + head_axis + "'");
    m.head_axes = {head_axis};
    m.table_axes = {'C'};
  } else if (configuration == "head_ab") {
    m.head_axes = {'A', 'B'};
  } else if (configuration == "head_cb") {
    // The C head turns about the carriage's Z and carries the B head, whose Y turns with it.
    m.head_axes = {'C', 'B'};
  } else {
    throw std::invalid_argument("unknown kinematics '" + std::string(configuration) +
                                "' (expected table_ac, table_bc, table_ab, head_table, head_ab or head_cb)");
  }
  if (!m.head_axes.empty() && !(pivot_to_ball_mm > 0))
    throw std::invalid_argument(m.name + ": the pivot-to-ball length must be > 0 mm for a spindle head");
  m.pivot_to_ball_mm = m.head_axes.empty() ? 0.0 : pivot_to_ball_mm;
  const char* carrier = "the machine";
  for (char a : m.table_axes) {
    addAxis(m, m.table_chain, a, -1.0, carrier);
    carrier = a == 'A' ? "the A axis" : (a == 'B' ? "the B axis" : "the C axis");
  }
  const char* xyz[3] = {"X", "Y", "Z"};
  const M t[3] = {M::Tx, M::Ty, M::Tz};
  for (int k = 0; k < 3; ++k)
    m.table_chain.push_back({t[k], addParameter(m, std::string("d") + xyz[k] + "_S", ParamKind::Length,
                                                std::string("the sphere's set-up: its centre's offset in ") + xyz[k] +
                                                    " from the nominal, on the table"),
                             0, 1.0});
  carrier = "the carriage";
  for (char a : m.head_axes) {
    addAxis(m, m.head_chain, a, 1.0, carrier);
    carrier = a == 'A' ? "the A axis" : (a == 'B' ? "the B axis" : "the C axis");
  }
  if (!m.head_axes.empty()) {
    m.head_chain.push_back({M::Tx, addParameter(m, "dX_T", ParamKind::Length, "the ball centre's offset from the spindle axis in X"), 0, 1.0});
    m.head_chain.push_back({M::Ty, addParameter(m, "dY_T", ParamKind::Length, "the ball centre's offset from the spindle axis in Y"), 0, 1.0});
    // dL > 0: the ball is farther from the pivot than nominal (Tz(-dL) before the -L offset).
    m.head_chain.push_back({M::Tz, addParameter(m, "dL", ParamKind::Length, "the pivot-to-ball length's deviation"), 0, -1.0});
  }
  return m;
}

Eigen::Isometry3d T_m_w(const KinematicModel& m, const Eigen::VectorXd& p, const Pose& pose) {
  return chainProduct(m.table_chain, p, pose);
}

Eigen::Isometry3d T_c_t(const KinematicModel& m, const Eigen::VectorXd& p, const Pose& pose) {
  return chainProduct(m.head_chain, p, pose);
}

Eigen::Vector3d sphereCentreInAxes(const KinematicModel& m, const Eigen::VectorXd& p, const Pose& pose) {
  return T_m_w(m, p, pose) * m.sphere_mm - T_c_t(m, p, pose) * ballInTool(m);
}

Eigen::Matrix<double, 3, Eigen::Dynamic> J_X_p(const KinematicModel& m, const Eigen::VectorXd& p, const Pose& pose) {
  Eigen::Matrix<double, 3, Eigen::Dynamic> J = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, m.size());
  addChainDerivative(m.table_chain, p, pose, m.sphere_mm, 1.0, J);
  addChainDerivative(m.head_chain, p, pose, ballInTool(m), -1.0, J);
  return J;
}

}  // namespace rotacal
