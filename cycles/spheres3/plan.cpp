#include "cycles/spheres3/plan.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/units.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

Spheres3Layout Spheres3Layout::fromOptions(const MachineModel& machine, const CycleOptions& options) {
  Spheres3Layout l;
  const double rho = machine.table_diameter_mm / 2.0 - 30.0;
  const double heights[3] = {60.0, 100.0, 140.0};
  const double angles_deg[3] = {90.0, 210.0, 330.0};
  for (int i = 0; i < 3; ++i)
    l.centers_w_mm[i] = Eigen::Vector3d(rho * std::cos(degToRad(angles_deg[i])), rho * std::sin(degToRad(angles_deg[i])),
                                        heights[i]);
  OptionTable table("spheres3");
  table.number("c_step_deg", &l.c_step_deg).number("c_start_deg", &l.c_start_deg).number("radius_mm", &l.radius_mm);
  for (int i = 0; i < 3; ++i) table.vec3(fmt::format("sphere{}_w_mm", i + 1), &l.centers_w_mm[i]);
  table.read(options);
  if (!(l.radius_mm > 0)) throw std::invalid_argument("option radius_mm must be positive");
  l.angleCount();
  // The three centres must span a plane (a rigid pose per angle) and the spheres must not overlap.
  const Eigen::Vector3d n = (l.centers_w_mm[1] - l.centers_w_mm[0]).cross(l.centers_w_mm[2] - l.centers_w_mm[0]);
  if (n.norm() < 1e-3 * std::pow((l.centers_w_mm[1] - l.centers_w_mm[0]).norm() + 1.0, 2))
    throw std::invalid_argument("the three sphere centres are collinear: they cannot fix the table's orientation");
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if ((l.centers_w_mm[i] - l.centers_w_mm[j]).norm() < 2 * l.radius_mm)
        throw std::invalid_argument(fmt::format("spheres {} and {} overlap", i + 1, j + 1));
  return l;
}

int Spheres3Layout::angleCount() const {
  if (!(c_step_deg > 0)) throw std::invalid_argument("option c_step_deg must be positive");
  const double n = 360.0 / c_step_deg;
  // Before any rounding to an integer: a tiny step gives more angles than an int holds.
  requirePlanSize(fmt::format("option c_step_deg = {:g} ({:.0f} C angles)", c_step_deg, n), 15.0 * n, n);
  const long r = std::lround(n);
  if (std::abs(n - static_cast<double>(r)) > 1e-9 || r < 4)
    throw std::invalid_argument(fmt::format(
        "option c_step_deg = {:g}: must divide 360 deg into at least 4 equal steps (the component errors are "
        "identified as harmonics over the full turn)",
        c_step_deg));
  return static_cast<int>(r);
}

CycleOptions Spheres3Layout::toOptions() const {
  auto v3 = [](const Eigen::Vector3d& v) { return fmt::format("{:g},{:g},{:g}", v.x(), v.y(), v.z()); };
  return {{"c_step_deg", fmt::format("{:g}", c_step_deg)},
          {"c_start_deg", fmt::format("{:g}", c_start_deg)},
          {"radius_mm", fmt::format("{:g}", radius_mm)},
          {"sphere1_w_mm", v3(centers_w_mm[0])},
          {"sphere2_w_mm", v3(centers_w_mm[1])},
          {"sphere3_w_mm", v3(centers_w_mm[2])}};
}

const std::array<Eigen::Vector3d, 5>& spheres3Approaches() {
  static const std::array<Eigen::Vector3d, 5> a = {-Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitY(),
                                                   Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                                   -Eigen::Vector3d::UnitZ()};
  return a;
}

