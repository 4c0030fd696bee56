#include "core/rotary_backlash.hpp"

namespace rotacal {

std::vector<Eigen::Vector3d> rotaryApproachDirections(const ProbePlan& plan, bool from_start) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(plan.points.size());
  Eigen::Vector3d dir = from_start ? Eigen::Vector3d::Ones() : Eigen::Vector3d::Zero();
  bool first = true;
  Eigen::Vector3d last = Eigen::Vector3d::Zero();
  for (const auto& p : plan.points) {
    const Eigen::Vector3d cmd(p.pose.A, p.pose.B, p.pose.C);
    // Without a known start, the first pose's angles are where the axes came from nowhere known.
    if (from_start || !first)
      for (int k = 0; k < 3; ++k)
        if (cmd[k] != last[k]) dir[k] = cmd[k] > last[k] ? 1.0 : -1.0;
    first = false;
    last = cmd;
    out.push_back(dir);
  }
  return out;
}

}  // namespace rotacal
