#include "cycles/one_sphere/design.hpp"

#include <cmath>
#include <string>

#include "core/units.hpp"

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
    row->setZero(x.size());
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

SphereBacklashTerms appendBacklashParameters(const MachineModel& machine, const std::vector<Eigen::Vector3d>& directions,
                                             std::vector<IdentifiabilityParameter>* names) {
  SphereBacklashTerms terms;
  for (int k = 0; k < 3; ++k) {
    const char axis = static_cast<char>('A' + k);
    if (!machine.hasRotary(axis)) continue;
    bool known = false, unknown = false;
    for (const auto& d : directions) (d[k] == 0.0 ? unknown : known) = true;
    if (known) {
      terms.lost_motion[static_cast<size_t>(k)] = static_cast<Eigen::Index>(names->size());
      names->push_back({std::string("backlash_") + axis, ParamKind::Angle});
    }
    if (unknown && known) {  // without a move of the axis in the plan, its offset is the model's own
      terms.lead_in[static_cast<size_t>(k)] = static_cast<Eigen::Index>(names->size());
      names->push_back({std::string("lead_in_") + axis, ParamKind::Angle});
    }
  }
  return terms;
}

Pose backlashPose(const SphereBacklashTerms& terms, const Eigen::VectorXd& x, const Pose& commanded,
                  const Eigen::Vector3d& direction) {
  double angle[3] = {commanded.A, commanded.B, commanded.C};
  for (size_t k = 0; k < 3; ++k) {
    const Eigen::Index b = terms.lost_motion[k], lead = terms.lead_in[k];
    const double d = direction[static_cast<Eigen::Index>(k)];
    if (d != 0.0 && b >= 0) angle[k] -= 0.5 * d * radToDeg(x[b]);
    if (d == 0.0 && lead >= 0) angle[k] += radToDeg(x[lead]);
  }
  return Pose{angle[0], angle[1], angle[2]};
}

double sphereTouchResidual(const KinematicModel& m, bool squareness, const SphereBacklashTerms& terms,
                           const Eigen::VectorXd& x, const Pose& pose, const Eigen::Vector3d& direction,
                           const Eigen::Vector3d& t, double rho, Eigen::RowVectorXd* row) {
  const Pose actual = backlashPose(terms, x, pose, direction);
  const double r = sphereTouchResidual(m, squareness, x, actual, t, rho, row);
  if (!row) return r;
  constexpr double h_deg = 1e-4;
  for (size_t k = 0; k < 3; ++k) {
    const Eigen::Index b = terms.lost_motion[k], lead = terms.lead_in[k];
    const double d = direction[static_cast<Eigen::Index>(k)];
    if (!((d != 0.0 && b >= 0) || (d == 0.0 && lead >= 0))) continue;
    Pose up = actual, down = actual;
    double* u = k == 0 ? &up.A : (k == 1 ? &up.B : &up.C);
    double* w = k == 0 ? &down.A : (k == 1 ? &down.B : &down.C);
    *u += h_deg;
    *w -= h_deg;
    const double slope_per_deg = (sphereTouchResidual(m, squareness, x, up, t, rho, nullptr) -
                                  sphereTouchResidual(m, squareness, x, down, t, rho, nullptr)) /
                                 (2 * h_deg);
    if (d != 0.0) (*row)[b] = -0.5 * d * radToDeg(1.0) * slope_per_deg;
    else (*row)[lead] = radToDeg(1.0) * slope_per_deg;
  }
  return r;
}

Eigen::Vector3d sphereTouchNormal(const KinematicModel& m, bool squareness, const Eigen::VectorXd& x, const Pose& pose,
                                  const Eigen::Vector3d& t) {
  const int np = m.size();
  return (t + squarenessError(squareness, x, np, t) - sphereCentreInAxes(m, x.head(np), pose)).normalized();
}

}  // namespace rotacal
