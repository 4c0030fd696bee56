#include "cycles/one_sphere/plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/identifiability.hpp"
#include "core/kinematic_model.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

namespace {


Pose poseOf(char axis, double tilt, double c) {
  Pose p;
  (axis == 'A' ? p.A : p.B) = tilt;
  p.C = c;
  return p;
}

}  // namespace

char sphereTiltAxis(Kinematics kinematics) {
  if (kinematics == Kinematics::TableAC) return 'A';
  if (kinematics == Kinematics::TableBC) return 'B';
  throw std::invalid_argument(fmt::format(
      "cycle one_sphere runs on tilting-table machines (table_ac, table_bc) in this version, not {}: the head kinematics "
      "are modelled (core/kinematic_model.hpp) but not yet simulated",
      kinematicsName(kinematics)));
}

const std::vector<Eigen::Vector3d>& sphereApproaches() {
  static const std::vector<Eigen::Vector3d> a = {-Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitY(),
                                                 Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                                 -Eigen::Vector3d::UnitZ()};
  return a;
}

SphereLayout SphereLayout::fromOptions(const MachineModel& machine, const CycleOptions& options) {
  SphereLayout l;
  const RotaryAxis& tilt = machine.rotaryAxis(sphereTiltAxis(machine.kinematics));
  for (double t : {-90.0, -60.0, -30.0, 0.0, 30.0, 60.0, 90.0})
    if (tilt.stroke_deg.contains(t)) l.tilt_deg.push_back(t);
  for (const auto& [key, value] : options) {
    if (key == "center_w_mm") l.center_w_mm = parseVec3Option(key, value);
    else if (key == "radius_mm") l.radius_mm = parseNumber(key, value);
    else if (key == "stem_length_mm") l.stem_length_mm = parseNumber(key, value);
    else if (key == "stem_diameter_mm") l.stem_diameter_mm = parseNumber(key, value);
    else if (key == "tilt_list") l.tilt_deg = parseNumberList(key, value);
    else if (key == "c_list") l.c_deg = parseNumberList(key, value);
    else
      throw std::invalid_argument("unknown option '" + key +
                                  "' for cycle one_sphere (center_w_mm, radius_mm, stem_length_mm, stem_diameter_mm, "
                                  "tilt_list, c_list)");
  }
  if (!(l.radius_mm > 0)) throw std::invalid_argument("option radius_mm must be > 0");
  if (!(l.stem_diameter_mm > 0 && l.stem_diameter_mm < l.radius_mm))
    throw std::invalid_argument("option stem_diameter_mm must be > 0 and below the sphere's radius");
  if (!(l.stem_length_mm > l.radius_mm))
    throw std::invalid_argument("option stem_length_mm must exceed the sphere's radius (the sphere stands on its stem)");
  requirePlanSize(fmt::format("options tilt_list and c_list ({} x {} poses)", l.tilt_deg.size(), l.c_deg.size()),
                  5.0 * static_cast<double>(l.tilt_deg.size() * l.c_deg.size()),
                  static_cast<double>(l.tilt_deg.size() * l.c_deg.size()));
  return l;
}

CycleOptions SphereLayout::toOptions() const {
  return {{"center_w_mm", fmt::format("{:g},{:g},{:g}", center_w_mm.x(), center_w_mm.y(), center_w_mm.z())},
          {"radius_mm", fmt::format("{:g}", radius_mm)},
          {"stem_length_mm", fmt::format("{:g}", stem_length_mm)},
          {"stem_diameter_mm", fmt::format("{:g}", stem_diameter_mm)},
          {"tilt_list", numberListOption(tilt_deg)},
          {"c_list", numberListOption(c_deg)}};
}

SphereLayout sphereLayoutOf(const ProbePlan& plan) { return SphereLayout::fromOptions(plan.machine, plan.options); }

