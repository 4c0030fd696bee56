#pragma once
// The contributors to the uncertainty of the identified location errors (000 Sec. 5, Table 5),
// each with its standard uncertainty (k = 1, normal distribution), and the file that lists them
// (CONTRIB.json, "rotacal-contributors/1").
//
// Ids follow 000 Table 5 (contract.md): probe_repeatability, probe_pretravel, E_xx_lin,
// E_xx_rand, E_yx_rand, E_zx_rand, E_yy_lin, E_yy_rand, E_xy_rand, E_zy_rand, S_xy, E_zz_lin,
// E_zz_rand, E_xz_rand, E_yz_rand, S_xz, S_yz, setup_position, setup_orientation,
// surface_roughness; and form_error (the test piece's own form, which 000 leaves out).
// The R-test device's own (002; touch probing ignores them): rtest_sensor_gain,
// rtest_sensor_direction, rtest_sphere_form, rtest_sphere_offset, rtest_cycle_drift. The R-test
// analysis also reads the linear-axis ids above (002 Sec. 4.3: the device cannot separate them).
// E_ba_* is the error in direction b of the motion of axis a (ISO 230-1 naming); the linear-axis
// model is core/linear_axes.hpp.
//
// How each enters a run (per run, drawn anew; "per touch" = independently at every trigger):
//   probe_repeatability  per touch, along the approach
//   probe_pretravel      per probing direction (+X -X +Y -Y +Z -Z of the machine), along the approach
//   E_aa_lin, E_ba_rand, S_..   the linear-axis model (000 Eq. (22)-(23))
//   setup_position       translation of the piece [x, y, z]
//   setup_orientation    rotation of the piece about X, Y, Z (about its top centre)
//   surface_roughness    per touch, height of the surface under the ball along its normal
//   form_error           per face: offset along the normal, and tilts about its two in-plane axes
//   rtest_sensor_gain    per sensor (X, Y, Z of the nest), per run: reading scaled by 1 + g (ratio)
//   rtest_sensor_direction  per sensor pair, per run: the sensor's direction calibrated wrong, so
//                        each reading picks up the other two displacements times d (rad)
//   rtest_sphere_form    per reading and sensor: the sphere's form at the contact point (Type A)
//   rtest_sphere_offset  the sphere centre off its calibrated place on the spindle [x, y, z],
//                        machine frame (runout, tool length), per run
//   rtest_cycle_drift    thermal drift of the sphere against the table over one measuring cycle
//                        [x, y, z] (its start to its end, linear in time), machine frame, per run
// A laser reading a target sphere (004 Sec. VII; the tool-tip cycle):
//   laser_resolution     per reading and read direction: the laser system's own error (Type A)
//   laser_alignment      per read direction, per run: the beam tilted off its nominal direction by
//                        a drawn angle in the read plane and one out of it (rad): the cosine error
//                        of the reading and the cross-talk of the other components
//   laser_sphere_form    per reading: the target sphere's form where the beam meets it (the sphere
//                        turns with the head, so every reading sees another spot; Type A)
//   laser_lateral_coupling  per reading: the sphere moving across the beam changes the path by
//                        the sagitta d^2 / (2 r) (004: 0.000070 in at 0.010 in lateral; Type A)
#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/linear_axes.hpp"

namespace rotacal {

enum class ContributorKind {
  ProbeRepeatability,
  ProbePretravel,
  LinearScale,      // E_aa_lin
  LinearRandom,     // E_ba_rand
  Squareness,       // S_xy S_xz S_yz
  SetupPosition,
  SetupOrientation,
  SurfaceRoughness,
  FormError,
  RtestSensorGain,
  RtestSensorDirection,
  RtestSphereForm,
  RtestSphereOffset,
  RtestCycleDrift,
  LaserResolution,
  LaserAlignment,
  LaserSphereForm,
  LaserLateralCoupling,
};

/// What a contributor id means: its kind and, for the linear axes, the moving axis and the
/// direction of the error (0 = X, 1 = Y, 2 = Z).
struct ContributorInfo {
  std::string_view id;
  ContributorKind kind;
  int axis = -1;
  int direction = -1;
  std::string_view description;
};

/// Every known contributor, in the order of 000 Table 5 (then form_error).
const std::vector<ContributorInfo>& contributorCatalog();
const ContributorInfo* findContributor(std::string_view id);  // nullptr when unknown

struct Contributor {
  const ContributorInfo* info = nullptr;
  /// Standard uncertainty, internal units: mm (lengths), mm/mm (slopes), rad (angles). Scalar
  /// contributors use u[0]; setup_*, rtest_sphere_offset and rtest_cycle_drift use [x, y, z];
  /// form_error uses [offset mm, tilt rad, -].
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  std::string unit;  // as written in the file, for the echo in reports
  std::string note;
};

/// Reference figures to compare with (e.g. 000 Table 6 and Table 5's right-hand columns), in
/// report units (um, mdeg). Optional; never used in a computation other than a comparison or
/// the weights of a plan design.
struct ReferenceUncertainty {
  std::string source;
  std::map<std::string, double> combined;                               // parameter -> u
  std::map<std::string, std::map<std::string, double>> contributors;    // contributor -> parameter -> u
};

struct ContributorSet {
  std::string file;  // where it came from, for messages
  std::string description;
  std::vector<Contributor> items;  // in catalog order
  double node_spacing_min_mm = 20.0, node_spacing_max_mm = 50.0;  // 000 Eq. (22): p_rand
  std::optional<ReferenceUncertainty> reference;

  const Contributor* find(std::string_view id) const;
  /// The linear-axis part, for core/linear_axes.hpp.
  LinearAxisModel linearAxisModel() const;
  bool validate(std::string* why) const;
};

/// Units accepted, with their factor to internal units:
///   Length  um, mm                                                    -> mm
///   Ratio   um/m (= ppm), ppm, um/100mm, um/mm, mm/m, urad, mrad, mdeg  -> mm/mm or rad
/// (slopes and small angles are the same quantity: 3 um/100mm = 30 urad). Returns false when the
/// unit is not one of its class.
enum class Quantity { Length, Ratio };
bool unitFactor(Quantity quantity, std::string_view unit, double* factor);

ContributorSet contributorsFromJson(const JsonDoc& doc);
/// The same from an object inside another document (MACHINE.json's inline `contributors`).
ContributorSet contributorsFromJsonValue(const JsonDoc& doc, const Json& value);
ContributorSet loadContributors(const std::string& path);
Json contributorsToJson(const ContributorSet& set);

}  // namespace rotacal
