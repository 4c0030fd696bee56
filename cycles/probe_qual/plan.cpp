#include "cycles/probe_qual/plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/units.hpp"
#include "postproc/program_check.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

ProbeQualLayout ProbeQualLayout::fromOptions(const CycleOptions& options) {
  ProbeQualLayout l;
  OptionTable("probe_qual")
      .count("azimuths", &l.azimuths, 4, 36)
      .list("latitude_list", &l.latitude_deg)
      .count("repeats", &l.repeats, 2, 100)
      .vec3("center_w_mm", &l.center_w_mm)
      .number("radius_mm", &l.radius_mm)
      .number("stem_length_mm", &l.stem_length_mm)
      .number("stem_diameter_mm", &l.stem_diameter_mm)
      .read(options);
  if (!(l.radius_mm > 0)) throw std::invalid_argument("option radius_mm must be > 0");
  if (!(l.stem_diameter_mm > 0 && l.stem_diameter_mm < l.radius_mm))
    throw std::invalid_argument("option stem_diameter_mm must be > 0 and below the sphere's radius");
  if (!(l.stem_length_mm > l.radius_mm))
    throw std::invalid_argument("option stem_length_mm must exceed the sphere's radius (the sphere stands on its stem)");
  if (l.latitude_deg.empty() || l.latitude_deg.size() > 10)
    throw std::invalid_argument("option latitude_list must hold 1 to 10 latitudes");
  for (double a : l.latitude_deg)
    if (!(a >= 0.0 && a <= 80.0))
      throw std::invalid_argument(fmt::format(
          "option latitude_list: {:g} deg is outside 0-80 (below the equator the stylus would reach toward the stem; "
          "the top has its own touch)",
          a));
  return l;
}

CycleOptions ProbeQualLayout::toOptions() const {
  return {{"center_w_mm", fmt::format("{:g},{:g},{:g}", center_w_mm.x(), center_w_mm.y(), center_w_mm.z())},
          {"radius_mm", fmt::format("{:g}", radius_mm)},
          {"stem_length_mm", fmt::format("{:g}", stem_length_mm)},
          {"stem_diameter_mm", fmt::format("{:g}", stem_diameter_mm)},
          {"azimuths", fmt::format("{}", azimuths)},
          {"latitude_list", numberListOption(latitude_deg)},
          {"repeats", fmt::format("{}", repeats)}};
}

std::vector<Eigen::Vector3d> ProbeQualLayout::approaches() const {
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < azimuths; ++k) {
    const double th = degToRad(360.0 * k / azimuths);
    out.emplace_back(-std::cos(th), -std::sin(th), 0.0);  // toward the centre from the contact's side
  }
  out.push_back(-Eigen::Vector3d::UnitZ());
  return out;
}

std::vector<std::string> ProbeQualLayout::approachNames() const {
  std::vector<std::string> out;
  for (int k = 0; k < azimuths; ++k) out.push_back(fmt::format("contact az {:g}", 360.0 * k / azimuths));
  out.push_back("top (-Z)");
  return out;
}

std::vector<ProbeQualLayout::Touch> ProbeQualLayout::touches() const {
  std::vector<Touch> out;
  for (double lat : latitude_deg)
    for (int k = 0; k < azimuths; ++k) {
      const double az = 360.0 * k / azimuths;
      const double phi = degToRad(lat), th = degToRad(az);
      out.push_back({k, Eigen::Vector3d(std::cos(phi) * std::cos(th), std::cos(phi) * std::sin(th), std::sin(phi)),
                     fmt::format("az {:g} lat {:g}", az, lat)});
    }
  out.push_back({azimuths, Eigen::Vector3d::UnitZ(), "top"});
  return out;
}

ProbeQualLayout probeQualLayoutOf(const ProbePlan& plan) { return ProbeQualLayout::fromOptions(plan.options); }

