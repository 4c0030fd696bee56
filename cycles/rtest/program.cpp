#include "cycles/rtest/program.hpp"

#include <fmt/format.h>

#include "cycles/rtest/plan.hpp"
#include "core/units.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {

nc::Program rtestProgram(const ProbePlan& plan, const std::string& dialect) {
  const MachineModel& m = plan.machine;
  const Kinematics kin = m.kinematics;
  const char tilt = tiltAxis(kin);
  const RtestSchedule sched = rtestSchedule(plan);
  nc::Program prog;
  prog.cycle = plan.cycle;
  prog.name = "ROTACAL_RTEST";
  prog.unit = m.units == LengthUnit::Inch ? nc::Unit::Inch : nc::Unit::Millimetre;
  const double k = m.units == LengthUnit::Inch ? 1.0 / kMmPerInch : 1.0;
  prog.probe_tool = m.probe.tool_number;
  prog.results_file = "rotacal_rtest";
  prog.point_count = 0;  // no probing moves: the readings come from the R-test logger
  for (const auto& r : m.rotary) prog.rotary_axes.push_back(r.name);
  const Eigen::Vector3d nest = rtestNest_w(plan);
  prog.header = {
      fmt::format("rotacal static R-test cycle (002), {} poses per cycle, {} cycle(s)", plan.points.size(), sched.cycles()),
      fmt::format("machine: {}", m.name),
      fmt::format("sphere {:.3f} mm on the spindle, in the probe's place; nest at {:.3f} {:.3f} {:.3f} mm on the table",
                  m.probe.ball_diameter_mm, nest.x(), nest.y(), nest.z()),
      fmt::format("each pose: enter along the nest axis, dwell, READ = trigger the R-test logger [pose id]"),
      rtestResetReads(plan)
          ? fmt::format("reset: every cycle reads {} 0 C 0 first [pose 0, 002 Eq. 4] and again at its end [pose 0: a "
                        "difference is a sensor step]; the logger zeroes the sensors at the first of them",
                        tilt)
          : fmt::format("reset: the logger zeroes the sensors at the first reading at {} 0 C 0 [002 Eq. 4]", tilt),
  };
  if (sched.thermal)
    prog.header.push_back(fmt::format("thermal test: every {:g} min for {:g} h, {} reciprocates {:g} to {:g} deg at "
                                      "{:g} deg/min in between",
                                      sched.interval_s / 60.0, sched.duration_s / 3600.0, tilt, sched.recip_from_deg,
                                      sched.recip_to_deg, sched.recip_feed_deg_min));
  // X Y Z read the sphere's centre as they would the probe's (setupLines: a head's pivot on a head)
  for (const auto& l : setupLines(m)) prog.header.insert(prog.header.begin() + 2, l);
  for (const auto& l : angleSignLines(m, dialect, angleConvention(m.kinematics))) prog.header.push_back(l);
  auto comment = [&](const std::string& t) { prog.ops.push_back(commentOp(t)); };
  auto index = [&](const Pose& pose, bool tilt_only, double feed) {
    prog.ops.push_back(indexOp(m, pose, dialect, tilt_only ? tilt : 0, feed));
  };
  const auto moves = rtestCycleMoves(plan);
  auto cycle = [&](const std::string& title) {
    comment(title);
    int reads_in_cycle = 0;
    for (const auto& mv : moves) {
      nc::Op op = pathMoveOp(mv, m, k);
      switch (mv.kind) {
        case Waypoint::Kind::ClimbZ:
        case Waypoint::Kind::Rapid:
        case Waypoint::Kind::Position:
        case Waypoint::Kind::Retract:
        case Waypoint::Kind::Probe: break;  // no probing move: the sphere sits in the nest
        case Waypoint::Kind::Index: {
          const std::string name = poseNameAt(plan, mv.pose);
          const bool reset_visit = rtestResetReads(plan) && (reads_in_cycle == 0 || reads_in_cycle == static_cast<int>(plan.points.size()) + 1);
          comment((reset_visit ? (reads_in_cycle == 0 ? "reset pose " : "re-read of the reset pose ") : "pose ") + name);
          index(mv.pose, false, 0.0);
          continue;
        }
        case Waypoint::Kind::Dwell:
          op.kind = nc::Op::Kind::Dwell;
          op.seconds = mv.seconds;
          break;
        case Waypoint::Kind::Read:
          op.kind = nc::Op::Kind::Read;
          op.point_id = mv.point_id;
          if (mv.point_id == 0) {
            // 002 Eq. (4): the reset pose, read before the first pose and again after the last.
            const bool before = reads_in_cycle == 0;
            op.pose_name = before ? "reset" : "re-read";
            op.text = before ? fmt::format("R-test reset reading {} 0 C 0 [pose 0, before the first pose]", tilt)
                             : fmt::format("R-test re-read of the reset {} 0 C 0 [pose 0, catches a sensor step]", tilt);
          } else {
            op.pose_name = plan.points[static_cast<size_t>(mv.point_id - 1)].pose_name;
            op.text = fmt::format("R-test reading pose {} {}", mv.point_id, op.pose_name);
          }
          ++reads_in_cycle;
          break;
      }
      prog.ops.push_back(op);
    }
  };
  cycle("measuring cycle 1");
  if (sched.thermal && sched.cycles() > 1) {
    const int n = rtestReciprocations(plan);
    nc::Op begin;
    begin.kind = nc::Op::Kind::RepeatBegin;
    begin.count = sched.cycles() - 1;
    prog.ops.push_back(begin);
    comment(fmt::format("warm-up: {} round trips of {} between {:g} and {:g} deg", n, tilt, sched.recip_from_deg,
                        sched.recip_to_deg));
    index(tiltPose(kin, sched.recip_from_deg, 0.0), true, 0.0);
    if (n > 0) {
      nc::Op inner;
      inner.kind = nc::Op::Kind::RepeatBegin;
      inner.count = n;
      prog.ops.push_back(inner);
      index(tiltPose(kin, sched.recip_to_deg, 0.0), true, sched.recip_feed_deg_min);
      index(tiltPose(kin, sched.recip_from_deg, 0.0), true, sched.recip_feed_deg_min);
      nc::Op end;
      end.kind = nc::Op::Kind::RepeatEnd;
      prog.ops.push_back(end);
    }
    cycle("measuring cycle 2 and later");
    nc::Op end;
    end.kind = nc::Op::Kind::RepeatEnd;
    prog.ops.push_back(end);
  }
  return prog;
}

}  // namespace rotacal
