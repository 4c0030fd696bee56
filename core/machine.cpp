#include "core/machine.hpp"

#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "core/errors.hpp"
#include "core/limits.hpp"
#include "core/transforms.hpp"
#include "core/units.hpp"

namespace rotacal {

const RotaryAxis& MachineModel::rotaryAxis(char axis) const {
  for (const auto& r : rotary)
    if (r.name == axis) return r;
  throw std::invalid_argument(std::string("machine has no rotary axis ") + axis);
}

bool MachineModel::hasRotary(char axis) const {
  for (const auto& r : rotary)
    if (r.name == axis) return true;
  return false;
}

int MachineModel::controllerSign(char axis, const std::string& dialect) const {
  const RotaryAxis& r = rotaryAxis(axis);
  const auto it = r.dialect_sign.find(dialect);
  return it != r.dialect_sign.end() ? it->second : r.controller_sign;
}

namespace {

AxisRange rangeFrom(const JsonDoc& doc, const Json& obj, const std::string& key, double max_abs, const char* unit) {
  const Json& v = requireArray(doc, obj, key);
  if (v.size() != 2 || !v[0].is_number() || !v[1].is_number())
    doc.fail(obj, key, fmt::format("field '{}' must be [min, max] in {}", key, unit));
  AxisRange r{checkNumber(doc, obj, key, v[0].get<double>(), Limits::symmetric(max_abs, unit)),
              checkNumber(doc, obj, key, v[1].get<double>(), Limits::symmetric(max_abs, unit))};
  if (r.min >= r.max) doc.fail(obj, key, fmt::format("stroke '{}' has min >= max ([{:g}, {:g}])", key, r.min, r.max));
  return r;
}

Eigen::Vector3d vec3From(const JsonDoc& doc, const Json& obj, const std::string& key, const Limits& limits) {
  const Json& a = requireArray(doc, obj, key);
  if (a.size() != 3) doc.fail(obj, key, "field '" + key + "' must be [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!a[i].is_number()) doc.fail(obj, key, "field '" + key + "' must hold numbers");
    v[i] = checkNumber(doc, obj, key, a[i].get<double>(), limits);
  }
  return v;
}

int signFrom(const JsonDoc& doc, const Json& obj, const std::string& key) {
  const int s = intOr(doc, obj, key, 1, -1, 1);
  if (s == 0) doc.fail(obj, key, "field '" + key + "' must be 1 or -1");
  return s;
}

MachineModel machineFrom(const JsonDoc& doc, const Json& j) {
  if (!j.is_object()) doc.fail(j, "", "machine description must be a JSON object");
  MachineModel m;
  if (j.contains("format") && j["format"] != "rotacal-machine/1")
    doc.fail(j, "format", "unsupported machine format (expected rotacal-machine/1)");
  m.name = requireString(doc, j, "name");
  m.description = stringOr(doc, j, "description", "");
  try {
    m.kinematics = kinematicsFromName(requireString(doc, j, "kinematics"));
  } catch (const std::invalid_argument& e) {
    doc.fail(j, "kinematics", e.what());
  }
  const std::string units = stringOr(doc, j, "units", "mm");
  if (units == "mm") m.units = LengthUnit::Millimetre;
  else if (units == "inch") m.units = LengthUnit::Inch;
  else doc.fail(j, "units", "units must be \"mm\" or \"inch\"");

  const Json& s = requireObject(doc, j, "strokes");
  m.x = rangeFrom(doc, s, "X", kMaxCoordinateMm, "mm");
  m.y = rangeFrom(doc, s, "Y", kMaxCoordinateMm, "mm");
  m.z = rangeFrom(doc, s, "Z", kMaxCoordinateMm, "mm");
  if (m.kinematics == Kinematics::HeadTable) {
    if (!j.contains("head"))
      doc.fail(j, "kinematics", "kinematics head_table needs \"head\": {\"axis\": \"B\" or \"A\", \"pivot_to_ball_mm\": L}");
    const Json& h = requireObject(doc, j, "head");
    const std::string axis = requireString(doc, h, "axis");
    if (axis != "A" && axis != "B") doc.fail(h, "axis", "the head axis must be \"A\" or \"B\"");
    SpindleHead head;
    head.axis = axis[0];
    head.pivot_to_ball_mm = requireNumber(doc, h, "pivot_to_ball_mm", Limits::positive(kMaxCoordinateMm, "mm"));
    m.head = head;
  } else if (m.kinematics == Kinematics::HeadAB && j.contains("head")) {
    // Optional here: 004's head_ab machine carries a tester's sphere at a radius its cycle sets,
    // not a touch probe; a touch-probe cycle needs the pivot-to-ball length.
    const Json& h = requireObject(doc, j, "head");
    if (h.contains("axis"))
      doc.fail(h, "axis", "a head_ab head turns in A and, on it, B: it has no single 'axis' (only pivot_to_ball_mm)");
    SpindleHead head;
    head.axis = 0;
    head.pivot_to_ball_mm = requireNumber(doc, h, "pivot_to_ball_mm", Limits::positive(kMaxCoordinateMm, "mm"));
    m.head = head;
  } else if (m.kinematics == Kinematics::HeadCB) {
    // Always: X Y Z read the pivot, and the probe hangs the pivot length below it (5axiskins'
    // pivot-length); the head's two axes are fixed by the kinematics (C, and B on it).
    if (!j.contains("head"))
      doc.fail(j, "kinematics", "kinematics head_cb needs \"head\": {\"pivot_to_ball_mm\": L} (the pivot to the "
                                "probe-ball centre along the spindle)");
    const Json& h = requireObject(doc, j, "head");
    if (h.contains("axis"))
      doc.fail(h, "axis", "a head_cb head turns in C and, on it, B: it has no single 'axis' (only pivot_to_ball_mm)");
    for (const auto& [key, value] : h.items()) {
      (void)value;
      if (key != "pivot_to_ball_mm")
        doc.fail(h, key, "unknown field '" + key + "' of a head_cb machine's \"head\" (it holds pivot_to_ball_mm only)");
    }
    SpindleHead head;
    head.axis = 0;
    head.pivot_to_ball_mm = requireNumber(doc, h, "pivot_to_ball_mm", Limits::positive(kMaxCoordinateMm, "mm"));
    m.head = head;
  } else if (j.contains("head")) {
    doc.fail(j, "head", "'head' describes a head_table, head_ab or head_cb machine's spindle head, not a " +
                            std::string(kinematicsName(m.kinematics)) + " machine's");
  }
  const std::string rot = m.kinematics == Kinematics::TableAC                                       ? "AC"
                          : m.kinematics == Kinematics::HeadAB || m.kinematics == Kinematics::TableAB ? "AB"
                          : m.kinematics == Kinematics::HeadCB                                        ? "BC"
                          : m.head                                                                    ? std::string(1, m.head->axis) + "C"
                                                                                                      : "BC";
  const Json& axes = requireObject(doc, j, "rotary_axes");
  for (char axis : rot) {
    const std::string key(1, axis);
    if (!axes.contains(key)) doc.fail(j, "rotary_axes", "rotary_axes lacks axis " + key);
    const Json& a = requireObject(doc, axes, key);
    RotaryAxis r;
    r.name = axis;
    r.continuous = boolOr(doc, a, "continuous", false);
    if (!r.continuous) {
      if (!a.contains("stroke_deg")) doc.fail(axes, key, "axis " + key + " needs stroke_deg or continuous");
      r.stroke_deg = rangeFrom(doc, a, "stroke_deg", kMaxAngleDeg, "deg");
    }
    r.controller_sign = signFrom(doc, a, "controller_sign");
    if (a.contains("dialect_sign")) {
      const Json& ds = requireObject(doc, a, "dialect_sign");
      for (const auto& [dialect, sign] : ds.items()) {
        (void)sign;
        r.dialect_sign[dialect] = signFrom(doc, ds, dialect);
      }
    }
    m.rotary.push_back(r);
  }
  m.table_diameter_mm = numberOr(doc, j, "table_diameter_mm", 500.0, Limits::positive(2 * kMaxCoordinateMm, "mm"));
  if (j.contains("tolerance")) {
    const Json& t = requireObject(doc, j, "tolerance");
    if (t.contains("length_um")) m.tolerance.length_um = requireNumber(doc, t, "length_um", Limits::positive(1e6, "um"));
    if (t.contains("angle_mdeg")) m.tolerance.angle_mdeg = requireNumber(doc, t, "angle_mdeg", Limits::positive(1e6, "mdeg"));
    if (!m.tolerance.any()) doc.fail(j, "tolerance", "give length_um, angle_mdeg or both");
  }
  if (j.contains("table_top_z_mm"))
    m.table_top_z_mm = requireNumber(doc, j, "table_top_z_mm", Limits::symmetric(kMaxCoordinateMm, "mm"));
  if (!j.contains("probe")) doc.fail(j, "", "missing object 'probe'");
  const Json& p = requireObject(doc, j, "probe");
  const Limits probe_len = Limits::positive(kMaxProbeLengthMm, "mm");
  m.probe.ball_diameter_mm = requireNumber(doc, p, "ball_diameter_mm", probe_len);
  m.probe.stylus_length_mm = requireNumber(doc, p, "stylus_length_mm", probe_len);
  m.probe.body_clearance_mm =
      numberOr(doc, p, "body_clearance_mm", m.probe.body_clearance_mm, Limits::nonNegative(kMaxProbeLengthMm, "mm"));
  m.probe.tool_number = intOr(doc, p, "tool_number", 0, 0, kMaxToolNumber);
  if (m.head && m.probe.tool_number != 0)
    doc.fail(p, "tool_number", "a spindle head's X, Y and Z must read its pivot: tool_number must be 0 (a "
                               "tool length offset moves Z, not the ball along the tilted spindle)");
  m.probe.repeatability_um =
      numberOr(doc, p, "repeatability_um", m.probe.repeatability_um, Limits::positive(kMaxRepeatabilityUm, "um"));
  if (j.contains("feeds")) {
    const Json& f = requireObject(doc, j, "feeds");
    const Limits feed = Limits::positive(kMaxFeedPerMin, "per min");
    m.feeds.rapid_mm_min = numberOr(doc, f, "rapid_mm_min", m.feeds.rapid_mm_min, feed);
    m.feeds.positioning_mm_min = numberOr(doc, f, "positioning_mm_min", m.feeds.positioning_mm_min, feed);
    m.feeds.probing_mm_min = numberOr(doc, f, "probing_mm_min", m.feeds.probing_mm_min, feed);
    m.feeds.rotary_deg_min = numberOr(doc, f, "rotary_deg_min", m.feeds.rotary_deg_min, feed);
    m.feeds.probing_slow_mm_min = numberOr(doc, f, "probing_slow_mm_min", 0.0, Limits::nonNegative(kMaxFeedPerMin, "per min"));
  }
  // Clearance 0 would rapid the ball along the artefact's top: a real machine needs room.
  const Limits room = Limits::positive(kMaxProbeLengthMm, "mm");
  m.clearance_mm = numberOr(doc, j, "clearance_mm", m.clearance_mm, room);
  m.approach_mm = numberOr(doc, j, "approach_mm", m.approach_mm, room);
  m.overtravel_mm = numberOr(doc, j, "overtravel_mm", m.overtravel_mm, room);
  m.retract_mm = numberOr(doc, j, "retract_mm", 0.0, Limits::nonNegative(kMaxProbeLengthMm, "mm"));
  if (m.retract_mm > 0 && !(m.feeds.probing_slow_mm_min > 0))
    doc.fail(j, "retract_mm", "retract_mm > 0 (double touch) needs feeds.probing_slow_mm_min > 0 for the second touch");
  if (m.retract_mm > 0 && m.retract_mm >= m.approach_mm)
    doc.fail(j, "retract_mm", "retract_mm must be smaller than approach_mm: the back-off stays inside the approach");
  if (j.contains("artefact")) {
    const Json& a = requireObject(doc, j, "artefact");
    const std::string type = requireString(doc, a, "type");
    if (type != "square_column") doc.fail(a, "type", "artefact type must be square_column");
    SquareColumn col;
    col.top_centre_w = vec3From(doc, a, "top_centre_w_mm", Limits::symmetric(kMaxCoordinateMm, "mm"));
    col.size_mm = vec3From(doc, a, "size_mm", Limits::positive(kMaxCoordinateMm, "mm"));
    m.artefact = col;
  }
  if (j.contains("contributors")) {
    const Json& c = j["contributors"];
    if (c.is_string()) {
      std::string path = c.get<std::string>();
      if (path.empty()) doc.fail(j, "contributors", "'contributors' names no file");
      const std::filesystem::path base = std::filesystem::path(doc.file).parent_path();
      if (std::filesystem::path(path).is_relative() && !base.empty()) path = (base / path).string();
      try {
        m.contributors = loadContributors(path);
      } catch (const InputError& e) {
        doc.fail(j, "contributors", std::string("its contributors file: ") + e.what());
      }
    } else if (c.is_object()) {
      m.contributors = contributorsFromJsonValue(doc, c);
    } else {
      doc.fail(j, "contributors", "'contributors' must be a contributors file's path or its object (rotacal-contributors/1)");
    }
  }
  return m;
}

}  // namespace

namespace {
Eigen::Matrix3d headRotation(const MachineModel& m, const Pose& pose) {
  if (!m.head) return Eigen::Matrix3d::Identity();
  // head_ab: the A head carries the B head (core/kinematic_model.hpp), both turning by +angle.
  if (m.kinematics == Kinematics::HeadAB)
    return (elementary(Motion::Rx, degToRad(pose.A)) * elementary(Motion::Ry, degToRad(pose.B))).linear();
  // head_cb: the C head carries the B head (core/kinematic_model.hpp), both by +angle.
  if (m.kinematics == Kinematics::HeadCB)
    return (elementary(Motion::Rz, degToRad(pose.C)) * elementary(Motion::Ry, degToRad(pose.B))).linear();
  const char a = m.head->axis;
  return elementary(a == 'A' ? Motion::Rx : Motion::Ry, degToRad(pose.angle(a))).linear();
}
}  // namespace

Eigen::Vector3d ballFromAxes_m(const MachineModel& m, const Pose& pose) {
  if (!m.head) return Eigen::Vector3d::Zero();
  return headRotation(m, pose) * Eigen::Vector3d(0.0, 0.0, -m.head->pivot_to_ball_mm);
}

Eigen::Vector3d stylusAxis_m(const MachineModel& m, const Pose& pose) { return headRotation(m, pose).col(2); }

double ballDropBelowAxes(const MachineModel& m) { return m.head ? m.head->pivot_to_ball_mm : 0.0; }

MachineModel machineFromJson(const JsonDoc& doc, const Json& j) {
  return guardJson(doc, [&] { return machineFrom(doc, j); });
}

MachineModel loadMachine(const std::string& path) {
  const JsonDoc doc = readJsonFile(path);
  return machineFromJson(doc, doc.value);
}

Json machineToJson(const MachineModel& m) {
  Json j;
  j["format"] = "rotacal-machine/1";
  j["name"] = m.name;
  if (!m.description.empty()) j["description"] = m.description;
  j["kinematics"] = std::string(kinematicsName(m.kinematics));
  j["units"] = m.units == LengthUnit::Inch ? "inch" : "mm";
  j["strokes"] = {{"X", {m.x.min, m.x.max}}, {"Y", {m.y.min, m.y.max}}, {"Z", {m.z.min, m.z.max}}};
  Json rot = Json::object();
  for (const auto& r : m.rotary) {
    Json a;
    if (r.continuous) a["continuous"] = true;
    else a["stroke_deg"] = {r.stroke_deg.min, r.stroke_deg.max};
    a["controller_sign"] = r.controller_sign;
    if (!r.dialect_sign.empty()) a["dialect_sign"] = r.dialect_sign;
    rot[std::string(1, r.name)] = a;
  }
  j["rotary_axes"] = rot;
  j["table_diameter_mm"] = m.table_diameter_mm;
  if (m.table_top_z_mm) j["table_top_z_mm"] = *m.table_top_z_mm;
  if (m.tolerance.any()) {
    Json t = Json::object();
    if (m.tolerance.length_um) t["length_um"] = *m.tolerance.length_um;
    if (m.tolerance.angle_mdeg) t["angle_mdeg"] = *m.tolerance.angle_mdeg;
    j["tolerance"] = t;
  }
  j["probe"] = {{"ball_diameter_mm", m.probe.ball_diameter_mm},
                {"stylus_length_mm", m.probe.stylus_length_mm},
                {"body_clearance_mm", m.probe.body_clearance_mm},
                {"tool_number", m.probe.tool_number},
                {"repeatability_um", m.probe.repeatability_um}};
  j["feeds"] = {{"rapid_mm_min", m.feeds.rapid_mm_min},
                {"positioning_mm_min", m.feeds.positioning_mm_min},
                {"probing_mm_min", m.feeds.probing_mm_min},
                {"rotary_deg_min", m.feeds.rotary_deg_min}};
  // Written only for a double touch, so that single-touch plans stay as they were.
  if (m.feeds.probing_slow_mm_min > 0) j["feeds"]["probing_slow_mm_min"] = m.feeds.probing_slow_mm_min;
  j["clearance_mm"] = m.clearance_mm;
  j["approach_mm"] = m.approach_mm;
  j["overtravel_mm"] = m.overtravel_mm;
  if (m.retract_mm > 0) j["retract_mm"] = m.retract_mm;
  if (m.artefact) {
    j["artefact"] = {{"type", "square_column"},
                     {"top_centre_w_mm", {m.artefact->top_centre_w.x(), m.artefact->top_centre_w.y(), m.artefact->top_centre_w.z()}},
                     {"size_mm", {m.artefact->size_mm.x(), m.artefact->size_mm.y(), m.artefact->size_mm.z()}}};
  }
  if (m.head) {
    j["head"] = {{"pivot_to_ball_mm", m.head->pivot_to_ball_mm}};
    if (m.head->axis != 0) j["head"]["axis"] = std::string(1, m.head->axis);
  }
  if (m.contributors) j["contributors"] = contributorsToJson(*m.contributors);
  return j;
}

}  // namespace rotacal
