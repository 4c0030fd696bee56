#pragma once
// What the three-sphere model gets wrong (issues 6 and 16), decided by the one judge
// (core/judge.hpp, rules in docs/diagnosis.md "The judge"):
//  - baseline: the C axis's location errors Oxc Oyc Sxc Syc + the three sphere positions (13
//    parameters; `identifySpheres3` with ComponentModel::None), linearised at its solution:
//    y = the sphere centres' residuals (um, 3 per centre), J0 = d(centre)/d(parameter) of the
//    exact model by central differences;
//  - sigma = the DECLARED probe repeatability (MACHINE.json) carried to each centre coordinate by
//    the sphere fit's own (J^T J)^-1 (5 touches, radius fitted: about 0.71 sigma in X and Y,
//    1.12 sigma in Z), never the fit's own noise: an unmodelled effect then shows as a misfit;
//    the centre covariance's off-diagonal terms are dropped (zero for the +-X, +-Y, -Z layout);
//  - catalog (each family tested jointly): the C axis's component errors as harmonics of C up to
//    `max_harmonic` (radial EXC/EYC, axial EZC, tilt EAC/EBC, angular ECC; the same identifiable
//    terms as the analysis model), linear-axis scale (X Y Z) and squareness (S_xy S_xz S_yz), and
//    thermal drift of the table's position (X Y Z per hour) when there are repeats with a clock;
//  - groups = C angles (leave one angle out, every sphere and repeat at it); factors = C angle,
//    sphere, coordinate, repeat, time;
//  - confounding comes from the Jacobians on this plan (the judge's principal angles), never a
//    list: e.g. a Z scale moves every sphere by a constant -s z_i, exactly a sphere position.
#include <string>
#include <vector>

#include "core/judge.hpp"
#include "cycles/spheres3/analyze.hpp"

namespace rotacal {

struct Spheres3DiagnosisOptions {
  JudgeOptions judge;     // alpha from the CLI's --alpha
  double sigma_um = 0.7;  // declared probe repeatability (MACHINE.json), k = 1
  /// Highest harmonic of C in the error-motion families. 3: an oval (2C) or trefoil (3C)
  /// bearing and a wobble (1C); higher orders are left to the adequacy test (model_inadequate).
  int max_harmonic = 3;
  /// The declared noise of the touches (spheres3DeclaredNoise, the machine's contributors): the
  /// judge then reads the centres' full declared covariance, each sphere fit's linear map of its
  /// touches' covariance (white and shared), in place of sigma_um. Null: sigma_um alone.
  const Spheres3Noise* noise = nullptr;

  bool validate(std::string* why) const;
};

/// Judge cause names, in catalog order (the ones a plan supports are used).
inline constexpr const char* kSpheres3Radial = "rotary_error_motion_radial";
inline constexpr const char* kSpheres3Axial = "rotary_error_motion_axial";
inline constexpr const char* kSpheres3Tilt = "rotary_error_motion_tilt";
inline constexpr const char* kSpheres3Angular = "rotary_error_motion_angular";
inline constexpr const char* kSpheres3Scale = "linear_axis_scale";
inline constexpr const char* kSpheres3Squareness = "linear_axis_squareness";
inline constexpr const char* kSpheres3Drift = "thermal_drift";

struct Spheres3Diagnosis {
  Spheres3Result baseline;  // location errors + sphere positions, no error motion
  JudgeProblem problem;     // what the judge saw
  JudgeSummary judged;
};

/// The judge's problem for a baseline fit (exposed for the tests). `runs` gives the trigger
/// times (thermal drift is a candidate only with more than one run and a clock).
JudgeProblem spheres3JudgeProblem(const Spheres3Result& baseline, const std::vector<MeasurementRun>& runs,
                                  const Spheres3DiagnosisOptions& options);

/// Throws std::invalid_argument for invalid options or unusable data (as identifySpheres3).
Spheres3Diagnosis diagnoseSpheres3(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                   const Spheres3DiagnosisOptions& options);

Json spheres3DiagnosisJson(const Spheres3Diagnosis& d);
std::string spheres3DiagnosisText(const Spheres3Diagnosis& d);

}  // namespace rotacal
