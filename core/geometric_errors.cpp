#include "core/geometric_errors.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/require_valid.hpp"
#include "core/transforms.hpp"
#include "core/units.hpp"

namespace rotacal {

namespace {

constexpr double kTurnDeg = 360.0;
// Equal spacing is judged on the printed angles of a report (6 decimals at most).
constexpr double kSpacingTolDeg = 1e-6;

int axisIndex(char axis) { return axis == 'A' ? 0 : axis == 'B' ? 1 : axis == 'C' ? 2 : -1; }

double axisAngle(const Pose& p, int index) { return index == 0 ? p.A : index == 1 ? p.B : p.C; }

}  // namespace

std::array<std::string, kNumComponentErrors> componentErrorNames(char axis) {
  const std::string a(1, axis);
  return {"EX" + a, "EY" + a, "EZ" + a, "EA" + a, "EB" + a, "EC" + a};
}

bool ComponentErrors::validate(std::string* why) const {
  if (axisIndex(axis) < 0) return invalidBecause(why, fmt::format("component errors of axis '{}': not A, B or C", axis));
  if (angle_deg.size() < 3)
    return invalidBecause(why, fmt::format("component errors of {}: {} angles, at least 3 are needed over the turn",
                                            axis, angle_deg.size()));
  if (values.size() != angle_deg.size() || (!u.empty() && u.size() != angle_deg.size()))
    return invalidBecause(why, fmt::format("component errors of {}: {} angles but {} values and {} uncertainties",
                                            axis, angle_deg.size(), values.size(), u.size()));
  for (size_t i = 0; i < angle_deg.size(); ++i) {
    if (!std::isfinite(angle_deg[i]) || !values[i].allFinite() || (!u.empty() && !u[i].allFinite()))
      return invalidBecause(why, fmt::format("component errors of {}: a value at angle #{} is not finite", axis, i + 1));
    if (i > 0 && !(angle_deg[i] > angle_deg[i - 1]))
      return invalidBecause(why, fmt::format("component errors of {}: the angles must ascend ({} deg after {} deg)", axis,
                                              angle_deg[i], angle_deg[i - 1]));
  }
  if (!(angle_deg.back() - angle_deg.front() < kTurnDeg))
    return invalidBecause(why, fmt::format("component errors of {}: the angles span {} deg, more than a turn", axis,
                                            angle_deg.back() - angle_deg.front()));
  return true;
}

bool ComponentErrors::equallySpaced() const {
  const double step = kTurnDeg / static_cast<double>(angle_deg.size());
  for (size_t i = 1; i < angle_deg.size(); ++i)
    if (std::abs(angle_deg[i] - angle_deg[i - 1] - step) > kSpacingTolDeg) return false;
  return true;
}

ComponentVector ComponentErrors::at(double deg) const {
  const size_t n = angle_deg.size();
  const double theta0 = angle_deg.front();
  if (equallySpaced()) {
    // Trigonometric interpolation (the DFT of the samples evaluated between them): terms
    // k = 0 .. floor((n-1)/2) in cos and sin, plus cos(n/2 t) for even n, t from the first angle.
    const double t = degToRad(deg - theta0);
    const int half = static_cast<int>(n) / 2;
    ComponentVector f = ComponentVector::Zero();
    for (size_t j = 0; j < n; ++j) {
      const double tj = 2.0 * kPi * static_cast<double>(j) / static_cast<double>(n);
      double w = 1.0;  // weight of sample j at t: (1/n) sum_k e^{ik(t - tj)} over the band
      for (int k = 1; k <= (static_cast<int>(n) - 1) / 2; ++k) w += 2.0 * std::cos(k * (t - tj));
      if (n % 2 == 0) w += std::cos(half * t) * std::cos(half * tj);
      f += values[j] * (w / static_cast<double>(n));
    }
    return f;
  }
  // Piecewise linear over the turn, the last sample joined to the first one a turn on.
  double x = std::fmod(deg - theta0, kTurnDeg);
  if (x < 0) x += kTurnDeg;
  for (size_t j = 0; j < n; ++j) {
    const double a0 = angle_deg[j] - theta0;
    const double a1 = j + 1 < n ? angle_deg[j + 1] - theta0 : kTurnDeg;
    if (x <= a1 || j + 1 == n) {
      const double s = (x - a0) / (a1 - a0);
      return values[j] * (1.0 - s) + values[(j + 1) % n] * s;
    }
  }
  return values.front();
}

const ComponentErrors* GeometricErrors::componentsOf(char axis) const {
  for (const auto& c : components)
    if (c.axis == axis) return &c;
  return nullptr;
}

bool GeometricErrors::validate(std::string* why) const {
  std::vector<char> moved;
  for (const auto& f : kinematicChain(location.kinematics))
    if (f.source == ChainFactor::Source::NegativeAxis) moved.push_back("ABC"[f.index]);
  for (size_t i = 0; i < components.size(); ++i) {
    if (!components[i].validate(why)) return false;
    bool ok = false;
    for (char c : moved) ok = ok || c == components[i].axis;
    if (!ok)
      return invalidBecause(why, fmt::format("component errors of {}: the {} kinematics has no {} axis",
                                              components[i].axis, kinematicsName(location.kinematics),
                                              components[i].axis));
    for (size_t j = 0; j < i; ++j)
      if (components[j].axis == components[i].axis)
        return invalidBecause(why, fmt::format("component errors of {} given twice", components[i].axis));
  }
  return true;
}

Eigen::Isometry3d componentTransform(const ComponentVector& v) {
  return Dx(v[0]) * Dy(v[1]) * Dz(v[2]) * Da(v[3]) * Db(v[4]) * Dc(v[5]);
}

Eigen::Isometry3d T_m_w(const GeometricErrors& errors, const Pose& pose) {
  if (errors.components.empty()) return T_m_w(errors.location, pose);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (const auto& f : kinematicChain(errors.location.kinematics)) {
    if (f.source == ChainFactor::Source::Parameter) {
      T = T * elementary(f.motion, errors.location.values[f.index]);
      continue;
    }
    const double deg = axisAngle(pose, f.index);
    if (const ComponentErrors* c = errors.componentsOf("ABC"[f.index])) T = T * componentTransform(c->at(deg));
    T = T * elementary(f.motion, -degToRad(deg));
  }
  return T;
}

}  // namespace rotacal
