#pragma once
// The static R-test cycle of 002 (Hong, Ibaraki): a sphere on the spindle sits in a nest of three
// displacement sensors on the table; at each index pose (tilt B_i*, C_j*) the linear axes put
// the sphere where the nest nominally is, and the sensors read the sphere-centre displacement
// in the workpiece frame, relative to the initial reset at B = C = 0 (002 Eq. (4)).
// This header: the plan (poses, nest, thermal schedule), the exact model of a reading, and the
// simulator. Identification: cycles/rtest/analyze.hpp.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"

namespace rotacal {

/// The six position-dependent errors of 002 Table 2, as indices into the location-error vector:
/// B/C: dx_BY dy_CB dz_BY a_BY b_BY c_BY; A/C (the same errors of the A axis, 000 Eq. (1)):
/// dx_AY dy_AY dz_AY a_AY b_AY c_AY.
constexpr int kRtestParams = 6;
const std::array<int, kRtestParams>& rtestParameterIndices(Kinematics kinematics);
std::string rtestParameterName(Kinematics kinematics, int p);  // p in 0..5
bool rtestParameterIsLength(int p);                             // p < 3

char tiltAxis(Kinematics kinematics);  // 'B' (table_bc) or 'A' (table_ac)
double tiltOf(Kinematics kinematics, const Pose& pose);
Pose tiltPose(Kinematics kinematics, double tilt_deg, double c_deg);

/// The thermal test schedule of 002 Sec. 2.3 / 4.1: the tilt axis reciprocates between two
/// angles, and every interval the measuring cycle runs, for a total duration.
struct RtestSchedule {
  bool thermal = false;
  double interval_s = 900.0;           // 002: every 15 min
  double duration_s = 3.0 * 3600.0;    // 002: about 3 h
  double recip_from_deg = -90.0;       // 002: B between -90 and -60 deg
  double recip_to_deg = -60.0;
  double recip_feed_deg_min = 5000.0;  // 002: 5000 deg/min
  int cycles() const;                  // measuring cycles: 1, or duration / interval + 1
  double strokeTime_s() const;         // one way
};

/// Options (`--set`): b_list (a_list on an A/C table), c_list, nest_w_mm, dwell_s, retract_mm,
/// thermal (0|1), interval_min, duration_h, recip_list, recip_feed_deg_min, sensor_noise_um,
/// reset_reads (0|1, default 1: the reset pose is read before the first pose of every cycle and
/// re-read at its end; plans written before it lack the option and read as 0).
ProbePlan makeRtestPlan(const MachineModel& machine, const CycleOptions& options);
RtestSchedule rtestSchedule(const ProbePlan& plan);
/// The options a loaded plan's simulation and analysis read back (schedule, retract, dwell,
/// sensor noise), checked as `plan` checks them; throws std::invalid_argument naming the option.
void rtestCheckPlanOptions(const ProbePlan& plan);
Eigen::Vector3d rtestNest_w(const ProbePlan& plan);          // nominal sphere centre in the nest, workpiece frame, mm
double rtestCycleTime_s(const ProbePlan& plan);              // one measuring cycle, from its first index to its end
int rtestReciprocations(const ProbePlan& plan);              // round trips between two cycles
int rtestReferencePoint(const ProbePlan& plan);              // the plan point at tilt 0, C 0 (the reset pose)
bool rtestResetReads(const ProbePlan& plan);                 // the plan reads the reset before and after every cycle
/// Planned time of every reading of one cycle from its start, in reading order: with reset reads
/// the reset, the poses, the re-read (poses + 2), else the poses.
std::vector<double> rtestReadTimes(const ProbePlan& plan);

/// The moves of one measuring cycle (shared by the time estimate, the program and the stroke
/// check). Between poses the sphere withdraws along the nest axis by retract_mm, climbs to the
/// index height, the table indexes, and the sphere enters the next pose's nest position along
/// its axis (the program runs in joint kinematics: a joint-space move with the sphere in the
/// nest would drag it through the sensors).
/// The path of one measuring cycle in the one move model (Waypoint: Dwell and Read where the
/// sphere sits in the nest; Read's point_id 0 is the reset pose's reading).
std::vector<Waypoint> rtestCycleMoves(const ProbePlan& plan);
std::vector<std::string> rtestStrokeViolations(const ProbePlan& plan);

/// One sensor reading (contract: `pose,t_s,B_deg,C_deg,dx_um,dy_um,dz_um`).
struct RtestReading {
  int pose_id = 0;
  double t_s = 0.0;
  double tilt_deg = 0.0;
  double c_deg = 0.0;
  Eigen::Vector3d dq_w_mm = Eigen::Vector3d::Zero();  // 002 Eq. (4): wq(B,C,t) - wq(0,0,t_reset)
};
struct RtestCycle {
  std::vector<RtestReading> readings;  // one per plan point, in plan order
  /// The reset pose (tilt 0, C 0) read before the first pose and again after the last (pose id 0
  /// in the results; sensor counts like every reading). Absent in results written before the
  /// plans read them: the reset cannot be checked then.
  std::optional<RtestReading> reset, reread;
  double t_s() const;                  // mean time of the poses' readings
};
struct RtestSeries {
  std::string source;
  std::vector<RtestCycle> cycles;  // in time order; the reset happened before the first
};

/// What the simulator puts on the machine beyond Truth: the commanded sphere position is off by
/// sphere_offset_m_mm (a tool-length error is its Z, 002 Sec. 4.3).
/// A step of the sensors' zero (a knock, a lost count): every reading from t_s on (common clock)
/// is off by offset_w_mm (workpiece frame, where the sensors sit).
struct RtestSensorStep {
  double t_s = 0.0;
  Eigen::Vector3d offset_w_mm = Eigen::Vector3d::Zero();
};

struct RtestTruthExtras {
  std::vector<RtestSensorStep> sensor_steps;
  Eigen::Vector3d sphere_offset_m_mm = Eigen::Vector3d::Zero();
  /// Time-dependent part of the sphere offset (e.g. the spindle's axial thermal growth: +Z),
  /// machine frame, mm, at a time on the common clock (s). Empty: none.
  std::function<Eigen::Vector3d(double t_s)> sphere_drift_m_mm;
  /// The sensors' actual response: reading = sensor_response x (sphere displacement since the
  /// zero), workpiece frame. Its diagonal is 1 + the gain errors, the rest the cross-talk of
  /// sensor directions calibrated wrong (rtest_sensor_gain, rtest_sensor_direction). Identity:
  /// perfect sensors.
  Eigen::Matrix3d sensor_response = Eigen::Matrix3d::Identity();
};

/// Exact sphere centre in the workpiece frame at a pose and time (002 Eq. (1)-(3)): the true
/// table transform carries truth.errors + pose_dependent(pose) + drift(t); the sphere is where
/// the linear axes put it: the commanded position + the sphere offset (+ drift) + the linear
/// axes' error at the commanded position (truth.linear_axis_error, when set).
Eigen::Vector3d rtestSphere_w(const ProbePlan& plan, const Truth& truth, const RtestTruthExtras& extras,
                              const Pose& pose, double t_s);

struct RtestSimOptions {
  std::uint64_t seed = 1;
  double noise_um = 0.0;   // sensor noise, standard deviation per axis
  double start_s = 0.0;    // clock at the reset
  int cycles = 0;          // 0: the schedule's count
};
/// The readings of the whole series (every cycle of the schedule), cycle k starting at
/// start_s + k x interval; the sensors are zeroed at the first cycle's reset reading at tilt 0,
/// C 0 (the operator's initial reset), so that reading is 0 plus noise; later readings are the
/// sensors' counts since (plus any sensor step of the truth). With reset reads every cycle also
/// carries its reset and re-read.
RtestSeries simulateRtest(const ProbePlan& plan, const Truth& truth, const RtestTruthExtras& extras,
                          const RtestSimOptions& options);

/// Truth file extras for the R-test: "component_errors" (position-dependent errors as tables in
/// the tilt angle, linearly interpolated) and "rtest": {"tool_length_error_um": ...,
/// "sensor_steps": [{"t_s": 5460, "offset_um": [1, 0, 0]}, ...]} (docs/rtest.md).
/// {"component_errors": {"B_deg": [-60, 0, 60], "dx_BY": {"unit": "um", "values": [1, 0, -1]}, ...}}
void rtestTruthFromJson(const JsonDoc& doc, Kinematics kinematics, Truth& truth, RtestTruthExtras& extras);

/// Results CSV (neutral, every dialect: the R-test device's logger writes it, not the control).
/// The reset and re-read rows have pose 0. Files without them (written before) are read: their
/// cycles have no reset / reread.
std::string rtestResultsCsv(const ProbePlan& plan, const RtestSeries& series);
RtestSeries parseRtestResults(const std::string& text, const std::string& file, const ProbePlan& plan);

/// What a PLAN.json of this cycle must satisfy beyond the format (the cycle's identity).
PlanRules rtestPlanRules();

}  // namespace rotacal
