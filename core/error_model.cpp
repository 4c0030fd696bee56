#include "core/error_model.hpp"

#include <stdexcept>

#include "core/units.hpp"

namespace rotacal {

namespace {
constexpr const char* kNoTableErrors =
    "a spindle-head machine (head_ab, head_table, head_cb) has none of the papers' table location errors: head_ab is "
    "calibrated at a fixed tool tip (004), head_table and head_cb by their own ISO 230-7 parameters "
    "(core/kinematic_model.hpp)";
}  // namespace

std::string_view kinematicsName(Kinematics kinematics) {
  if (kinematics == Kinematics::HeadAB) return "head_ab";
  if (kinematics == Kinematics::HeadTable) return "head_table";
  if (kinematics == Kinematics::TableAB) return "table_ab";
  if (kinematics == Kinematics::HeadCB) return "head_cb";
  return kinematics == Kinematics::TableAC ? "table_ac" : "table_bc";
}

Kinematics kinematicsFromName(std::string_view name) {
  if (name == "table_ac") return Kinematics::TableAC;
  if (name == "table_bc") return Kinematics::TableBC;
  if (name == "head_ab") return Kinematics::HeadAB;
  if (name == "head_table") return Kinematics::HeadTable;
  if (name == "table_ab") return Kinematics::TableAB;
  if (name == "head_cb") return Kinematics::HeadCB;
  throw std::invalid_argument("unknown kinematics '" + std::string(name) +
                              "' (expected table_ac, table_bc, table_ab, head_ab, head_table or head_cb)");
}

const std::vector<ParameterInfo>& locationParameters(Kinematics kinematics) {
  using K = ParamKind;
  static const std::vector<ParameterInfo> ac = {
      {"dx_AY", "X0A", K::Length, "linear offset of the A axis in X (C-axis centre in X at A = 0)"},
      {"dy_AY", "Y0A", K::Length, "linear offset of the A axis in Y"},
      {"dz_AY", "Z0A", K::Length, "linear offset of the A axis in Z"},
      {"dy_CA", "Y0C-Y0A", K::Length, "linear offset of the C axis from the A axis in Y"},
      {"a_AY", "A0A", K::Angle, "angular positioning error of the A axis at A = 0"},
      {"b_AY", "B0A", K::Angle, "squareness of the A axis to the Z axis"},
      {"c_AY", "C0A", K::Angle, "squareness of the A axis to the Y axis"},
      {"b_CA", "B0C-B0A", K::Angle, "squareness of the C axis to the A axis"},
  };
  static const std::vector<ParameterInfo> bc = {
      {"dx_BY", "X0B", K::Length, "location of the B axis in X"},
      {"dy_CB", "Y0C", K::Length, "location of the rotary table's (C) axis in Y"},
      {"dz_BY", "Z0B", K::Length, "location of the B axis in Z"},
      {"a_BY", "A0B", K::Angle, "orientation of the B axis around X"},
      {"b_BY", "B0B", K::Angle, "angular positioning error of the B axis"},
      {"c_BY", "C0B", K::Angle, "orientation of the B axis around Z"},
      {"a_CB", "A0C-A0B", K::Angle, "squareness of the C axis to the B axis around X (002: alpha_CB^0)"},
      {"dx_CB", "X0C-X0B", K::Length, "offset of the C axis from the B axis in X (002: dx_CB^0)"},
  };
  // The B axis's five keep the B/C table's names and places (both B axes sit on the bed), so a
  // name means one thing in every table family.
  static const std::vector<ParameterInfo> ab = {
      {"dx_BY", "X0B", K::Length, "location of the B axis in X"},
      {"dy_AB", "Y0A", K::Length, "location of the A table's axis in Y"},
      {"dz_BY", "Z0B", K::Length, "location of the B axis in Z"},
      {"a_BY", "A0B", K::Angle, "orientation of the B axis around X"},
      {"b_BY", "B0B", K::Angle, "angular positioning error of the B axis"},
      {"c_BY", "C0B", K::Angle, "orientation of the B axis around Z"},
      {"c_AB", "C0A-C0B", K::Angle, "squareness of the A axis to the B axis around Z"},
      {"dz_AB", "Z0A-Z0B", K::Length, "offset of the A axis from the B axis in Z"},
  };
  if (!hasPapersLocationErrors(kinematics)) throw std::invalid_argument(kNoTableErrors);
  if (kinematics == Kinematics::TableAB) return ab;
  return kinematics == Kinematics::TableAC ? ac : bc;
}

int parameterIndex(Kinematics kinematics, std::string_view name) {
  const auto& params = locationParameters(kinematics);
  for (size_t i = 0; i < params.size(); ++i)
    if (params[i].name == name) return static_cast<int>(i);
  return -1;
}

double LocationErrors::get(std::string_view name) const {
  const int i = parameterIndex(kinematics, name);
  if (i < 0) throw std::invalid_argument("unknown location error '" + std::string(name) + "'");
  return values[i];
}

void LocationErrors::set(std::string_view name, double value) {
  const int i = parameterIndex(kinematics, name);
  if (i < 0) throw std::invalid_argument("unknown location error '" + std::string(name) + "'");
  values[i] = value;
}

double LocationErrors::reportValue(int index) const {
  return locationParameters(kinematics)[index].kind == ParamKind::Length ? mmToUm(values[index])
                                                                          : radToMdeg(values[index]);
}

void LocationErrors::setReportValue(int index, double v) {
  values[index] =
      locationParameters(kinematics)[index].kind == ParamKind::Length ? umToMm(v) : mdegToRad(v);
}

std::string_view reportUnit(ParamKind kind) { return kind == ParamKind::Length ? "um" : "mdeg"; }

const std::vector<ChainFactor>& kinematicChain(Kinematics kinematics) {
  using S = ChainFactor::Source;
  using M = Motion;
  // 000 Eq. (1); parameter indices follow locationParameters(TableAC).
  static const std::vector<ChainFactor> ac = {
      {M::Tx, S::Parameter, 0}, {M::Ty, S::Parameter, 1}, {M::Tz, S::Parameter, 2},
      {M::Rx, S::Parameter, 4}, {M::Ry, S::Parameter, 5}, {M::Rz, S::Parameter, 6},
      {M::Rx, S::NegativeAxis, 0},
      {M::Ty, S::Parameter, 3}, {M::Ry, S::Parameter, 7},
      {M::Rz, S::NegativeAxis, 2},
  };
  // 002 Eq. (2); parameter indices follow locationParameters(TableBC).
  static const std::vector<ChainFactor> bc = {
      {M::Rx, S::Parameter, 3}, {M::Ry, S::Parameter, 4}, {M::Rz, S::Parameter, 5},
      {M::Tx, S::Parameter, 0}, {M::Ty, S::Parameter, 1}, {M::Tz, S::Parameter, 2},
      {M::Ry, S::NegativeAxis, 1},
      {M::Rx, S::Parameter, 6}, {M::Tx, S::Parameter, 7},
      {M::Rz, S::NegativeAxis, 2},
  };
  // The A/B table (error_model.hpp); parameter indices follow locationParameters(TableAB).
  static const std::vector<ChainFactor> ab = {
      {M::Rx, S::Parameter, 3}, {M::Ry, S::Parameter, 4}, {M::Rz, S::Parameter, 5},
      {M::Tx, S::Parameter, 0}, {M::Ty, S::Parameter, 1}, {M::Tz, S::Parameter, 2},
      {M::Ry, S::NegativeAxis, 1},
      {M::Tz, S::Parameter, 7}, {M::Rz, S::Parameter, 6},
      {M::Rx, S::NegativeAxis, 0},
  };
  if (!hasPapersLocationErrors(kinematics)) throw std::invalid_argument(kNoTableErrors);
  if (kinematics == Kinematics::TableAB) return ab;
  return kinematics == Kinematics::TableAC ? ac : bc;
}

namespace {

double factorValue(const ChainFactor& f, const LocationErrors& errors, const Pose& pose) {
  if (f.source == ChainFactor::Source::Parameter) return errors.values[f.index];
  const double deg = f.index == 0 ? pose.A : (f.index == 1 ? pose.B : pose.C);
  return -degToRad(deg);
}

}  // namespace

Eigen::Isometry3d T_m_w(const LocationErrors& errors, const Pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (const auto& f : kinematicChain(errors.kinematics))
    T = T * elementary(f.motion, factorValue(f, errors, pose));
  return T;
}

Eigen::Isometry3d T_m_w_nominal(Kinematics kinematics, const Pose& pose) {
  // A head over a C table: the table turns C alone (by -C, as every table axis does).
  if (kinematics == Kinematics::HeadTable) return elementary(Motion::Rz, -degToRad(pose.C));
  // Two head axes: the table does not move.
  if (hasFixedTable(kinematics)) return Eigen::Isometry3d::Identity();
  LocationErrors zero;
  zero.kinematics = kinematics;
  return T_m_w(zero, pose);
}

Eigen::Matrix<double, 3, kNumLocationErrors> J_pm_e(const LocationErrors& errors, const Pose& pose,
                                                    const Eigen::Vector3d& p_w) {
  const auto& chain = kinematicChain(errors.kinematics);
  std::vector<ChainFactorValue> values;
  for (const auto& f : chain) values.push_back({f.motion, factorValue(f, errors, pose)});
  const auto D = chainPointDerivatives(values, p_w);
  Eigen::Matrix<double, 3, kNumLocationErrors> J = Eigen::Matrix<double, 3, kNumLocationErrors>::Zero();
  for (size_t i = 0; i < chain.size(); ++i)
    if (chain[i].source == ChainFactor::Source::Parameter) J.col(chain[i].index) += D.col(static_cast<Eigen::Index>(i));
  return J;
}

}  // namespace rotacal
