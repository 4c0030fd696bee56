#pragma once
// What the controller recorded at one trigger, after a dialect parser has turned its file into
// the papers' frame: ball-centre machine coordinates in mm (origin at the rotary-axis
// intersection), and the time in seconds when the control has a clock (NaN otherwise).
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

namespace rotacal {

struct TriggerPoint {
  int point_id = 0;
  Eigen::Vector3d position_m_mm = Eigen::Vector3d::Zero();
  double t_s = std::numeric_limits<double>::quiet_NaN();
};

/// One results file: the triggers of one run of a plan.
struct MeasurementRun {
  std::string source;  // file name, for messages
  std::vector<TriggerPoint> points;
};

}  // namespace rotacal
