#pragma once
// 002 Sec. 4.3's measuring series, shared by the rtest diagnosis test and the judge bench so
// that the bench prints figures for the very scenario the test asserts on.
#include <fmt/format.h>

#include <string>

#include "core/machine.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"

namespace rotacal::test {

/// 11 measuring cycles over 3 h (every 18 min) on the bundled B/C machine (`source_dir`: the
/// source tree), `noise_um` of sensor noise declared.
inline ProbePlan rtest002Plan(const std::string& source_dir, double noise_um) {
  const CycleOptions o = {{"thermal", "1"}, {"interval_min", "18"}, {"sensor_noise_um", fmt::format("{:g}", noise_um)}};
  return makePlan("rtest", loadMachine(source_dir + "/examples/machines/bc_trunnion.json"), o);
}

/// 002-like position-dependent errors (um / mdeg at B = -60..60), varied by `shape`.
inline Truth rtest002Truth(int shape) {
  Truth t;
  t.errors.kinematics = Kinematics::TableBC;
  t.pose_dependent = [shape](const Pose& p) {
    const double s = p.B / 60.0;
    ErrorVector d = ErrorVector::Zero();
    d[0] = umToMm(3.0 + 2.0 * s);
    d[1] = umToMm(-4.0 + (shape % 2 ? 1.5 : -1.0) * s * s);
    d[2] = umToMm(5.0 * s);
    d[3] = mdegToRad(2.0 - s);
    d[4] = mdegToRad(-1.5 + 2.5 * s);
    d[5] = mdegToRad((shape % 3) * 0.5 * s * s);
    return d;
  };
  return t;
}

}  // namespace rotacal::test
