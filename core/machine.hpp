#pragma once
// The immutable description of a machine: kinematic type, strokes, probe, feeds, clearances and
// the artefact on its table (MACHINE.json). Free functions take it by const reference.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/artefact.hpp"
#include "core/error_model.hpp"
#include "core/contributors.hpp"
#include "core/json_io.hpp"
#include "core/verdict.hpp"

namespace rotacal {

enum class LengthUnit { Millimetre, Inch };

struct AxisRange {
  double min = 0.0;
  double max = 0.0;
  bool contains(double v, double tol = 1e-9) const { return v >= min - tol && v <= max + tol; }
};

/// A rotary axis. Strokes in the papers' convention (deg). controller_sign says how the
/// controller counts: commanded controller angle = controller_sign * paper angle. A dialect may
/// override it (e.g. LinuxCNC's xyzac-trt-kins turns the table the other way: -1).
struct RotaryAxis {
  char name = 'C';
  AxisRange stroke_deg{-1e9, 1e9};
  bool continuous = false;
  int controller_sign = 1;
  std::map<std::string, int> dialect_sign;
};

struct ProbeSpec {
  double ball_diameter_mm = 6.0;
  double stylus_length_mm = 50.0;     // ball centre to probe body
  double body_clearance_mm = 5.0;     // body must stay this far above the piece's top in the pose
  int tool_number = 0;                // 0: the controlled point is the ball centre, no G43
  double repeatability_um = 0.7;      // standard uncertainty, one direction (000 Table 5)
  double ball_radius_mm() const { return ball_diameter_mm / 2.0; }
};

struct Feeds {
  double rapid_mm_min = 20000.0;
  double positioning_mm_min = 2000.0;  // G1 moves near the piece
  double probing_mm_min = 100.0;       // guarded move (the first touch of a double touch)
  // Second, slow touch of a double touch (what probing macros do against trigger latency: the
  // controller samples the probe once per servo period, so a trigger is late by up to
  // feed x period). Used only when MachineModel::retract_mm > 0; 0 = single touch.
  double probing_slow_mm_min = 0.0;
  double rotary_deg_min = 3600.0;
};

/// The spindle head of a head_table machine (the axis it tilts about) or of a head_ab machine
/// (an A head carrying a B head: axis 0) or of a head_cb machine (a C head carrying a B head:
/// axis 0), and the nominal distance from its pivot (the
/// intersection of the head axes with the spindle axis) to the probe-ball centre, along the
/// spindle. The machine's X, Y and Z then read the pivot, with no tool length
/// offset: the ball is L from it along the tilted spindle.
struct SpindleHead {
  char axis = 'B';  // head_table: 'B' or 'A'; head_ab, head_cb: 0
  double pivot_to_ball_mm = 0.0;
};

struct MachineModel {
  std::string name;
  std::string description;
  Kinematics kinematics = Kinematics::TableAC;
  LengthUnit units = LengthUnit::Millimetre;
  AxisRange x, y, z;                     // machine frame, origin at the rotary-axis intersection, mm
  std::vector<RotaryAxis> rotary;        // e.g. A then C
  double table_diameter_mm = 500.0;
  /// Height of the table's top in the workpiece frame (mm; MACHINE.json "table_top_z_mm"). Unset:
  /// the artefact's bottom (the column stands on the table), or not known without one.
  std::optional<double> table_top_z_mm;
  ProbeSpec probe;
  Feeds feeds;
  double clearance_mm = 10.0;            // above the artefact for moves between points
  double approach_mm = 5.0;              // start of a probing move, before the nominal trigger
  double overtravel_mm = 2.0;            // end of a probing move, past the nominal trigger
  double retract_mm = 0.0;               // double touch: back-off after the first touch (0 = single touch)
  std::optional<SquareColumn> artefact;
  std::optional<SpindleHead> head;       // head_table and head_cb always, head_ab for a touch probe (MACHINE.json "head")
  /// The Type B contributors the owner declares: inline, or a contributors file named
  /// relative to MACHINE.json. Plans carry them inline. Absent: reports say u_B was not evaluated.
  std::optional<ContributorSet> contributors;
  /// The owner's tolerances on the location errors (MACHINE.json "tolerance": {"length_um",
  /// "angle_mdeg"}): the report's verdict decides against them (core/verdict.hpp).
  LocationTolerance tolerance;

  const RotaryAxis& rotaryAxis(char name) const;  // throws std::invalid_argument
  bool hasRotary(char name) const;
  int controllerSign(char axis, const std::string& dialect) const;
};

/// The probe-ball centre less the X Y Z reading at a pose, nominal, machine frame (mm): zero on a
/// table machine; with a head the ball hangs L from the pivot along the spindle the head turns
/// (by +angle, ISO 841: core/kinematic_model.hpp; head_ab: Rx(A) Ry(B); head_cb: Rz(C) Ry(B)).
Eigen::Vector3d ballFromAxes_m(const MachineModel& m, const Pose& pose);
/// The probe's axis from the ball towards its body, machine frame (unit): +Z on a table machine.
Eigen::Vector3d stylusAxis_m(const MachineModel& m, const Pose& pose);
/// The most the ball can hang below the Z reading at any head angle (mm): L with a head.
double ballDropBelowAxes(const MachineModel& m);

MachineModel machineFromJson(const JsonDoc& doc, const Json& value);
MachineModel loadMachine(const std::string& path);
Json machineToJson(const MachineModel& machine);

}  // namespace rotacal
