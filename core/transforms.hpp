#pragma once
// Elementary homogeneous transforms of 000 Eq. (1): D_x, D_y, D_z translate; D_a, D_b, D_c rotate
// about X, Y, Z (right hand, angle in rad). All exact: no small-angle forms here.
#include <Eigen/Geometry>
#include <vector>

namespace rotacal {

/// One elementary motion of a kinematic chain.
enum class Motion { Tx, Ty, Tz, Rx, Ry, Rz };

Eigen::Isometry3d Dx(double x_mm);
Eigen::Isometry3d Dy(double y_mm);
Eigen::Isometry3d Dz(double z_mm);
Eigen::Isometry3d Da(double a_rad);
Eigen::Isometry3d Db(double b_rad);
Eigen::Isometry3d Dc(double c_rad);

/// D_motion(value): the elementary transform for a chain factor.
Eigen::Isometry3d elementary(Motion motion, double value);

/// Twist generator G of the motion: d/dv D(v) = D(v) * G (4x4, bottom row zero).
Eigen::Matrix4d generator(Motion motion);

bool isRotation(Motion motion);

/// The chain T = D_m0(v0) D_m1(v1) ... applied to the point p, and its derivative with respect
/// to each factor's value: column i = prefix_i G_i suffix_i p (exact, no small-angle form).
struct ChainFactorValue {
  Motion motion;
  double value;
};
Eigen::Matrix<double, 3, Eigen::Dynamic> chainPointDerivatives(const std::vector<ChainFactorValue>& chain,
                                                               const Eigen::Vector3d& p);

}  // namespace rotacal
