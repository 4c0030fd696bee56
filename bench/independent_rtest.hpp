#pragma once
// The independent generator's R-test (002, Hong and Ibaraki): a B/C tilting table carrying a nest
// of three displacement sensors, a sphere on the spindle, written from 002 and the contributors
// file alone (not from core/simulation, core/contributor_draw, core/linear_axes, cycles/rtest's
// simulator or any budget). It uses rotacal's plan, machine and contributors-file types, the
// names of the location errors, the plan's schedule (rtestReadTimes, rtestSchedule: when each
// reading is taken) and the cycle's results type and writer (what `simulate` writes).
//
// One machine:
//   - the table of 002 Eq. (2) as exact 4x4 products, rT_w = rT_b bT_c,
//     rT_b = Da(a_BY) Db(b_BY) Dc(c_BY) Dx(dx_BY) Dy(dy_CB) Dz(dz_BY) Db(-B),
//     bT_c = Da(a_CB) Dx(dx_CB) Dc(-C), with its eight location errors drawn normally;
//   - the commanded sphere centre of 002 Eq. (3), rq = Db(-B) Dc(-C) wq* (wq* the nest);
//   - the sphere where the machine puts it: rq + its offset on the spindle (rtest_sphere_offset,
//     machine frame) + its drift against the table (rtest_cycle_drift over one measuring cycle,
//     linear in time from the series' start, machine frame) + the linear axes' error at rq (000
//     Eq. (22)-(23), bench/independent_machine.hpp's LinearAxes, drawn the same way);
//   - 002 Eq. (1): its centre in the workpiece frame wq = (rT_w)^-1 [sphere; 1];
//   - the three sensors of the nest, each a flat-ended plunger along its own direction n_i (the
//     workpiece frame's axis i tilted towards the other two by the drawn direction errors,
//     rtest_sensor_direction, exact unit vector) with its gain 1 + g_i (rtest_sensor_gain): a flat
//     face on a sphere moves with the centre's displacement along its axis, so sensor i reads
//     (1 + g_i) n_i . (wq - wq_zero) exactly;
//   - zeroed at the first cycle's reset reading (tilt 0, C 0: 002 Eq. (4)); the reset and its
//     re-read are read in every cycle where the plan says so (reset_reads);
//   - per reading and sensor the sensor's own scatter (the plan's sensor_noise_um) and the
//     sphere's form at the contact (rtest_sphere_form), both normal, drawn anew.
// Internal units mm and rad.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "bench/independent_machine.hpp"
#include "core/contributors.hpp"
#include "core/error_model.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "cycles/rtest/plan.hpp"

namespace rotacal::independent {

/// 002 Eq. (2): the workpiece (table) frame in the reference frame at the commanded B and C (deg),
/// with the B/C table's eight location errors (mm, rad; core/error_model.hpp's names).
Eigen::Matrix4d tableTransformBC(const LocationErrors& errors, double B_deg, double C_deg);

/// One drawn R-test machine.
struct RtestMachine {
  LocationErrors location;  // table_bc, mm and rad
  Eigen::Vector3d sphere_offset_mm = Eigen::Vector3d::Zero();  // machine frame
  Eigen::Vector3d drift_mm_per_s = Eigen::Vector3d::Zero();    // the sphere against the table, machine frame
  bool has_linear_axes = false;
  LinearAxes axes;
  std::array<double, 3> gain{};  // g_x g_y g_z (ratio)
  /// Direction errors (rad): sensor i tilted towards axis j, in the order xy xz yx yz zx zy.
  std::array<double, 6> direction{};
  double sensor_noise_mm = 0.0, sphere_form_mm = 0.0;  // per reading and sensor, k = 1
  std::uint64_t reading_seed = 0;

  /// Sensor i's unit direction in the workpiece frame.
  Eigen::Vector3d sensorDirection(int i) const;
  /// Rows (1 + g_i) n_i^T: what the three sensors read of a displacement.
  Eigen::Matrix3d response() const;
};

/// What to draw, and around what.
struct RtestDrawOptions {
  /// The centre of the location errors (um / mdeg, core/error_model.hpp's B/C order dx_BY dy_CB
  /// dz_BY a_BY b_BY c_BY a_CB dx_CB): the bundled example's truth (examples/truth/bc_location.json:
  /// several um, a few tens of mdeg; 002 gives its B axis's errors as curves, Fig. 10).
  std::array<double, 8> centre{12.4, -8.6, -15.3, 24.0, -31.0, 18.0, -27.0, 9.7};
  /// The spread around it (k = 1), as the A/C generator's.
  double sd_um = 5.0;
  double sd_mdeg = 0.5;
  // Each contributor can be switched off (every other draw stays as it was).
  bool linear_axes = true, sphere = true, sensors = true, drift = true, noise = true, form = true;
};

/// Draws one R-test machine from the contributors (their declared u, k = 1, normal) with its own
/// seed; the sensors' own scatter is the plan's sensor_noise_um (default 0.2 um, 002 Table 1).
RtestMachine drawRtestMachine(const ContributorSet& contributors, const ProbePlan& plan, const RtestDrawOptions& options,
                              std::uint64_t seed);

/// A machine with the given location errors and nothing else (the cross-check's clean machine).
RtestMachine cleanRtestMachine(const LocationErrors& errors);

/// A gross reading: the value of one sensor (axis 0 x, 1 y, 2 z) at one pose (plan point id) of
/// one cycle (0-based) off by `mm`.
struct RtestChip {
  int cycle = 0;
  int pose_id = 0;
  int axis = 0;
  double mm = 0.0;
};

/// The readings of the plan's whole series (each cycle k starting at k x the schedule's interval;
/// within a cycle the plan's reading times), as rotacal's results type carries them. The
/// per-reading draws come from the machine's reading_seed in reading order (two per sensor per
/// reading whatever is declared), so a chip or a switched-off term changes no other draw.
RtestSeries measureRtest(const ProbePlan& plan, const RtestMachine& m, const std::optional<RtestChip>& chip = std::nullopt);

/// The per-tilt errors of 002 Table 2 the analysis reports (report units um / mdeg, order dx_BY
/// dy_CB dz_BY a_BY b_BY c_BY), of the machine's own table: at each tilt B the exact pose of the
/// C axis average line, rT_b bT_c at C = 0 written as Da(a) Db(b) Dc(c) Dx(dx) Dy(dy) Dz(dz) Db(-B)
/// (rotation decomposed X-Y-Z, translation in the rotated frame), then put in the analysis'
/// convention: the reset cannot see dz and c at tilt 0 (docs/rtest.md), so their values e0, c0 are
/// moved out, to first order, along the C axis at each tilt a(B) = Db(-B) z = (-sin B, 0, cos B):
/// t(B) - e0 a(B), rotation(B) - c0 a(B). The sphere's offset, the linear axes, the sensors and
/// the drift are not the table's: the analysis' u_B carries them.
struct PerTiltTruth {
  std::vector<double> tilt_deg;
  std::vector<std::array<double, 6>> value;  // per tilt
};
PerTiltTruth perTiltTruth(const ProbePlan& plan, const RtestMachine& m);

}  // namespace rotacal::independent