ProbePlan makeProbeQualPlan(const MachineModel& machine, const CycleOptions& options) {
  const ProbeQualLayout l = ProbeQualLayout::fromOptions(options);
  const auto touches = l.touches();
  const auto approaches = l.approaches();
  requirePlanSize(fmt::format("options azimuths, latitude_list, repeats ({} x {} touches)", touches.size(), l.repeats),
                  static_cast<double>(touches.size()) * l.repeats, 1.0);
  const double r = machine.probe.ball_radius_mm();
  const double R = l.radius_mm;
  const double reach = R + r + machine.approach_mm;  // an equatorial start's distance from the centre
  if (machine.probe.stylus_length_mm < R + machine.probe.body_clearance_mm)
    throw std::invalid_argument(fmt::format(
        "the stylus ({:g} mm) is too short for a touch at the equator of a {:g} mm sphere: the probe body would come "
        "within {:g} mm of its top",
        machine.probe.stylus_length_mm, 2 * R, machine.probe.body_clearance_mm));
  // A horizontal approach to a contact at latitude phi starts `approach` out from the ball's
  // trigger, which lies (R + r) from the centre at phi: the start's gap to the sphere is less
  // than the approach above the equator, and the verifier wants the planned gap less its allowance.
  const double planned = std::min(machine.clearance_mm, machine.approach_mm);
  const double need = planned - std::min(kCompensationAllowanceMm, 0.5 * planned);
  for (double lat : l.latitude_deg) {
    const double phi = degToRad(lat);
    const double gap = std::hypot((R + r) * std::cos(phi) + machine.approach_mm, (R + r) * std::sin(phi)) - (R + r);
    if (gap < need)
      throw std::invalid_argument(fmt::format(
          "option latitude_list: at {:g} deg a horizontal approach starts {:.2f} mm from the sphere, nearer than the "
          "{:.2f} mm the program verifier requires: use a lower latitude",
          lat, gap, need));
  }

  const Pose pose{};  // every rotary axis at 0: the workpiece frame is the machine frame
  const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
  const Eigen::Vector3d c_m = T * l.center_w_mm;
  if (machine.artefact) {
    const std::string why = sphereReachRefusal(machine, T, c_m, R, reach);
    if (!why.empty()) throw std::invalid_argument("the sphere at center_w_mm: " + why + " (move it with center_w_mm)");
  }
  ProbePlan plan;
  plan.cycle = "probe_qual";
  plan.machine = machine;
  plan.options = l.toOptions();
  // A head's X Y Z read its pivot, the ball L below it at this pose.
  const Eigen::Vector3d b_m = ballFromAxes_m(machine, pose);
  const double top_z = c_m.z() + R + r + machine.clearance_mm - b_m.z();
  // The program indexes to the pose from wherever the axes stand: above all the table carries.
  plan.index_z_mm = tableSweepRadius(machine, l.center_w_mm, R) + r + machine.clearance_mm + ballDropBelowAxes(machine);
  int id = 1;
  for (int k = 0; k < l.repeats; ++k) {
    // Each repeat is a pose of its own (the same angles): a pose's touches are what a Macro B
    // program keeps in its retained variables before it prints them (70 at most).
    const std::string pose_name = fmt::format("A0C0R{}", k + 1);
    plan.poses.push_back({pose_name, pose, top_z});
    for (size_t d = 0; d < touches.size(); ++d) {
      const Eigen::Vector3d n_m = T.linear() * touches[d].n;
      ProbePoint p;
      p.id = id++;
      p.pose_name = pose_name;
      p.pose = pose;
      p.target = static_cast<int>(d) + 1;
      p.face = faceOfNormal(n_m);
      p.contact_w_mm = l.center_w_mm + R * touches[d].n;
      p.normal_w = touches[d].n;
      p.trigger_m_mm = c_m + (R + r) * n_m - b_m;
      p.approach_m = approaches[static_cast<size_t>(touches[d].approach)];
      p.sphere = SphereTarget{1, l.center_w_mm, R};
      plan.points.push_back(p);
    }
  }
  finishTouchPlan(plan);
  return plan;
}

PlanRules probeQualPlanRules() {
  PlanRules r;
  r.spheres = 1;  // one sphere, every touch on it
  r.safe_height_over_artefact = false;  // the plan keeps the test piece out of reach sideways (plan.cpp)
  r.check_options = [](const ProbePlan& p) { (void)probeQualLayoutOf(p); };
  return r;
}

}  // namespace rotacal
