#include "cycles/tooltip/program.hpp"

#include <cmath>

#include <fmt/format.h>

#include "cycles/tooltip/plan.hpp"
#include "core/units.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {
namespace {

double roundTo(double v, int decimals) {
  const double s = std::pow(10.0, decimals);
  const double r = std::round(v * s) / s;
  return r == 0.0 ? 0.0 : r;
}

}  // namespace

nc::Program tooltipProgram(const ProbePlan& plan, const std::string& dialect) {
  const MachineModel& m = plan.machine;
  const TooltipOptions o = tooltipOptionsFrom(plan.options, m);
  nc::Program prog;
  prog.cycle = "tooltip";
  prog.name = "ROTACAL_TOOLTIP";
  prog.unit = o.inch ? nc::Unit::Inch : nc::Unit::Millimetre;
  const double k = o.inch ? 1.0 / kMmPerInch : 1.0;
  const int dec = nc::rotaryLinearDecimals(prog.unit);
  prog.results_file = "rotacal_tooltip";
  prog.point_count = 0;  // no probing: the laser system records the readings
  prog.rotary_axes = {'A', 'B'};
  prog.header = {
      fmt::format("rotacal tooltip cycle [004]: 5-axis, R={:.4f}{}, {}-degree linear interpolation", o.radius_mm * k,
                  o.inch ? " in" : " mm", o.step_deg),
      fmt::format("{} axis steps, tool tip fixed; {}", o.axis,
                  o.sweeps ? fmt::format("dynamic test [004 Sec. VI]: {} sweeps 0 -> +{} -> -{} -> 0 deg", o.sweeps,
                                         o.end_deg, o.end_deg)
                           : fmt::format("static test {} .. {} deg, dwell {} s per reading", o.start_deg, o.end_deg,
                                         o.dwell_s)),
      fmt::format("machine: {}; X Y Z = pivot, origin at its start position [004: Yp = Zp = A = B = 0]", m.name),
      fmt::format("readings: laser system, file angle_deg,{}_um,dz_um{}; stop M0: zero the laser", o.axis == 'A' ? "dy" : "dx",
                  o.repeats > 1 ? fmt::format(", the {} runs one after the other in one file", o.repeats) : std::string()),
  };
  const int pieces = tooltipPiecesPerStep(o);
  if (o.sweeps > 0)
    prog.header.push_back(fmt::format("each {}-degree step in {} moves: the tool tip stays within {:.3f} um of its point, "
                                      "plus the rounding of the printed coordinates",
                                      o.step_deg, pieces, tooltipSagUm(o)));
  const std::string axes = o.axis == 'A' ? "YZ" : "XYZ";
  auto angleOf = [&](const Pose& p) { return o.axis == 'A' ? p.A : p.B; };
  for (int run = 1; run <= o.repeats; ++run) {
    if (o.repeats > 1)
      prog.ops.push_back(commentOp(fmt::format("run {} of {}: the plan again, the laser zeroed anew", run, o.repeats)));
    size_t i = 0;
    while (i < plan.points.size()) {
      const std::string sweep = plan.points[i].pose_name;
      size_t end = i;
      while (end < plan.points.size() && plan.points[end].pose_name == sweep) ++end;
      // Zero pose of the sweep: pivot at the origin, stepping axis at 0.
      const ProbePoint* zero = nullptr;
      for (size_t q = i; q < end && !zero; ++q)
        if (std::abs(angleOf(plan.points[q].pose)) < 1e-9) zero = &plan.points[q];
      if (!zero) throw std::invalid_argument("tooltip program: sweep " + sweep + " has no pose at 0 deg");
      prog.ops.push_back(commentOp(fmt::format("sweep {}: {} axis with the tool tip fixed", sweep, o.axis)));
      nc::Op mode;
      mode.kind = nc::Op::Kind::Mode;
      prog.ops.push_back(mode);  // G90 G94
      nc::Op index;
      index.kind = nc::Op::Kind::Index;
      for (char ax : {'A', 'B'})
        index.rotary.emplace_back(ax, controllerAngle(m, ax, dialect, ax == 'A' ? zero->pose.A : zero->pose.B));
      prog.ops.push_back(index);
      nc::Op rapid;
      rapid.kind = nc::Op::Kind::Rapid;
      rapid.xyz = zero->trigger_m_mm * k;
      prog.ops.push_back(rapid);
      mode.incremental = mode.inverse_time = true;
      mode.feed = 60.0 / o.move_s;
      prog.ops.push_back(mode);  // G91 G93
      nc::Op stop;
      stop.kind = nc::Op::Kind::Pause;
      stop.text = "zero the laser reading, then cycle start";
      prog.ops.push_back(stop);
      // The commanded path from the zero pose: down to the sweep's first pose if it starts below
      // 0 (no readings on the way), then the plan's points in order.
      std::vector<const ProbePoint*> path;
      if (zero != &plan.points[i])
        for (size_t q = static_cast<size_t>(zero - plan.points.data()); q-- > i;) path.push_back(&plan.points[q]);
      const size_t readings_from = path.size();
      for (size_t q = i; q < end; ++q)
        if (!(q == i && zero == &plan.points[i])) path.push_back(&plan.points[q]);
      Eigen::Vector3d prev_pos = zero->trigger_m_mm * k;
      for (int a = 0; a < 3; ++a) prev_pos[a] = roundTo(prev_pos[a], dec);
      double prev_angle = angleOf(zero->pose);
      double prev_piece_angle = prev_angle;
      const Eigen::Vector3d tip = zero->contact_w_mm;  // the fixed tool tip (machine frame)
      for (size_t q = 0; q < path.size(); ++q) {
        const ProbePoint& pt = *path[q];
        // The dynamic test's step in equal moves, each end on the exact pivot circle about the tip
        // (absolute positions and angles rounded, increments their differences: no drift).
        for (int j = 1; j <= pieces; ++j) {
          Pose at = pt.pose;
          // Angles are written with 4 decimals (controllers/program_writing.cpp rotaryLinearWords).
          const double angle = j == pieces ? angleOf(pt.pose)
                                           : roundTo(prev_angle + (angleOf(pt.pose) - prev_angle) * j / pieces, 4);
          (o.axis == 'A' ? at.A : at.B) = angle;
          Eigen::Vector3d pos =
              (j == pieces ? pt.trigger_m_mm : Eigen::Vector3d(tip - tipOffset_m(degToRad(at.A), degToRad(at.B), o.radius_mm))) * k;
          for (int a = 0; a < 3; ++a) pos[a] = roundTo(pos[a], dec);
          nc::Op mv;
          mv.kind = nc::Op::Kind::RotaryLinear;
          mv.axes = axes;
          mv.xyz = pos - prev_pos;
          for (int a = 0; a < 3; ++a) mv.xyz[a] = roundTo(mv.xyz[a], dec);
          const double step = pieces == 1 ? angle - prev_piece_angle : roundTo(angle - prev_piece_angle, 4);
          mv.rotary.emplace_back(o.axis, controllerAngle(m, o.axis, dialect, step));
          mv.feed = 60.0 / o.move_s * pieces;  // inverse time: 1 / minutes of this move
          prog.ops.push_back(mv);
          prev_pos = pos;
          prev_piece_angle = angle;
        }
        if (o.sweeps == 0 && o.dwell_s > 0 && q + 1 > readings_from) {
          nc::Op dwell;
          dwell.kind = nc::Op::Kind::Pause;
          dwell.dwell_s = o.dwell_s;
          prog.ops.push_back(dwell);
        }
        prev_angle = angleOf(pt.pose);
      }
      mode.incremental = mode.inverse_time = false;
      mode.feed = 0.0;
      prog.ops.push_back(mode);  // G90 G94
      i = end;
    }
  }
  return prog;
}

}  // namespace rotacal
