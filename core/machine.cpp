#include "core/machine.hpp"

#include <stdexcept>

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

AxisRange rangeFrom(const JsonDoc& doc, const Json& obj, const std::string& key) {
  if (!obj.contains(key) || !obj[key].is_array() || obj[key].size() != 2 || !obj[key][0].is_number() ||
      !obj[key][1].is_number())
    doc.fail(key, "field '" + key + "' must be [min, max] in mm");
  AxisRange r{obj[key][0].get<double>(), obj[key][1].get<double>()};
  if (r.min >= r.max) doc.fail(key, "stroke '" + key + "' has min >= max");
  return r;
}

Eigen::Vector3d vec3From(const JsonDoc& doc, const Json& obj, const std::string& key) {
  if (!obj.contains(key) || !obj[key].is_array() || obj[key].size() != 3)
    doc.fail(key, "field '" + key + "' must be [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!obj[key][i].is_number()) doc.fail(key, "field '" + key + "' must hold numbers");
    v[i] = obj[key][i].get<double>();
  }
  return v;
}

void requirePositive(const JsonDoc& doc, const std::string& key, double v) {
  if (!(v > 0)) doc.fail(key, "field '" + key + "' must be positive");
}

}  // namespace

MachineModel machineFromJson(const JsonDoc& doc, const Json& j) {
  if (!j.is_object()) doc.fail("machine", "machine description must be a JSON object");
  MachineModel m;
  if (j.contains("format") && j["format"] != "rotacal-machine/1")
    doc.fail("format", "unsupported machine format (expected rotacal-machine/1)");
  m.name = requireString(doc, j, "name");
  m.description = j.value("description", "");
  try {
    m.kinematics = kinematicsFromName(requireString(doc, j, "kinematics"));
  } catch (const std::invalid_argument& e) {
    doc.fail("kinematics", e.what());
  }
  const std::string units = j.value("units", "mm");
  if (units == "mm") m.units = LengthUnit::Millimetre;
  else if (units == "inch") m.units = LengthUnit::Inch;
  else doc.fail("units", "units must be \"mm\" or \"inch\"");

  if (!j.contains("strokes") || !j["strokes"].is_object()) doc.fail("strokes", "missing object 'strokes'");
  const Json& s = j["strokes"];
  m.x = rangeFrom(doc, s, "X");
  m.y = rangeFrom(doc, s, "Y");
  m.z = rangeFrom(doc, s, "Z");
  const std::string rot = m.kinematics == Kinematics::TableAC ? "AC" : m.kinematics == Kinematics::HeadAB ? "AB" : "BC";
  if (!j.contains("rotary_axes") || !j["rotary_axes"].is_object())
    doc.fail("rotary_axes", "missing object 'rotary_axes'");
  for (char axis : rot) {
    const std::string key(1, axis);
    if (!j["rotary_axes"].contains(key)) doc.fail("rotary_axes", "rotary_axes lacks axis " + key);
    const Json& a = j["rotary_axes"][key];
    RotaryAxis r;
    r.name = axis;
    r.continuous = a.value("continuous", false);
    if (!r.continuous) {
      if (!a.contains("stroke_deg")) doc.fail(key, "axis " + key + " needs stroke_deg or continuous");
      r.stroke_deg = rangeFrom(doc, a, "stroke_deg");
    }
    r.controller_sign = static_cast<int>(numberOr(doc, a, "controller_sign", 1));
    if (r.controller_sign != 1 && r.controller_sign != -1) doc.fail("controller_sign", "controller_sign must be 1 or -1");
    if (a.contains("dialect_sign")) {
      for (const auto& [dialect, sign] : a["dialect_sign"].items()) {
        if (!sign.is_number_integer() || (sign != 1 && sign != -1))
          doc.fail("dialect_sign", "dialect_sign values must be 1 or -1");
        r.dialect_sign[dialect] = sign.get<int>();
      }
    }
    m.rotary.push_back(r);
  }
  m.table_diameter_mm = numberOr(doc, j, "table_diameter_mm", 500.0);
  if (j.contains("probe")) {
    const Json& p = j["probe"];
    m.probe.ball_diameter_mm = requireNumber(doc, p, "ball_diameter_mm");
    m.probe.stylus_length_mm = requireNumber(doc, p, "stylus_length_mm");
    m.probe.body_clearance_mm = numberOr(doc, p, "body_clearance_mm", m.probe.body_clearance_mm);
    m.probe.tool_number = static_cast<int>(numberOr(doc, p, "tool_number", 0));
    m.probe.repeatability_um = numberOr(doc, p, "repeatability_um", m.probe.repeatability_um);
    requirePositive(doc, "ball_diameter_mm", m.probe.ball_diameter_mm);
    requirePositive(doc, "stylus_length_mm", m.probe.stylus_length_mm);
  } else {
    doc.fail("probe", "missing object 'probe'");
  }
  if (j.contains("feeds")) {
    const Json& f = j["feeds"];
    m.feeds.rapid_mm_min = numberOr(doc, f, "rapid_mm_min", m.feeds.rapid_mm_min);
    m.feeds.positioning_mm_min = numberOr(doc, f, "positioning_mm_min", m.feeds.positioning_mm_min);
    m.feeds.probing_mm_min = numberOr(doc, f, "probing_mm_min", m.feeds.probing_mm_min);
    m.feeds.rotary_deg_min = numberOr(doc, f, "rotary_deg_min", m.feeds.rotary_deg_min);
    m.feeds.probing_slow_mm_min = numberOr(doc, f, "probing_slow_mm_min", 0.0);
    if (m.feeds.probing_slow_mm_min < 0) doc.fail("probing_slow_mm_min", "field 'probing_slow_mm_min' must be >= 0");
    requirePositive(doc, "probing_mm_min", m.feeds.probing_mm_min);
    requirePositive(doc, "positioning_mm_min", m.feeds.positioning_mm_min);
  }
  m.clearance_mm = numberOr(doc, j, "clearance_mm", m.clearance_mm);
  m.approach_mm = numberOr(doc, j, "approach_mm", m.approach_mm);
  m.overtravel_mm = numberOr(doc, j, "overtravel_mm", m.overtravel_mm);
  requirePositive(doc, "approach_mm", m.approach_mm);
  requirePositive(doc, "overtravel_mm", m.overtravel_mm);
  m.retract_mm = numberOr(doc, j, "retract_mm", 0.0);
  if (m.retract_mm < 0) doc.fail("retract_mm", "field 'retract_mm' must be >= 0 (0 = single touch)");
  if (m.retract_mm > 0 && !(m.feeds.probing_slow_mm_min > 0))
    doc.fail("retract_mm", "retract_mm > 0 (double touch) needs feeds.probing_slow_mm_min > 0 for the second touch");
  if (m.retract_mm > 0 && m.retract_mm >= m.approach_mm)
    doc.fail("retract_mm", "retract_mm must be smaller than approach_mm: the back-off stays inside the approach");
  if (j.contains("artefact")) {
    const Json& a = j["artefact"];
    const std::string type = requireString(doc, a, "type");
    if (type != "square_column") doc.fail("type", "artefact type must be square_column");
    SquareColumn col;
    col.top_centre_w = vec3From(doc, a, "top_centre_w_mm");
    col.size_mm = vec3From(doc, a, "size_mm");
    if ((col.size_mm.array() <= 0).any()) doc.fail("size_mm", "artefact size must be positive");
    m.artefact = col;
  }
  return m;
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
  return j;
}

}  // namespace rotacal
