#include "postproc/probe_program.hpp"

#include <fmt/format.h>

#include "core/units.hpp"

namespace rotacal {

double controllerAngle(const MachineModel& machine, char axis, const std::string& dialect, double paper_deg) {
  const double a = machine.controllerSign(axis, dialect) * paper_deg;
  return a == 0.0 ? 0.0 : a;  // no "-0.000"
}

nc::Op indexOp(const MachineModel& m, const Pose& pose, const std::string& dialect, char axis, double feed) {
  nc::Op op;
  op.kind = nc::Op::Kind::Index;
  op.feed = feed;
  for (const auto& r : m.rotary)
    if (axis == 0 || r.name == axis) op.rotary.emplace_back(r.name, controllerAngle(m, r.name, dialect, pose.angle(r.name)));
  return op;
}

std::string poseNameAt(const ProbePlan& plan, const Pose& pose) {
  std::string name;
  for (const auto& p : plan.poses)
    if (p.pose.A == pose.A && p.pose.B == pose.B && p.pose.C == pose.C) name = p.name;
  return name;
}

nc::Op commentOp(const std::string& text) {
  nc::Op c;
  c.kind = nc::Op::Kind::Comment;
  c.text = text;
  return c;
}

std::vector<std::string> angleSignLines(const MachineModel& m, const std::string& dialect, const std::string& source) {
  std::vector<std::string> out;
  for (const auto& r : m.rotary)
    out.push_back(fmt::format("{} angles: controller = {} x paper convention{}", r.name,
                              m.controllerSign(r.name, dialect) > 0 ? "+1" : "-1", source.empty() ? "" : " (" + source + ")"));
  return out;
}

std::string angleConvention(Kinematics k) {
  switch (k) {
    case Kinematics::TableAC: return "000 Eq. (1)";
    case Kinematics::TableBC: return "002 Eq. (2)";
    case Kinematics::TableAB: return "rotacal's A/B table chain (docs/conventions.md)";
    case Kinematics::HeadAB:
    case Kinematics::HeadCB:
    case Kinematics::HeadTable: return "ISO 841: the head turns by +angle";
  }
  return {};
}

std::vector<std::string> setupLines(const MachineModel& m) {
  if (m.head) {
    const std::string zero = m.kinematics == Kinematics::HeadTable
                                 ? "X0 Y0 on the C axis of the table, Z0 where MACHINE.json's frame has it"
                                 : "X0 Y0 Z0 at MACHINE.json's machine-frame origin";
    return {
        fmt::format("work offset: {}, no rotation", zero),
        fmt::format("X Y Z = the head's pivot [the head axes' intersection with the spindle axis], NOT the ball: the "
                    "ball centre hangs {:.3f} mm from it along the tilted spindle; no tool length compensation",
                    m.head->pivot_to_ball_mm),
    };
  }
  return {
      "work offset: X0 Y0 Z0 at the intersection of the rotary axes, no rotation",
      m.probe.tool_number ? fmt::format("X Y Z = the probe-ball centre, through tool {}'s length to the ball centre",
                                        m.probe.tool_number)
                          : std::string("X Y Z = the probe-ball centre [controlled point, no length compensation]"),
  };
}

nc::Op pathMoveOp(const Waypoint& w, const MachineModel& m, double k) {
  nc::Op op;
  op.xyz = w.position_m * k;
  switch (w.kind) {
    case Waypoint::Kind::ClimbZ:
      op.kind = nc::Op::Kind::Rapid;
      op.z_only = true;
      break;
    case Waypoint::Kind::Rapid: op.kind = nc::Op::Kind::Rapid; break;
    case Waypoint::Kind::Position:
    case Waypoint::Kind::Retract:
      op.kind = nc::Op::Kind::Linear;
      op.feed = m.feeds.positioning_mm_min * k;
      break;
    case Waypoint::Kind::Index:
    case Waypoint::Kind::Probe:
    case Waypoint::Kind::Dwell:
    case Waypoint::Kind::Read: break;
  }
  return op;
}

nc::Program probeProgram(const ProbePlan& plan, const std::string& dialect) {
  const MachineModel& m = plan.machine;
  nc::Program prog;
  prog.cycle = plan.cycle;
  prog.name = "ROTACAL_" + plan.cycle;
  for (auto& ch : prog.name) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  prog.unit = m.units == LengthUnit::Inch ? nc::Unit::Inch : nc::Unit::Millimetre;
  const double k = m.units == LengthUnit::Inch ? 1.0 / kMmPerInch : 1.0;
  prog.probe_tool = m.probe.tool_number;
  prog.results_file = "rotacal_" + plan.cycle;
  prog.point_count = static_cast<int>(plan.points.size());
  for (const auto& r : m.rotary) prog.rotary_axes.push_back(r.name);
  prog.header = {
      fmt::format("rotacal {} probing cycle, {} points, {} poses", plan.cycle, plan.points.size(), plan.poses.size()),
      fmt::format("machine: {} [{}]", m.name, kinematicsName(m.kinematics)),
  };
  for (const auto& l : setupLines(m)) prog.header.push_back(l);
  prog.header.push_back(
      fmt::format("ball diameter {:.3f} mm, probing feed {:.1f} mm/min", m.probe.ball_diameter_mm, m.feeds.probing_mm_min));
  if (m.retract_mm > 0)
    prog.header.push_back(fmt::format("double touch: back off {:.3f} mm, second touch at {:.1f} mm/min is recorded",
                                      m.retract_mm, m.feeds.probing_slow_mm_min));
  for (const auto& l : angleSignLines(m, dialect, angleConvention(m.kinematics))) prog.header.push_back(l);
  const auto path = plannedPath(plan);
  for (const auto& w : path) {
    nc::Op op = pathMoveOp(w, m, k);
    switch (w.kind) {
      case Waypoint::Kind::ClimbZ:
      case Waypoint::Kind::Rapid:
      case Waypoint::Kind::Position:
      case Waypoint::Kind::Retract:
      case Waypoint::Kind::Dwell:  // not on a probing path
      case Waypoint::Kind::Read: break;
      case Waypoint::Kind::Index: {
        op = indexOp(m, w.pose, dialect);
        prog.ops.push_back(commentOp(fmt::format("pose {}", poseNameAt(plan, w.pose))));
        break;
      }
      case Waypoint::Kind::Probe: {
        op.kind = nc::Op::Kind::Probe;
        op.feed = m.feeds.probing_mm_min * k;
        if (m.retract_mm > 0) {  // double touch: fast first touch, back off, slow recorded touch
          op.retract_mm = m.retract_mm * k;
          op.slow_feed = m.feeds.probing_slow_mm_min * k;
        }
        op.point_id = w.point_id;
        const ProbePoint* p = plan.findPoint(w.point_id);
        op.nominal_trigger = p->trigger_m_mm * k;
        op.pose_name = p->pose_name;
        op.text = p->sphere ? fmt::format("P{} pose {} sphere {}", p->id, p->pose_name, p->sphere->id)
                            : fmt::format("P{} pose {} target {} face {}", p->id, p->pose_name, p->target, faceName(p->face));
        break;
      }
    }
    prog.ops.push_back(op);
  }
  return prog;
}

}  // namespace rotacal
