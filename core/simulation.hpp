#pragma once
// The exact simulator: what the controller records when the true machine (location errors,
// full HTMs) probes the true test piece (setup + form, planes) with a ball of the probe's
// radius moving along the plan's approach line. No small-angle approximation anywhere.
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "core/artefact.hpp"
#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct Truth {
  LocationErrors errors;
  ArtefactTruth artefact;
  double noise_um = 0.0;          // probe repeatability, standard deviation along the approach
  double pretravel_um = 0.0;      // constant trigger lag along the approach (probe_pretravel)
  double start_time_s = 0.0;      // clock at the cycle start (repeats in time order)
  /// Positioning error of the linear axes: actual ball centre minus the position the controller
  /// reads, as a function of that position (machine frame, mm). Empty: perfect linear axes
  /// (000 Sec. 2.2's assumption). Used by the uncertainty analysis (000 Sec. 5, Eq. (22)-(23)).
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> linear_axis_error;
  /// Thermal drift: change of the location errors (mm / rad) at a time on the common clock (s).
  std::function<ErrorVector(double t_s)> drift;
  /// Direction-dependent pretravel (um) as a function of the approach direction (machine frame),
  /// added to pretravel_um.
  std::function<double(const Eigen::Vector3d& approach_m)> pretravel_by_direction_um;
  /// Position-dependent (component) errors of the rotary axes: change of the location errors
  /// (mm / rad) as a function of the commanded pose (rotary_error_motion).
  std::function<ErrorVector(const Pose& pose)> pose_dependent;
  /// Sphere cycles: true centre minus nominal centre of each sphere (by SphereTarget::id),
  /// workpiece frame, mm. Missing spheres are where the plan says.
  std::map<int, Eigen::Vector3d> sphere_center_error_w_mm;
  /// Sphere cycles: the full true pose of the table (T_m_w at a commanded pose), when the
  /// truth holds more than location errors (component errors of a rotary axis as full
  /// transforms). Empty: T_m_w of the location errors (+ drift, + pose_dependent).
  std::function<Eigen::Isometry3d(const Pose& pose, double t_s)> table_transform;
  /// Lost motion (backlash) of the rotary axes A, B, C, deg: the axis stops short of the commanded
  /// angle by half of it in the direction it last moved, actual = commanded - sign(last move) b / 2.
  /// The last move is read from the plan's order of poses (each probing pose reached straight from
  /// the one before; the program starts at A = B = C = 0, reached in +). Outside every cycle's catalog: the test of
  /// `model_inadequate`.
  Eigen::Vector3d rotary_backlash_deg = Eigen::Vector3d::Zero();
  /// A spindle head: the true probe-ball centre less the X Y Z reading at a pose (machine frame,
  /// mm), the head's exact chain. Empty: the reading is the ball centre (a table machine).
  std::function<Eigen::Vector3d(const Pose& pose, double t_s)> head_ball;
};

/// Distance s (mm) along the approach from the nominal trigger at which the ball of radius r
/// first touches the plane, both in the machine frame: n.(c0 + s u - x) = r.
double ballPlaneContact(const Eigen::Vector3d& c0_m, const Eigen::Vector3d& u_m, double r_mm, const Plane& plane_m);

/// Distance s (mm) along the approach from the nominal trigger at which the ball of radius r
/// first touches the sphere of radius R centred at x (machine frame): the smaller root of
/// |c0 + s u - x| = r + R. Throws std::invalid_argument when the line misses the sphere.
double ballSphereContact(const Eigen::Vector3d& c0_m, const Eigen::Vector3d& u_m, double r_mm,
                         const Eigen::Vector3d& center_m_mm, double R_mm);

/// The true face plane of a point in the machine frame at its pose.
Plane truePlane_m(const ProbePlan& plan, const ProbePoint& point, const Truth& truth);

struct SimulationOptions {
  std::uint64_t seed = 1;
};

/// Simulated triggers for every plan point. Throws std::runtime_error naming the point when the
/// probe would not trigger within [-approach_mm, +overtravel_mm] (the program would alarm).
MeasurementRun simulate(const ProbePlan& plan, const Truth& truth, const SimulationOptions& options);

struct KinematicModel;
/// A truth whose table and head are a kinematic model's exact chains at parameters p (mm, rad):
/// table_transform and head_ball set, nothing else.
Truth truthOfModel(const KinematicModel& model, const Eigen::VectorXd& p);

/// Whether the truth's location errors are all its table carries: no drift, no pose-dependent
/// (component) errors, no full table transform. Only then is `errors` what a fit of the location
/// errors should find.
inline bool locationErrorsAreConstant(const Truth& t) { return !t.drift && !t.pose_dependent && !t.table_transform; }

Truth truthFromJson(const JsonDoc& doc, Kinematics kinematics);
/// The truth of a machine: for head_table, head_cb (and head_ab with a "head") its "location_errors" are
/// the ISO 230-7 parameters of core/kinematic_model.hpp (X0C .. dL, Y0A .. dL), which set
/// table_transform and head_ball exactly.
Truth truthFromJson(const JsonDoc& doc, const MachineModel& machine);
Truth loadTruth(const std::string& path, Kinematics kinematics);
Json truthToJson(const Truth& truth);

}  // namespace rotacal