ProbePlan makeSpheres3Plan(const MachineModel& machine, const CycleOptions& options) {
  if (!machine.hasRotary('C')) throw std::invalid_argument("cycle spheres3 needs a C axis");
  // Its touches place the ball at the reading and its report speaks a tilting table's errors.
  if (hasSpindleHead(machine.kinematics))
    throw std::invalid_argument(fmt::format("cycle spheres3 runs on a tilting-table machine, not a {} one: it places the "
                                            "ball at the axes' reading, which a head carries L away",
                                            kinematicsName(machine.kinematics)));
  const Spheres3Layout layout = Spheres3Layout::fromOptions(machine, options);
  const int n_angles = layout.angleCount();
  const double r = machine.probe.ball_radius_mm();
  const double R = layout.radius_mm;

  ProbePlan plan;
  plan.cycle = "spheres3";
  plan.machine = machine;
  plan.options = layout.toOptions();

  // One safe height for the whole cycle: with the tilt axis at 0 the C rotation keeps every
  // height, so the top of the highest sphere (and of the test piece, if the machine carries one)
  // plus the ball and the clearance is safe at every angle; the C axis indexes there too.
  double top_z = -1e300;
  for (const auto& c : layout.centers_w_mm) top_z = std::max(top_z, c.z() + R);
  if (machine.artefact)
    for (const auto& corner : machine.artefact->corners_w()) top_z = std::max(top_z, corner.z());
  const double safe_z = top_z + r + machine.clearance_mm;
  plan.index_z_mm = safe_z;

  // The ball descends vertically to each side touch's start: that line must clear the other
  // spheres and the test piece's footprint (checked in the workpiece frame: C keeps it).
  const double reach = R + r + machine.approach_mm;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector3d start_w = layout.centers_w_mm[i] - reach * spheres3Approaches()[j];
      for (int k = 0; k < 3; ++k) {
        if (k == i) continue;
        const Eigen::Vector2d d = (start_w - layout.centers_w_mm[k]).head<2>();
        if (d.norm() < R + r + machine.probe.body_clearance_mm && start_w.z() < layout.centers_w_mm[k].z() + R + r)
          throw std::invalid_argument(fmt::format("sphere {}: the probe's way down to a side touch passes over sphere {}",
                                                  i + 1, k + 1));
      }
      if (machine.artefact) {
        const auto& col = *machine.artefact;
        const Eigen::Vector2d lo = col.top_centre_w.head<2>() - col.size_mm.head<2>() / 2;
        const Eigen::Vector2d hi = col.top_centre_w.head<2>() + col.size_mm.head<2>() / 2;
        const Eigen::Vector2d p = start_w.head<2>();
        const double dx = std::max({lo.x() - p.x(), 0.0, p.x() - hi.x()});
        const double dy = std::max({lo.y() - p.y(), 0.0, p.y() - hi.y()});
        if (std::hypot(dx, dy) < r + machine.clearance_mm)
          throw std::invalid_argument(fmt::format(
              "sphere {}: the probe's way down to a side touch passes within {:.1f} mm of the test piece", i + 1,
              r + machine.clearance_mm));
      }
    }

  int id = 1;
  for (int n = 0; n < n_angles; ++n) {
    const double c = layout.c_start_deg + n * layout.c_step_deg;
    Pose pose;
    pose.C = c;
    // Whole angles keep their three-digit names; others need all their digits to stay distinct.
    const std::string name = c == std::round(c) ? fmt::format("C{:03.0f}", c) : fmt::format("C{}", c);
    plan.poses.push_back({name, pose, safe_z});
    const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d c_m = T * layout.centers_w_mm[i];
      for (int j = 0; j < 5; ++j) {
        const Eigen::Vector3d u = spheres3Approaches()[j];
        const Eigen::Vector3d n_m = -u;  // outward normal at the contact
        ProbePoint p;
        p.id = id++;
        p.pose_name = name;
        p.pose = pose;
        p.target = 5 * i + j + 1;
        p.face = faceOfNormal(n_m);
        p.contact_w_mm = T.inverse() * (c_m + R * n_m);
        p.normal_w = T.linear().transpose() * n_m;
        p.trigger_m_mm = c_m + (R + r) * n_m;
        p.approach_m = u;
        p.sphere = SphereTarget{i + 1, layout.centers_w_mm[i], R};
        plan.points.push_back(p);
      }
    }
  }
  finishTouchPlan(plan);
  return plan;
}

PlanRules spheres3PlanRules() {
  PlanRules r;
  r.spheres = 3;  // 001 Fig. 2: three spheres, each fitted at every pose
  return r;
}

}  // namespace rotacal