ProbePlan makeSpherePlan(const MachineModel& machine, const CycleOptions& options) {
  const char tilt_axis = sphereTiltAxis(machine.kinematics);
  if (!machine.hasRotary('C')) throw std::invalid_argument("cycle one_sphere needs a C axis");
  const SphereLayout l = SphereLayout::fromOptions(machine, options);
  const double r = machine.probe.ball_radius_mm();
  const double R = l.radius_mm;
  if (machine.probe.stylus_length_mm < R + machine.probe.body_clearance_mm)
    throw std::invalid_argument(fmt::format(
        "the stylus ({:g} mm) is too short for a side touch at the equator of a {:g} mm sphere: the probe body would "
        "come within {:g} mm of its top",
        machine.probe.stylus_length_mm, 2 * R, machine.probe.body_clearance_mm));

  ProbePlan plan;
  plan.cycle = "one_sphere";
  plan.machine = machine;
  plan.options = l.toOptions();
  // The table indexes with the ball above everything it carries, whatever the pose.
  double sweep = std::max(machine.table_diameter_mm / 2, l.center_w_mm.norm() + R);
  if (machine.artefact)
    for (const auto& corner : machine.artefact->corners_w()) sweep = std::max(sweep, corner.norm());
  plan.index_z_mm = sweep + r + machine.clearance_mm;

  const double reach = R + r + machine.approach_mm;  // the side touches' starts, from the centre
  int id = 1;
  for (double tilt : l.tilt_deg)
    for (double c : l.c_deg) {
      const Pose pose = poseOf(tilt_axis, tilt, c);
      const std::string name = fmt::format("{}{:g}C{:g}", tilt_axis, tilt, c);
      const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
      const Eigen::Vector3d c_m = T * l.center_w_mm;
      const Eigen::Vector3d s_m = T.linear() * -Eigen::Vector3d::UnitZ();  // the stem, from the centre
      if (s_m.z() > 1e-9)
        throw std::invalid_argument(fmt::format(
            "pose {}: {} = {:g} deg turns the table above the sphere: the probe would reach it past the table "
            "(keep |tilt| <= 90 deg)",
            name, tilt_axis, tilt));
      double top_z = c_m.z() + R;
      if (machine.artefact) {
        // The test piece: above the sphere's probing region in no pose (the ball comes down from
        // the safe height there), and below the safe height.
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
        for (const auto& corner : machine.artefact->corners_w()) {
          const Eigen::Vector3d q = T * corner;
          lo = lo.cwiseMin(q);
          hi = hi.cwiseMax(q);
          top_z = std::max(top_z, q.z());
        }
        const double dx = std::max({lo.x() - c_m.x(), 0.0, c_m.x() - hi.x()});
        const double dy = std::max({lo.y() - c_m.y(), 0.0, c_m.y() - hi.y()});
        if (std::hypot(dx, dy) < reach + r + machine.clearance_mm && hi.z() > c_m.z() - R - r - machine.clearance_mm)
          throw std::invalid_argument(fmt::format(
              "pose {}: the test piece stands within {:.1f} mm of the probe's way to the sphere (move the sphere with "
              "center_w_mm or choose other angles with tilt_list, c_list)",
              name, reach + r + machine.clearance_mm));
      }
      plan.poses.push_back({name, pose, top_z + r + machine.clearance_mm});
      const size_t before = plan.points.size();
      const auto& approaches = sphereApproaches();
      for (size_t j = 0; j < approaches.size(); ++j) {
        const Eigen::Vector3d u = approaches[j];
        const Eigen::Vector3d n_m = -u;  // outward normal at the contact
        if (n_m.dot(s_m) > 1e-9) continue;  // the stem's half: the stylus would reach round to the stem
        ProbePoint p;
        p.id = id++;
        p.pose_name = name;
        p.pose = pose;
        p.target = static_cast<int>(j) + 1;
        p.face = faceOfNormal(n_m);
        p.contact_w_mm = T.inverse() * (c_m + R * n_m);
        p.normal_w = T.linear().transpose() * n_m;
        p.trigger_m_mm = c_m + (R + r) * n_m;
        p.approach_m = u;
        p.sphere = SphereTarget{1, l.center_w_mm, R};
        plan.points.push_back(p);
      }
      if (plan.points.size() - before < 4)
        throw std::invalid_argument(fmt::format("pose {}: fewer than 4 touches clear the stem", name));
    }

  // The plan must see every parameter the sphere can show (core/identifiability.hpp): the tilt
  // axis needs two tilts and the C axis three angles, and some layouts lose more.
  const KinematicModel model = kinematicModel(kinematicsName(machine.kinematics), l.center_w_mm);
  Eigen::MatrixXd J(3 * static_cast<Eigen::Index>(plan.poses.size()), model.size());
  for (size_t k = 0; k < plan.poses.size(); ++k)
    J.middleRows(3 * static_cast<Eigen::Index>(k), 3) = J_X_p(model, Eigen::VectorXd::Zero(model.size()), plan.poses[k].pose);
  std::vector<IdentifiabilityParameter> names;
  for (const auto& q : model.parameters) names.push_back({q.name, q.kind});
  const Identifiability id_ = identifiability(J, names);
  if (id_.rank < model.size() - 2) {
    std::string lost;
    for (const auto& c : id_.combinations) lost += (lost.empty() ? "" : "; ") + c.text;
    throw std::invalid_argument(fmt::format(
        "the poses ({} {} x {} C angles) leave {} directions of the location errors unseen, beyond the 2 no sphere "
        "shows: {}",
        l.tilt_deg.size(), tilt_axis, l.c_deg.size(), model.size() - id_.rank, lost));
  }
  finishTouchPlan(plan);
  return plan;
}

}  // namespace rotacal
