#include "core/artefact.hpp"

#include <stdexcept>
#include <string>

namespace rotacal {

std::string_view faceName(Face face) {
  switch (face) {
    case Face::PosX: return "+X";
    case Face::PosY: return "+Y";
    case Face::NegX: return "-X";
    case Face::NegY: return "-Y";
    case Face::Top: return "top";
  }
  return "?";
}

Face faceFromName(std::string_view name) {
  for (Face f : kAllFaces)
    if (faceName(f) == name) return f;
  throw std::invalid_argument("unknown face '" + std::string(name) + "' (expected +X +Y -X -Y top)");
}

Eigen::Vector3d faceNormal_w(Face face) {
  switch (face) {
    case Face::PosX: return Eigen::Vector3d::UnitX();
    case Face::PosY: return Eigen::Vector3d::UnitY();
    case Face::NegX: return -Eigen::Vector3d::UnitX();
    case Face::NegY: return -Eigen::Vector3d::UnitY();
    case Face::Top: return Eigen::Vector3d::UnitZ();
  }
  return Eigen::Vector3d::UnitZ();
}

std::array<Eigen::Vector3d, 2> faceAxes_w(Face face) {
  switch (face) {
    case Face::PosX:
    case Face::NegX: return {Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
    case Face::PosY:
    case Face::NegY: return {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ()};
    case Face::Top: return {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
  }
  return {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
}

Plane SquareColumn::nominalFace(Face face) const {
  const Eigen::Vector3d n = faceNormal_w(face);
  const Eigen::Vector3d centre = top_centre_w - Eigen::Vector3d(0, 0, size_mm.z() / 2);
  Plane p;
  p.normal = n;
  p.point = centre + 0.5 * n.cwiseProduct(size_mm);
  return p;
}

std::array<Eigen::Vector3d, 8> SquareColumn::corners_w() const {
  std::array<Eigen::Vector3d, 8> c;
  int i = 0;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      for (int sz : {0, 1})
        c[i++] = top_centre_w + Eigen::Vector3d(sx * size_mm.x() / 2, sy * size_mm.y() / 2,
                                                 sz == 1 ? 0.0 : -size_mm.z());
  return c;
}

Eigen::Isometry3d SetupError::transform(const Eigen::Vector3d& pivot_w) const {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(rotation_rad.z(), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(rotation_rad.y(), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(rotation_rad.x(), Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = pivot_w - R * pivot_w + translation_mm;
  return T;
}

Plane ArtefactTruth::face(const SquareColumn& nominal, Face f) const {
  Plane p = nominal.nominalFace(f);
  const FaceForm& ff = form[static_cast<size_t>(f)];
  const auto axes = faceAxes_w(f);
  const Eigen::Matrix3d tilt = (Eigen::AngleAxisd(ff.tilt_u_rad, axes[0]) *
                                Eigen::AngleAxisd(ff.tilt_v_rad, axes[1]))
                                   .toRotationMatrix();
  p.normal = tilt * p.normal;  // turns about the face centre
  p.point = p.point + ff.offset_mm * p.normal;
  const Eigen::Isometry3d S = setup.transform(nominal.top_centre_w);
  p.point = S * p.point;
  p.normal = S.linear() * p.normal;
  return p;
}

}  // namespace rotacal
