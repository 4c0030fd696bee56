#include "cycles/one_sphere/design.hpp"

namespace rotacal {

namespace {

Eigen::Vector3d squarenessError(bool squareness, const Eigen::VectorXd& x, int np, const Eigen::Vector3d& t) {
  if (!squareness) return Eigen::Vector3d::Zero();
  const double S_xy = x[np + 1], S_xz = x[np + 2], S_yz = x[np + 3];
  return {S_xy * t.y() + S_xz * t.z(), S_yz * t.z(), 0.0};
}

}  // namespace

std::vector<IdentifiabilityParameter> sphereFitParameters(const KinematicModel& m, bool squareness) {
  std::vector<IdentifiabilityParameter> names;
  for (const auto& q : m.parameters) names.push_back({q.name, q.kind});
  names.push_back({"dR", ParamKind::Length});
  // Out-of-squareness is an angle between two axes (mm per mm = rad), reported in mdeg as the
  // location errors' angles are (1 mdeg = 17.45 um/m).
  if (squareness)
    for (const char* s : {"S_xy", "S_xz", "S_yz"}) names.push_back({s, ParamKind::Angle});
  return names;
}

double sphereTouchResidual(const KinematicModel& m, bool squareness, const Eigen::VectorXd& x, const Pose& pose,
                           const Eigen::Vector3d& t, double rho, Eigen::RowVectorXd* row) {
  const int np = m.size();
  const Eigen::Vector3d d = t + squarenessError(squareness, x, np, t) - sphereCentreInAxes(m, x.head(np), pose);
  if (row) {
    const Eigen::Vector3d n = d.normalized();
    row->resize(x.size());
    row->head(np) = -(n.transpose() * J_X_p(m, x.head(np), pose));
    (*row)[np] = -1.0;
    if (squareness) {
      (*row)[np + 1] = n.x() * t.y();
      (*row)[np + 2] = n.x() * t.z();
      (*row)[np + 3] = n.y() * t.z();
    }
  }
  return d.norm() - (rho + x[np]);
}

Eigen::Vector3d sphereTouchNormal(const KinematicModel& m, bool squareness, const Eigen::VectorXd& x, const Pose& pose,
                                  const Eigen::Vector3d& t) {
  const int np = m.size();
  return (t + squarenessError(squareness, x, np, t) - sphereCentreInAxes(m, x.head(np), pose)).normalized();
}

}  // namespace rotacal
