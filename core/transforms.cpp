#include "core/transforms.hpp"

#include <cmath>

namespace rotacal {

Eigen::Isometry3d Dx(double x_mm) { return Eigen::Isometry3d(Eigen::Translation3d(x_mm, 0, 0)); }
Eigen::Isometry3d Dy(double y_mm) { return Eigen::Isometry3d(Eigen::Translation3d(0, y_mm, 0)); }
Eigen::Isometry3d Dz(double z_mm) { return Eigen::Isometry3d(Eigen::Translation3d(0, 0, z_mm)); }
Eigen::Isometry3d Da(double a_rad) {
  return Eigen::Isometry3d(Eigen::AngleAxisd(a_rad, Eigen::Vector3d::UnitX()));
}
Eigen::Isometry3d Db(double b_rad) {
  return Eigen::Isometry3d(Eigen::AngleAxisd(b_rad, Eigen::Vector3d::UnitY()));
}
Eigen::Isometry3d Dc(double c_rad) {
  return Eigen::Isometry3d(Eigen::AngleAxisd(c_rad, Eigen::Vector3d::UnitZ()));
}

Eigen::Isometry3d elementary(Motion motion, double value) {
  switch (motion) {
    case Motion::Tx: return Dx(value);
    case Motion::Ty: return Dy(value);
    case Motion::Tz: return Dz(value);
    case Motion::Rx: return Da(value);
    case Motion::Ry: return Db(value);
    case Motion::Rz: return Dc(value);
  }
  return Eigen::Isometry3d::Identity();
}

Eigen::Matrix4d generator(Motion motion) {
  Eigen::Matrix4d g = Eigen::Matrix4d::Zero();
  switch (motion) {
    case Motion::Tx: g(0, 3) = 1; break;
    case Motion::Ty: g(1, 3) = 1; break;
    case Motion::Tz: g(2, 3) = 1; break;
    case Motion::Rx: g(2, 1) = 1; g(1, 2) = -1; break;
    case Motion::Ry: g(0, 2) = 1; g(2, 0) = -1; break;
    case Motion::Rz: g(1, 0) = 1; g(0, 1) = -1; break;
  }
  return g;
}

bool isRotation(Motion motion) {
  return motion == Motion::Rx || motion == Motion::Ry || motion == Motion::Rz;
}

Eigen::Matrix<double, 3, Eigen::Dynamic> chainPointDerivatives(const std::vector<ChainFactorValue>& chain,
                                                               const Eigen::Vector3d& p) {
  const size_t n = chain.size();
  // prefix[i] = product of factors 0..i (inclusive); suffix[i] = product of factors i+1..n-1.
  std::vector<Eigen::Matrix4d> prefix(n), suffix(n);
  Eigen::Matrix4d acc = Eigen::Matrix4d::Identity();
  for (size_t i = 0; i < n; ++i) {
    acc = acc * elementary(chain[i].motion, chain[i].value).matrix();
    prefix[i] = acc;
  }
  acc = Eigen::Matrix4d::Identity();
  for (size_t i = n; i-- > 0;) {
    suffix[i] = acc;
    acc = elementary(chain[i].motion, chain[i].value).matrix() * acc;
  }
  const Eigen::Vector4d ph(p.x(), p.y(), p.z(), 1.0);
  Eigen::Matrix<double, 3, Eigen::Dynamic> D(3, static_cast<Eigen::Index>(n));
  for (size_t i = 0; i < n; ++i)
    D.col(static_cast<Eigen::Index>(i)) = (prefix[i] * generator(chain[i].motion) * suffix[i] * ph).head<3>();
  return D;
}

}  // namespace rotacal
