#pragma once
// The geometric errors of a machine's rotary axes as compensation needs them (ISO 230-7): the
// location errors of both axes (position-independent, core/error_model.hpp) and the component
// errors of an axis (position-dependent: EXC EYC EZC EAC EBC ECC for C, functions of its angle).
//
// Where the component errors enter the chain: a rotary axis's error motion moves what the axis
// carries, so T_E(q) = Dx(EX) Dy(EY) Dz(EZ) Da(EA) Db(EB) Dc(EC) is inserted right before that
// axis's rotation factor, after every location error of the axis:
//   A/C table: ... Da(-A) Dy(dy_CA) Db(b_CA) T_E(C) Dc(-C)
// which at A = 0 is the three-sphere cycle's model p = T_L T_E(C) Dc(-C) s (001 Table 1). At
// A != 0 the C axis's error motion tilts with the A axis, as the hardware does.
//
// The component errors are given at sampled angles over a full turn (what a cycle reports) and
// interpolated: by the trigonometric polynomial through equally spaced samples (it reproduces
// exactly a Fourier series with no more terms than samples, the form the sphere cycle
// identifies), else piecewise linearly over the turn.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/error_model.hpp"

namespace rotacal {

/// The six component errors of one rotary axis in ISO 230-7 order (EX, EY, EZ, EA, EB, EC of
/// that axis): lengths mm, angles rad.
constexpr int kNumComponentErrors = 6;
using ComponentVector = Eigen::Matrix<double, kNumComponentErrors, 1>;

/// ISO names of the component errors of an axis: "EXC", ..., "ECC" for axis 'C'.
std::array<std::string, kNumComponentErrors> componentErrorNames(char axis);

/// Component errors of one rotary axis, sampled over one turn.
struct ComponentErrors {
  char axis = 'C';
  std::vector<double> angle_deg;       // ascending, spanning less than one turn (papers' convention)
  std::vector<ComponentVector> values; // mm / rad at each angle
  std::vector<ComponentVector> u;      // standard uncertainty (k = 1) at each angle; empty if unknown

  /// False, and why (fewer than 3 angles, not ascending, more than a turn, sizes that differ, a
  /// value that is not finite), when the table cannot be used.
  bool validate(std::string* why) const;
  /// True when the angles are equally spaced over the full turn (trigonometric interpolation).
  bool equallySpaced() const;
  /// The component errors at any angle (deg).
  ComponentVector at(double angle_deg) const;
};

/// Location errors of the kinematics plus the component errors of some of its rotary axes.
struct GeometricErrors {
  LocationErrors location;
  std::vector<ComponentErrors> components;  // at most one per rotary axis
  /// Covariance of the location errors (mm, rad; order of locationParameters()), when the
  /// reports gave one.
  std::optional<Eigen::Matrix<double, kNumLocationErrors, kNumLocationErrors>> location_covariance;

  GeometricErrors() = default;
  GeometricErrors(const LocationErrors& l) : location(l) {}  // NOLINT: a location-only model

  Kinematics kinematics() const { return location.kinematics; }
  const ComponentErrors* componentsOf(char axis) const;
  /// False, and why: an axis the kinematics does not turn, two tables for one axis, a bad table.
  bool validate(std::string* why) const;
};

/// T_m_w of the machine with these errors: the location chain with each axis's T_E inserted
/// before its rotation (exact HTMs).
Eigen::Isometry3d T_m_w(const GeometricErrors& errors, const Pose& pose);

/// T_E(v) = Dx(v0) Dy(v1) Dz(v2) Da(v3) Db(v4) Dc(v5).
Eigen::Isometry3d componentTransform(const ComponentVector& v);

}  // namespace rotacal
