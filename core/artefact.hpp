#pragma once
// The square-column test piece of 000 Sec. 4.1, its faces as planes in the workpiece frame, and
// the ways a real piece differs from the nominal one: setup (position/orientation on the table)
// and form (each face's own offset and tilt, e.g. sides out of square, a tilted top).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string_view>

namespace rotacal {

enum class Face { PosX, PosY, NegX, NegY, Top };
constexpr std::array<Face, 5> kAllFaces = {Face::PosX, Face::PosY, Face::NegX, Face::NegY, Face::Top};

std::string_view faceName(Face face);            // "+X" "+Y" "-X" "-Y" "top"
Face faceFromName(std::string_view name);        // throws std::invalid_argument
Eigen::Vector3d faceNormal_w(Face face);         // nominal outward normal, workpiece frame
/// Two in-plane unit axes (u, v) of a face; the form tilts turn the normal about them.
std::array<Eigen::Vector3d, 2> faceAxes_w(Face face);

struct Plane {
  Eigen::Vector3d point;
  Eigen::Vector3d normal;  // unit, outward
};

/// Nominal square column: top-face centre and full size in the workpiece frame, mm.
struct SquareColumn {
  Eigen::Vector3d top_centre_w = Eigen::Vector3d(0, -200, 170);
  Eigen::Vector3d size_mm = Eigen::Vector3d(100, 100, 150);

  Plane nominalFace(Face face) const;
  /// Corners of the column, workpiece frame (for reach and clearance checks).
  std::array<Eigen::Vector3d, 8> corners_w() const;
};

/// Rigid setup error of the piece on the table: rotation (rad, X then Y then Z, exact) about the
/// nominal top centre, then translation (mm), both in the workpiece frame.
struct SetupError {
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();

  Eigen::Isometry3d transform(const Eigen::Vector3d& pivot_w) const;
};

/// Form error of one face: offset along the outward normal (mm) and tilts of the normal about
/// the face's in-plane axes u and v (rad, exact rotations).
struct FaceForm {
  double offset_mm = 0.0;
  double tilt_u_rad = 0.0;
  double tilt_v_rad = 0.0;
};

/// The real piece: nominal column + form per face + setup.
struct ArtefactTruth {
  SetupError setup;
  std::array<FaceForm, 5> form{};  // indexed by Face

  Plane face(const SquareColumn& nominal, Face face) const;
};

}  // namespace rotacal
