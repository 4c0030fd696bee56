#pragma once
// Location errors of the rotary axes and the exact table kinematics that carries them.
//  A/C tilting table, 000 Eq. (1):
//    T_m_w = Dx(dx_AY) Dy(dy_AY) Dz(dz_AY) Da(a_AY) Db(b_AY) Dc(c_AY) Da(-A)
//            Dy(dy_CA) Db(b_CA) Dc(-C)                        (a_CA, c_CA are redundant, omitted)
//  B/C tilting table, 002 Eq. (2)-(3) with constant errors:
//    T_m_w = Da(a_BY) Db(b_BY) Dc(c_BY) Dx(dx_BY) Dy(dy_CB) Dz(dz_BY) Db(-B)
//            Da(a_CB) Dx(dx_CB) Dc(-C)
//  A/B dual rotary table (LinuxCNC's xyzab_tdr_kins: a B axis on the bed about Y carrying an A
//  table about X), rotacal's chain in 002's style, B's errors relative to the bed, A's to B:
//    T_m_w = Da(a_BY) Db(b_BY) Dc(c_BY) Dx(dx_BY) Dy(dy_AB) Dz(dz_BY) Db(-B)
//            Dz(dz_AB) Dc(c_AB) Da(-A)                       (B0A-B0B is B's zero, A0A the set-up's)
// T_m_w maps a point fixed on the table (workpiece frame) to the machine frame, whose origin is
// the nominal intersection of the rotary axes. Angles A, B, C are the commanded angles in the
// papers' sign convention (a controller may count the other way: see MachineModel).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <string_view>
#include <vector>

#include "core/transforms.hpp"

namespace rotacal {

// HeadAB: a spindle head tilting in A and B about a pivot, the tool tip at distance R from it
// (004 Sec. IV); it has no table location errors and serves the fixed-tool-tip cycle (004).
// HeadTable: a B (or A) spindle head over a C table (MachineModel::head). Its location errors are
// the ISO 230-7 parameters of core/kinematic_model.hpp, not the papers' eight: the tables and
// offsets of the papers' machines do not apply to it. The table turns C only.
// TableAB: the A/B dual rotary table above; the B axis (the tilt) sits on the bed, the A table
// rides on it, as LinuxCNC's xyzab_tdr_kins has them (docs/conventions.md).
// HeadCB: a C head on the Z carriage carrying a B head that tilts the spindle, over a fixed table
// (the bridge mill of LinuxCNC's 5axiskins). Like head_table, its location errors are the ISO
// 230-7 parameters of core/kinematic_model.hpp; it needs MACHINE.json's "head" (the pivot length).
enum class Kinematics { TableAC, TableBC, HeadAB, HeadTable, TableAB, HeadCB };

std::string_view kinematicsName(Kinematics kinematics);  // "table_ac", "table_bc", "head_ab", "head_table", "table_ab", "head_cb"
/// Whether the machine's XYZ carry a spindle head (its XYZ are the pivot's, not the ball centre's).
inline bool hasSpindleHead(Kinematics k) {
  return k == Kinematics::HeadAB || k == Kinematics::HeadTable || k == Kinematics::HeadCB;
}
/// Whether both rotary axes are in the head and the table stays (head_ab, head_cb).
inline bool hasFixedTable(Kinematics k) { return k == Kinematics::HeadAB || k == Kinematics::HeadCB; }
/// Whether the papers' eight table location errors (000 / 002) describe the machine.
/// (table_ab's eight are rotacal's, written in the papers' style: the chain above.)
inline bool hasPapersLocationErrors(Kinematics k) {
  return k == Kinematics::TableAC || k == Kinematics::TableBC || k == Kinematics::TableAB;
}
/// The tilting axis of a table machine, on the bed ('A', else 'B'), and the axis it carries
/// ('C', or 'A' on the A/B table).
inline char tableTiltAxis(Kinematics k) { return k == Kinematics::TableAC ? 'A' : 'B'; }
inline char tableTurnAxis(Kinematics k) { return k == Kinematics::TableAB ? 'A' : 'C'; }
Kinematics kinematicsFromName(std::string_view name);         // throws std::invalid_argument

enum class ParamKind { Length, Angle };

/// What one error parameter is: the papers' symbol in ASCII, its ISO 230-7 name, its kind.
struct ParameterInfo {
  std::string_view name;
  std::string_view iso;
  ParamKind kind;
  std::string_view description;
};

constexpr int kNumLocationErrors = 8;
using ErrorVector = Eigen::Matrix<double, kNumLocationErrors, 1>;

/// The eight location errors of a kinematics, in order, 000 Table 1 / 002 Table 2 (table_ab: the
/// B/C table's B-axis five at the same places, then A's place and squareness relative to B).
const std::vector<ParameterInfo>& locationParameters(Kinematics kinematics);
int parameterIndex(Kinematics kinematics, std::string_view name);  // -1 when unknown

/// One identified parameter of a kinematic model (core/kinematic_model.hpp) by its ISO 230-7
/// name: what a head machine's offsets are written from, having none of the papers' eight.
struct ParameterEstimate {
  std::string name;
  ParamKind kind = ParamKind::Length;
  double value = 0.0;   // mm / rad
  double u = 0.0;       // standard uncertainty, mm / rad
  bool held = false;    // not separable by the plan: held at nominal (value 0), not identified
};

/// A commanded rotary pose in degrees, papers' convention. Unused axes stay 0.
struct Pose {
  double A = 0.0;
  double B = 0.0;
  double C = 0.0;
  /// The angle of rotary axis `axis` ('A', 'B', else C), deg.
  double angle(char axis) const { return axis == 'A' ? A : (axis == 'B' ? B : C); }
};

/// Location errors of one machine: lengths in mm, angles in rad, order of locationParameters().
struct LocationErrors {
  Kinematics kinematics = Kinematics::TableAC;
  ErrorVector values = ErrorVector::Zero();

  double get(std::string_view name) const;
  void set(std::string_view name, double value_mm_or_rad);
  /// Value in report units: um for lengths, mdeg for angles.
  double reportValue(int index) const;
  void setReportValue(int index, double um_or_mdeg);
};

/// Factor of the kinematic chain: a motion whose value is an error parameter or a commanded angle.
struct ChainFactor {
  Motion motion;
  enum class Source { Parameter, NegativeAxis } source;
  int index;  // parameter index, or axis (0 = A, 1 = B, 2 = C)
};
const std::vector<ChainFactor>& kinematicChain(Kinematics kinematics);

/// T_m_w: workpiece (table) frame in the machine frame, exact HTM product.
Eigen::Isometry3d T_m_w(const LocationErrors& errors, const Pose& pose);

/// Nominal T_m_w (all errors zero): a pure rotation.
Eigen::Isometry3d T_m_w_nominal(Kinematics kinematics, const Pose& pose);

/// J_pm_e: derivative of p_m = T_m_w p_w with respect to the eight location errors
/// (mm/mm and mm/rad), evaluated exactly at the given errors.
Eigen::Matrix<double, 3, kNumLocationErrors> J_pm_e(const LocationErrors& errors, const Pose& pose,
                                                    const Eigen::Vector3d& p_w);

/// Unit used in reports for a parameter kind: "um" or "mdeg".
std::string_view reportUnit(ParamKind kind);

}  // namespace rotacal
