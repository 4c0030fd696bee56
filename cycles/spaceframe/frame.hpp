#pragma once
// The 7-sphere space frame of 003 (de Aquino Silva): the sphere coordinates of 003 Table 1, the
// rotation/tilt map of 003 Sec. 3.1 and the length errors of 003 Eq. (2)-(5).
//
// 003 prints [RotTilt] with -cos(phi) in its (3,3) entry: that matrix has determinant -1 (a
// mirror) and does not give back Table 1 at theta = phi = 0, which 003 says it must. The map
// here is the rotation that does: RotTilt = D_c(-theta) D_a(-phi) (the printed matrix with
// +cos(phi) in (3,3)).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rotacal {

/// 003 Table 1: nominal sphere centres at theta = phi = 0, frame coordinates, mm (spheres 1..7).
const std::array<Eigen::Vector3d, 7>& spaceFrameTable1_mm();

/// The frame as calibrated by its owner (a CMM report): the seven sphere centres in frame
/// coordinates (those of 003 Table 1: origin, axes), mm, their standard uncertainty per
/// coordinate (um, k = 1) and where they come from. FRAME.json, "rotacal-frame/1":
///   {"format": "rotacal-frame/1", "source": "CMM report 4711, 2026-10-02, 20.0 C",
///    "u_um": 1.0, "spheres_mm": {"1": [x, y, z], ..., "7": [x, y, z]}}
/// The default is 003 Table 1 taken as exact (u 0): 003's own frame, not the user's.
struct FrameCalibration {
  std::array<Eigen::Vector3d, 7> spheres_mm = spaceFrameTable1_mm();
  double u_um = 0.0;
  std::string source = "003 Table 1 (taken as exact)";
};
/// Throws InputError naming the file and line of what is wrong.
FrameCalibration loadFrameCalibration(const std::string& path);

/// 003's [RotTilt] (corrected, see above): frame point at (theta, phi) = RotTilt * point at (0, 0).
Eigen::Matrix3d rotTilt003(double theta_rad, double phi_rad);

/// 003 Eq. (5): number of lengths between n_p points, n_p! / ((n_p - 2)! 2!).
std::uint64_t lengthCount(std::uint64_t n_points);

/// One length of 003 Eq. (2)-(4): between points j < k (0-based).
struct LengthError {
  int j = 0;
  int k = 0;
  double nominal_mm = 0.0;   // L_n, Eq. (4)
  double measured_mm = 0.0;  // L_m, Eq. (3)
  double u_um = 0.0;         // standard uncertainty of dL (k = 1); 0 when not evaluated
  double dL_mm() const { return measured_mm - nominal_mm; }  // Eq. (2)
};

/// Every length between the points (003's j, k loops): n (n - 1) / 2 entries, j < k.
std::vector<LengthError> lengthErrors(const std::vector<Eigen::Vector3d>& measured_mm,
                                      const std::vector<Eigen::Vector3d>& nominal_mm);

/// The length-measurement specification of 003 Sec. 4 (BS 6808-2): U = +-(A + K L).
struct LengthSpec {
  double A_um = 5.0;
  double K_um_per_m = 10.0;
  double limit_um(double L_mm) const { return A_um + K_um_per_m * L_mm * 1e-3; }
};

/// ISO 14253-1's decision with the measurement's expanded uncertainty U = k u of each dL:
/// conformance is proven where |dL| <= MPE - U, non-conformance where |dL| > MPE + U; between the
/// two the measurement cannot decide.
enum class LengthDecision { Pass, Fail, Inconclusive };
std::string_view lengthDecisionName(LengthDecision d);  // "pass", "fail", "inconclusive"

struct LengthVerdict {
  bool pass = true;            // decision == Pass
  LengthDecision decision = LengthDecision::Pass;
  int lengths = 0;
  int outside = 0;             // |dL| > A + K L (the verdict without the uncertainty)
  int conforming = 0;          // |dL| <= A + K L - U
  int nonconforming = 0;       // |dL| > A + K L + U
  int undecided = 0;           // the rest: inside the guard bands
  double max_U_um = 0.0;       // largest expanded uncertainty of a dL
  double max_abs_dL_um = 0.0;
  double rms_dL_um = 0.0;
  double worst_ratio = 0.0;    // max |dL| / (A + K L): <= 1 passes
  int worst_index = -1;        // into the lengths
};

/// Checks every |dL| against A + K L, with L the measured length (003 Fig. 6 plots dL against
/// the measured distances), and decides by ISO 14253-1 with U = k u_um of each length: Pass when
/// every length conforms, Fail when any does not conform, Inconclusive otherwise.
LengthVerdict checkLengths(const std::vector<LengthError>& lengths, const LengthSpec& spec, double k = 2.0);

}  // namespace rotacal
