#include "core/contributors.hpp"

#include <cmath>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/limits.hpp"

#include "core/units.hpp"

namespace rotacal {

const std::vector<ContributorInfo>& contributorCatalog() {
  using K = ContributorKind;
  static const std::vector<ContributorInfo> c = {
      {"probe_repeatability", K::ProbeRepeatability, -1, -1, "probe: unidirectional repeatability, per touch"},
      {"probe_pretravel", K::ProbePretravel, -1, -1, "probe: directional pre-travel variation, per probing direction"},
      {"E_xx_lin", K::LinearScale, 0, 0, "X axis: linear (scale) error"},
      {"E_xx_rand", K::LinearRandom, 0, 0, "X axis: non-systematic positioning error"},
      {"E_yx_rand", K::LinearRandom, 0, 1, "X axis: straightness in Y"},
      {"E_zx_rand", K::LinearRandom, 0, 2, "X axis: straightness in Z"},
      {"E_yy_lin", K::LinearScale, 1, 1, "Y axis: linear (scale) error"},
      {"E_yy_rand", K::LinearRandom, 1, 1, "Y axis: non-systematic positioning error"},
      {"E_xy_rand", K::LinearRandom, 1, 0, "Y axis: straightness in X"},
      {"E_zy_rand", K::LinearRandom, 1, 2, "Y axis: straightness in Z"},
      {"S_xy", K::Squareness, 1, 0, "squareness of Y to X (X error proportional to Y)"},
      {"E_zz_lin", K::LinearScale, 2, 2, "Z axis: linear (scale) error"},
      {"E_zz_rand", K::LinearRandom, 2, 2, "Z axis: non-systematic positioning error"},
      {"E_xz_rand", K::LinearRandom, 2, 0, "Z axis: straightness in X"},
      {"E_yz_rand", K::LinearRandom, 2, 1, "Z axis: straightness in Y"},
      {"S_xz", K::Squareness, 2, 0, "squareness of Z to X (X error proportional to Z)"},
      {"S_yz", K::Squareness, 2, 1, "squareness of Z to Y (Y error proportional to Z)"},
      {"setup_position", K::SetupPosition, -1, -1, "test piece: position error in X, Y, Z"},
      {"setup_orientation", K::SetupOrientation, -1, -1, "test piece: orientation error around X, Y, Z"},
      {"surface_roughness", K::SurfaceRoughness, -1, -1, "test piece: surface roughness under the ball, per touch"},
      {"form_error", K::FormError, -1, -1, "test piece: form of each face (offset along the normal, two tilts)"},
      {"rtest_sensor_gain", K::RtestSensorGain, -1, -1, "R-test: gain (calibration) error of each displacement sensor"},
      {"rtest_sensor_direction", K::RtestSensorDirection, -1, -1,
       "R-test: direction of each sensor in the nest calibrated wrong (cross-talk between sensors)"},
      {"rtest_sphere_form", K::RtestSphereForm, -1, -1, "R-test: form of the sphere at each contact, per reading"},
      {"rtest_sphere_offset", K::RtestSphereOffset, -1, -1,
       "R-test: sphere centre off its calibrated place on the spindle (runout, tool length) in X, Y, Z"},
      {"rtest_cycle_drift", K::RtestCycleDrift, -1, -1,
       "R-test: thermal drift of the sphere against the table over one measuring cycle in X, Y, Z"},
      {"laser_resolution", K::LaserResolution, -1, -1, "laser: the system's own error of one reading, per reading"},
      {"laser_alignment", K::LaserAlignment, -1, -1,
       "laser: beam direction off its nominal one (cosine error, cross-talk of the other components), per run"},
      {"laser_sphere_form", K::LaserSphereForm, -1, -1, "laser: form of the target sphere where the beam meets it, per reading"},
      {"laser_lateral_coupling", K::LaserLateralCoupling, -1, -1,
       "laser: the target sphere moving across the beam (its curvature read as a change of path), per reading"},
  };
  return c;
}

const ContributorInfo* findContributor(std::string_view id) {
  for (const auto& c : contributorCatalog())
    if (c.id == id) return &c;
  return nullptr;
}

const Contributor* ContributorSet::find(std::string_view id) const {
  for (const auto& c : items)
    if (c.info->id == id) return &c;
  return nullptr;
}

LinearAxisModel ContributorSet::linearAxisModel() const {
  LinearAxisModel m;
  m.spacing_min_mm = node_spacing_min_mm;
  m.spacing_max_mm = node_spacing_max_mm;
  for (const auto& c : items) {
    const ContributorInfo& i = *c.info;
    switch (i.kind) {
      case ContributorKind::LinearScale: m.u_scale[i.axis] = c.u[0]; break;
      case ContributorKind::LinearRandom: m.u_rand(i.direction, i.axis) = c.u[0]; break;
      case ContributorKind::Squareness:
        if (i.id == "S_xy") m.u_S_xy = c.u[0];
        else if (i.id == "S_xz") m.u_S_xz = c.u[0];
        else m.u_S_yz = c.u[0];
        break;
      default: break;
    }
  }
  return m;
}

bool ContributorSet::validate(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  std::set<std::string_view> seen;
  for (const auto& c : items) {
    if (!c.info) return fail("contributor without an id");
    if (!seen.insert(c.info->id).second) return fail("contributor '" + std::string(c.info->id) + "' is listed twice");
    if (!(c.u.minCoeff() >= 0) || !c.u.allFinite())
      return fail("contributor '" + std::string(c.info->id) + "': standard uncertainties must be finite and >= 0");
    // Internal units: mm for lengths, else ratios (rad); 10 mm bounds both. Beyond it the
    // linearised chain of the Monte Carlo is meaningless and its tables overflow.
    if (c.u.maxCoeff() > kMaxContributorU * 1e-3)
      return fail(fmt::format("contributor '{}': standard uncertainty beyond the plausible {:g} um (or {:g} mm/m)",
                              c.info->id, kMaxContributorU, kMaxContributorU));
  }
  return linearAxisModel().validate(why);
}

bool unitFactor(Quantity q, std::string_view unit, double* f) {
  if (q == Quantity::Length) {
    if (unit == "um") *f = 1e-3;
    else if (unit == "mm") *f = 1.0;
    else return false;
    return true;
  }
  if (unit == "um/m" || unit == "ppm" || unit == "urad") *f = 1e-6;
  else if (unit == "um/100mm") *f = 1e-5;
  else if (unit == "um/mm" || unit == "mm/m" || unit == "mrad") *f = 1e-3;
  else if (unit == "mdeg") *f = mdegToRad(1.0);
  else return false;
  return true;
}

namespace {

constexpr const char* kLengthUnits = "um or mm";
constexpr const char* kRatioUnits = "um/m, ppm, um/100mm, um/mm, mm/m, urad, mrad or mdeg";

Quantity quantityOf(ContributorKind k) {
  switch (k) {
    case ContributorKind::LinearScale:
    case ContributorKind::Squareness:
    case ContributorKind::SetupOrientation:
    case ContributorKind::RtestSensorGain:
    case ContributorKind::RtestSensorDirection:
    case ContributorKind::LaserAlignment: return Quantity::Ratio;
    default: return Quantity::Length;
  }
}

bool isVectorKind(ContributorKind k) {
  return k == ContributorKind::SetupPosition || k == ContributorKind::SetupOrientation ||
         k == ContributorKind::RtestSphereOffset || k == ContributorKind::RtestCycleDrift;
}

/// The largest standard uncertainty of a contributor in internal units (mm, or a ratio / rad).
double maxContributorU(Quantity q) { return q == Quantity::Length ? kMaxContributorU * 1e-3 : kMaxContributorU * 1e-6; }

/// parent[key] = {"u": number | [x, y, z], "unit": "..."} -> internal units.
Eigen::Vector3d readU(const JsonDoc& doc, const Json& parent, const std::string& key, Quantity q, bool vector,
                      std::string* unit_out) {
  const Json& entry = parent[key];
  if (!entry.is_object() || !entry.contains("u"))
    doc.fail(parent, key, fmt::format("'{}' needs {{\"u\": {}, \"unit\": ...}}", key, vector ? "[x, y, z]" : "number"));
  if (!entry.contains("unit") || !entry["unit"].is_string())
    doc.fail(parent, key, fmt::format("'{}' lacks its unit ({})", key, q == Quantity::Length ? kLengthUnits : kRatioUnits));
  const std::string unit = entry["unit"].get<std::string>();
  double f = 0;
  if (!unitFactor(q, unit, &f))
    doc.fail(entry, "unit",
             fmt::format("'{}': unit '{}' is not one of {}", key, unit, q == Quantity::Length ? kLengthUnits : kRatioUnits));
  // Finite, non-negative and plausible: a typo of 1e308 would overflow the Monte Carlo.
  const Limits limits = Limits::nonNegative(maxContributorU(q) / f, unit);
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  const Json& v = entry["u"];
  if (vector && v.is_array()) {
    if (v.size() != 3) doc.fail(entry, "u", fmt::format("'{}': u must be [x, y, z] or one number", key));
    for (int i = 0; i < 3; ++i) {
      if (!v[i].is_number()) doc.fail(entry, "u", fmt::format("'{}': u must hold numbers", key));
      u[i] = checkNumber(doc, entry, "u", v[i].get<double>(), limits);
    }
  } else if (v.is_number()) {
    u = Eigen::Vector3d::Constant(checkNumber(doc, entry, "u", v.get<double>(), limits));
    if (!vector) u.tail<2>().setZero();
  } else {
    doc.fail(entry, "u", fmt::format("'{}': u must be {}", key, vector ? "[x, y, z] or a number" : "a number"));
  }
  if (unit_out) *unit_out = unit;
  return u * f;
}

ReferenceUncertainty readReference(const JsonDoc& doc, const Json& r) {
  ReferenceUncertainty ref;
  ref.source = stringOr(doc, r, "source", "");
  auto value = [&](const Json& parent, const std::string& param) {
    const Json& e = parent[param];
    int i = -1;
    for (const Kinematics k : {Kinematics::TableAC, Kinematics::TableBC, Kinematics::TableAB})
      if (i < 0) i = parameterIndex(k, param);
    if (i < 0) doc.fail(parent, param, "reference: unknown location error '" + param + "'");
    if (!e.is_object() || !e.contains("u") || !e["u"].is_number() || !e.contains("unit"))
      doc.fail(parent, param, "reference: '" + param + "' needs {\"u\": number, \"unit\": \"um\" | \"mdeg\"}");
    const std::string unit = stringOr(doc, e, "unit", "");
    if (unit != "um" && unit != "mdeg") doc.fail(e, "unit", "reference: unit of '" + param + "' must be um or mdeg");
    return requireNumber(doc, e, "u", Limits::nonNegative(kMaxContributorU, unit));
  };
  if (r.contains("combined")) {
    const Json& c = requireObject(doc, r, "combined");
    for (const auto& [param, e] : c.items()) ref.combined[param] = value(c, param);
  }
  if (r.contains("contributors")) {
    const Json& cs = requireObject(doc, r, "contributors");
    for (const auto& [id, per] : cs.items()) {
      if (!findContributor(id)) doc.fail(cs, id, "reference: unknown contributor '" + id + "'");
      if (!per.is_object()) doc.fail(cs, id, "reference: '" + id + "' must map parameters to {\"u\", \"unit\"}");
      for (const auto& [param, e] : per.items()) ref.contributors[id][param] = value(per, param);
    }
  }
  return ref;
}

ContributorSet contributorsFrom(const JsonDoc& doc, const Json& j) {
  if (!j.is_object() || !j.contains("format") || j["format"] != "rotacal-contributors/1")
    doc.fail(j, "format", "not a contributors file (expected \"format\": \"rotacal-contributors/1\")");
  ContributorSet set;
  set.file = doc.file;
  set.description = stringOr(doc, j, "description", "");
  if (j.contains("node_spacing_mm")) {
    const Json& n = j["node_spacing_mm"];
    if (!n.is_array() || n.size() != 2 || !n[0].is_number() || !n[1].is_number())
      doc.fail(j, "node_spacing_mm", "'node_spacing_mm' must be [min, max] (000 Eq. (22): [20, 50])");
    const Limits spacing = Limits::positive(kMaxCoordinateMm, "mm");
    set.node_spacing_min_mm = checkNumber(doc, j, "node_spacing_mm", n[0].get<double>(), spacing);
    set.node_spacing_max_mm = checkNumber(doc, j, "node_spacing_mm", n[1].get<double>(), spacing);
    if (!(set.node_spacing_max_mm >= set.node_spacing_min_mm))
      doc.fail(j, "node_spacing_mm", "'node_spacing_mm' must satisfy 0 < min <= max");
  }
  if (!j.contains("contributors") || !j["contributors"].is_object() || j["contributors"].empty())
    doc.fail(j, "contributors", "missing object 'contributors' (ids of 000 Table 5 with {\"u\", \"unit\"})");
  const Json& cs = j["contributors"];
  for (const auto& [id, entry] : cs.items()) {
    if (!findContributor(id)) {
      std::string known;
      for (const auto& c : contributorCatalog()) known += (known.empty() ? "" : ", ") + std::string(c.id);
      doc.fail(cs, id, "unknown contributor '" + id + "' (known: " + known + ")");
    }
  }
  for (const auto& info : contributorCatalog()) {  // catalog order, whatever the file's order
    const std::string id(info.id);
    if (!cs.contains(id)) continue;
    const Json& e = cs[id];
    Contributor c;
    c.info = &info;
    if (e.is_object() && e.contains("note") && e["note"].is_string()) c.note = e["note"].get<std::string>();
    if (info.kind == ContributorKind::FormError) {
      if (!e.is_object() || !e.contains("offset") || !e.contains("tilt"))
        doc.fail(cs, id, "'form_error' needs {\"offset\": {\"u\", \"unit\"}, \"tilt\": {\"u\", \"unit\"}}");
      std::string u1, u2;
      c.u[0] = readU(doc, e, "offset", Quantity::Length, false, &u1)[0];
      c.u[1] = readU(doc, e, "tilt", Quantity::Ratio, false, &u2)[0];
      c.unit = u1 + ", " + u2;
    } else {
      const bool vec = isVectorKind(info.kind);
      c.u = readU(doc, cs, id, quantityOf(info.kind), vec, &c.unit);
    }
    set.items.push_back(c);
  }
  if (j.contains("reference")) set.reference = readReference(doc, requireObject(doc, j, "reference"));
  std::string why;
  if (!set.validate(&why)) doc.fail(j, "contributors", why);
  return set;
}

}  // namespace

ContributorSet contributorsFromJson(const JsonDoc& doc) {
  return guardJson(doc, [&] { return contributorsFrom(doc, doc.value); });
}

ContributorSet contributorsFromJsonValue(const JsonDoc& doc, const Json& value) {
  return guardJson(doc, [&] { return contributorsFrom(doc, value); });
}

ContributorSet loadContributors(const std::string& path) { return contributorsFromJson(readJsonFile(path)); }

Json contributorsToJson(const ContributorSet& set) {
  Json j;
  j["format"] = "rotacal-contributors/1";
  if (!set.description.empty()) j["description"] = set.description;
  j["node_spacing_mm"] = {set.node_spacing_min_mm, set.node_spacing_max_mm};
  Json cs = Json::object();
  for (const auto& c : set.items) {
    const ContributorKind k = c.info->kind;
    Json e;
    if (k == ContributorKind::FormError) {
      e["offset"] = {{"u", mmToUm(c.u[0])}, {"unit", "um"}};
      e["tilt"] = {{"u", c.u[1] * 1e3}, {"unit", "mrad"}};
    } else if (quantityOf(k) == Quantity::Length) {
      if (isVectorKind(k)) e["u"] = {mmToUm(c.u[0]), mmToUm(c.u[1]), mmToUm(c.u[2])};
      else e["u"] = mmToUm(c.u[0]);
      e["unit"] = "um";
    } else {
      if (k == ContributorKind::SetupOrientation) e["u"] = {c.u[0] * 1e6, c.u[1] * 1e6, c.u[2] * 1e6};
      else e["u"] = c.u[0] * 1e6;
      e["unit"] = "urad";
    }
    if (!c.note.empty()) e["note"] = c.note;
    cs[std::string(c.info->id)] = e;
  }
  j["contributors"] = cs;
  return j;
}

}  // namespace rotacal
