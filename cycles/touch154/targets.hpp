#pragma once
// The touch targets on the square column that the fixed touch154 layout and the designed plans
// (design.hpp) both place: one rule for the side touches and the faces' edges.
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/artefact.hpp"
#include "core/probe_plan.hpp"

namespace rotacal::touch154 {

/// A touch: its number (1-based, in plan order), the face and the contact point, world frame.
struct Target {
  int k;
  Face face;
  Eigen::Vector3d contact_w;
};

/// Throws std::invalid_argument when offset `off` lies off a face of half-width `half` (`what`:
/// "side" or "top").
void requireOnFace(double off, double half, const char* what);

/// The plan point `id` touching `t` at `pose` (`T`: its nominal machine-from-world transform)
/// with a ball of radius `r`: the trigger at the ball's centre, the approach against the normal.
ProbePoint touchPoint(int id, const std::string& pose_name, const Pose& pose, const Eigen::Isometry3d& T,
                      const Target& t, double r);

/// The touches of a plan on `col`, numbered from 1 in the order they are added.
class Targets {
 public:
  explicit Targets(const SquareColumn& col) : col_(col) {}
  /// The side touches at `depth` below the column's top, at each of `offsets` along each face,
  /// going round the column counter-clockwise seen from above (+X, +Y, -X, -Y).
  void addSides(double depth, const std::vector<double>& offsets);
  /// A touch on the top at (ox, oy) from its centre; throws when it lies off the top.
  void addTop(double ox, double oy);
  std::vector<Target> list;

 private:
  const SquareColumn& col_;
  int k_ = 1;
};

}  // namespace rotacal::touch154
