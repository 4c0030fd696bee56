#include "cycles/spaceframe/frame.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/json_io.hpp"
#include "core/units.hpp"

namespace rotacal {

const std::array<Eigen::Vector3d, 7>& spaceFrameTable1_mm() {
  static const std::array<Eigen::Vector3d, 7> t = {
      Eigen::Vector3d(-0.0170, -0.2243, 73.6373),   Eigen::Vector3d(0.1266, -102.977, 0.1119),
      Eigen::Vector3d(-88.1763, -51.6103, 149.8827), Eigen::Vector3d(-88.4696, 50.0995, -0.0242),
      Eigen::Vector3d(-2.3838, 101.2081, 150.2041),  Eigen::Vector3d(86.5175, 51.0002, 0.0012),
      Eigen::Vector3d(88.7260, -52.6343, 150.1732)};
  return t;
}

FrameCalibration loadFrameCalibration(const std::string& path) {
  const JsonDoc doc = readJsonFile(path);
  return guardJson(doc, [&] {
    const Json& j = doc.value;
    if (!j.is_object() || stringOr(doc, j, "format", "") != "rotacal-frame/1")
      doc.fail(j, "format", "not a frame calibration: \"format\" must be \"rotacal-frame/1\"");
    FrameCalibration c;
    c.source = requireString(doc, j, "source");
    if (c.source.empty()) doc.fail(j, "source", "\"source\" must say where the centres come from (a CMM report)");
    c.u_um = requireNumber(doc, j, "u_um", Limits::nonNegative(1000.0, "um"));
    const Json& sp = requireObject(doc, j, "spheres_mm");
    if (sp.size() != 7) doc.fail(j, "spheres_mm", "\"spheres_mm\" must hold the seven spheres \"1\" .. \"7\"");
    for (int s = 1; s <= 7; ++s) {
      const std::string key = std::to_string(s);
      const Json& a = requireArray(doc, sp, key);
      if (a.size() != 3) doc.fail(sp, key, "sphere " + key + " must be [x, y, z] in mm");
      for (int k = 0; k < 3; ++k) {
        if (!a[k].is_number()) doc.fail(sp, key, "sphere " + key + " must hold numbers");
        c.spheres_mm[static_cast<size_t>(s - 1)][k] = checkNumber(doc, sp, key, a[k].get<double>(), Limits::symmetric(1000.0, "mm"));
      }
      // A calibration of this frame: each centre within 5 mm of 003's design (a different frame
      // would need its own planning, which the layout does not offer).
      const double off = (c.spheres_mm[static_cast<size_t>(s - 1)] - spaceFrameTable1_mm()[static_cast<size_t>(s - 1)]).norm();
      if (off > 5.0)
        doc.fail(sp, key, fmt::format("sphere {} lies {:.3f} mm from 003 Table 1's centre: more than 5 mm, not a "
                                      "calibration of this frame", s, off));
    }
    return c;
  });
}

Eigen::Matrix3d rotTilt003(double theta, double phi) {
  const double ct = std::cos(theta), st = std::sin(theta), cp = std::cos(phi), sp = std::sin(phi);
  Eigen::Matrix3d m;
  // 003 Sec. 3.1, with +cos(phi) in (3,3) (the printed -cos(phi) is a mirror: det = -1).
  m << ct, st * cp, st * sp,  //
      -st, ct * cp, ct * sp,  //
      0.0, -sp, cp;
  return m;
}

std::uint64_t lengthCount(std::uint64_t n) { return n < 2 ? 0 : n * (n - 1) / 2; }

std::vector<LengthError> lengthErrors(const std::vector<Eigen::Vector3d>& measured,
                                      const std::vector<Eigen::Vector3d>& nominal) {
  if (measured.size() != nominal.size()) throw std::invalid_argument("measured and nominal point counts differ");
  std::vector<LengthError> out;
  const int n = static_cast<int>(nominal.size());
  out.reserve(static_cast<size_t>(lengthCount(static_cast<std::uint64_t>(n))));
  for (int j = 0; j < n; ++j)
    for (int k = j + 1; k < n; ++k)
      out.push_back({j, k, (nominal[j] - nominal[k]).norm(), (measured[j] - measured[k]).norm()});
  return out;
}

std::string_view lengthDecisionName(LengthDecision d) {
  switch (d) {
    case LengthDecision::Pass: return "pass";
    case LengthDecision::Fail: return "fail";
    case LengthDecision::Inconclusive: return "inconclusive";
  }
  return "inconclusive";
}

LengthVerdict checkLengths(const std::vector<LengthError>& lengths, const LengthSpec& spec, double k) {
  if (!(spec.A_um >= 0) || !(spec.K_um_per_m >= 0) || spec.A_um + spec.K_um_per_m <= 0)
    throw std::invalid_argument("length specification needs A >= 0 um, K >= 0 um/m, not both zero");
  LengthVerdict v;
  v.lengths = static_cast<int>(lengths.size());
  double ss = 0.0;
  for (size_t i = 0; i < lengths.size(); ++i) {
    const double d = std::abs(mmToUm(lengths[i].dL_mm()));
    const double lim = spec.limit_um(lengths[i].measured_mm);
    ss += d * d;
    if (d > lim) ++v.outside;
    const double U = k * lengths[i].u_um;
    v.max_U_um = std::max(v.max_U_um, U);
    if (d <= lim - U) ++v.conforming;
    else if (d > lim + U) ++v.nonconforming;
    else ++v.undecided;
    v.max_abs_dL_um = std::max(v.max_abs_dL_um, d);
    if (d / lim > v.worst_ratio || v.worst_index < 0) {
      v.worst_ratio = d / lim;
      v.worst_index = static_cast<int>(i);
    }
  }
  v.rms_dL_um = lengths.empty() ? 0.0 : std::sqrt(ss / static_cast<double>(lengths.size()));
  v.decision = v.nonconforming > 0 ? LengthDecision::Fail
               : v.undecided > 0    ? LengthDecision::Inconclusive
                                    : LengthDecision::Pass;
  v.pass = v.decision == LengthDecision::Pass;
  return v;
}

}  // namespace rotacal
