#include "core/probe_plan.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "core/errors.hpp"
#include "core/units.hpp"

namespace rotacal {

}  // namespace rotacal
namespace rotacal {

const ProbePoint* ProbePlan::findPoint(int id) const {
  if (id >= 1 && id <= static_cast<int>(points.size()) && points[id - 1].id == id) return &points[id - 1];
  for (const auto& p : points)
    if (p.id == id) return &p;
  return nullptr;
}

const PlanPose& ProbePlan::poseByName(const std::string& name) const {
  for (const auto& p : poses)
    if (p.name == name) return p;
  throw std::invalid_argument("plan has no pose '" + name + "'");
}

double parseNumber(const std::string& key, const std::string& text) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument("");
    return v;
  } catch (const std::exception&) {
    throw std::invalid_argument("option " + key + ": '" + text + "' is not a number");
  }
}

std::vector<double> parseNumberList(const std::string& key, const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(parseNumber(key, item));
  if (out.empty()) throw std::invalid_argument("option " + key + ": empty list");
  return out;
}

namespace {

Json vec(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

Json poseJson(Kinematics k, const Pose& p) {
  if (k == Kinematics::TableAC) return {{"A", p.A}, {"C", p.C}};
  if (k == Kinematics::HeadAB) return {{"A", p.A}, {"B", p.B}};
  return {{"B", p.B}, {"C", p.C}};
}

Eigen::Vector3d vecFrom(const JsonDoc& doc, const Json& obj, const char* key) {
  if (!obj.contains(key) || !obj[key].is_array() || obj[key].size() != 3)
    doc.fail(key, std::string("field '") + key + "' must be [x, y, z]");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!obj[key][i].is_number()) doc.fail(key, std::string("field '") + key + "' must hold numbers");
    v[i] = obj[key][i].get<double>();
  }
  return v;
}

Pose poseFrom(const JsonDoc& doc, const Json& obj) {
  if (!obj.contains("pose") || !obj["pose"].is_object()) doc.fail("pose", "point lacks 'pose'");
  Pose p;
  const Json& j = obj["pose"];
  p.A = numberOr(doc, j, "A", 0.0);
  p.B = numberOr(doc, j, "B", 0.0);
  p.C = numberOr(doc, j, "C", 0.0);
  return p;
}

}  // namespace

Json planToJson(const ProbePlan& plan) {
  Json j;
  j["format"] = "rotacal-plan/1";
  j["cycle"] = plan.cycle;
  j["machine"] = machineToJson(plan.machine);
  j["options"] = plan.options;
  j["index_z_mm"] = plan.index_z_mm;
  Json poses = Json::array();
  for (const auto& p : plan.poses)
    poses.push_back({{"name", p.name}, {"pose", poseJson(plan.machine.kinematics, p.pose)}, {"safe_z_mm", p.safe_z_mm}});
  j["poses"] = poses;
  Json pts = Json::array();
  for (const auto& p : plan.points) {
    pts.push_back({{"id", p.id},
                   {"pose_name", p.pose_name},
                   {"pose", poseJson(plan.machine.kinematics, p.pose)},
                   {"target", p.target},
                   {"face", std::string(faceName(p.face))},
                   {"contact_w_mm", vec(p.contact_w_mm)},
                   {"normal_w", vec(p.normal_w)},
                   {"trigger_m_mm", vec(p.trigger_m_mm)},
                   {"approach_m", vec(p.approach_m)},
                   {"t_s", p.t_s}});
    if (p.sphere)
      pts.back()["sphere"] = {{"id", p.sphere->id}, {"center_w_mm", vec(p.sphere->center_w_mm)},
                              {"radius_mm", p.sphere->radius_mm}};
  }
  j["points"] = pts;
  return j;
}

ProbePlan planFromJson(const JsonDoc& doc) {
  const Json& j = doc.value;
  if (!j.is_object() || j.value("format", "") != "rotacal-plan/1")
    doc.fail("format", "not a rotacal plan (expected \"format\": \"rotacal-plan/1\")");
  ProbePlan plan;
  plan.cycle = requireString(doc, j, "cycle");
  if (!j.contains("machine")) doc.fail("machine", "plan lacks 'machine'");
  plan.machine = machineFromJson(doc, j["machine"]);
  if (j.contains("options") && j["options"].is_object())
    for (const auto& [k, v] : j["options"].items()) plan.options[k] = v.is_string() ? v.get<std::string>() : v.dump();
  plan.index_z_mm = requireNumber(doc, j, "index_z_mm");
  if (!j.contains("poses") || !j["poses"].is_array()) doc.fail("poses", "plan lacks 'poses'");
  for (const auto& p : j["poses"]) {
    PlanPose pp;
    pp.name = requireString(doc, p, "name");
    pp.pose = poseFrom(doc, p);
    pp.safe_z_mm = requireNumber(doc, p, "safe_z_mm");
    plan.poses.push_back(pp);
  }
  if (!j.contains("points") || !j["points"].is_array() || j["points"].empty())
    doc.fail("points", "plan has no points");
  for (const auto& q : j["points"]) {
    ProbePoint p;
    p.id = static_cast<int>(requireNumber(doc, q, "id"));
    p.pose_name = q.value("pose_name", "");
    p.pose = poseFrom(doc, q);
    p.target = static_cast<int>(numberOr(doc, q, "target", p.id));
    try {
      p.face = faceFromName(q.value("face", "top"));
    } catch (const std::invalid_argument& e) {
      doc.fail("face", e.what());
    }
    p.contact_w_mm = vecFrom(doc, q, "contact_w_mm");
    p.normal_w = vecFrom(doc, q, "normal_w");
    p.trigger_m_mm = vecFrom(doc, q, "trigger_m_mm");
    p.approach_m = vecFrom(doc, q, "approach_m");
    if (std::abs(p.approach_m.norm() - 1.0) > 1e-6 || std::abs(p.normal_w.norm() - 1.0) > 1e-6)
      doc.fail("approach_m", fmt::format("point {}: approach_m and normal_w must be unit vectors", p.id));
    p.t_s = numberOr(doc, q, "t_s", 0.0);
    if (q.contains("sphere")) {
      const Json& sj = q["sphere"];
      if (!sj.is_object()) doc.fail("sphere", fmt::format("point {}: 'sphere' must be an object", p.id));
      SphereTarget st;
      st.id = static_cast<int>(requireNumber(doc, sj, "id"));
      st.center_w_mm = vecFrom(doc, sj, "center_w_mm");
      st.radius_mm = requireNumber(doc, sj, "radius_mm");
      if (!(st.radius_mm > 0)) doc.fail("radius_mm", fmt::format("point {}: sphere radius must be positive", p.id));
      p.sphere = st;
    }
    if (p.id != static_cast<int>(plan.points.size()) + 1)
      doc.fail("id", fmt::format("point ids must run 1, 2, 3, ... in order (found {} at position {})", p.id,
                                 plan.points.size() + 1));
    plan.points.push_back(p);
  }
  return plan;
}

ProbePlan loadPlan(const std::string& path) { return planFromJson(readJsonFile(path)); }

std::vector<Waypoint> plannedPath(const ProbePlan& plan) {
  std::vector<Waypoint> path;
  const double a = plan.machine.approach_mm;
  const double o = plan.machine.overtravel_mm;
  bool first = true;
  std::string pose_name;
  Eigen::Vector3d cur(0, 0, plan.index_z_mm);
  Pose pose;
  auto push = [&](Waypoint::Kind k, const Eigen::Vector3d& p, int id = 0) {
    path.push_back({k, p, pose, id});
    cur = p;
  };
  for (const auto& pt : plan.points) {
    const Eigen::Vector3d start = pt.start_m(a);
    double safe_z = plan.index_z_mm;
    for (const auto& pp : plan.poses)
      if (pp.name == pt.pose_name) safe_z = pp.safe_z_mm;
    safe_z = std::max(safe_z, start.z());
    if (first || pt.pose_name != pose_name) {
      // Where the machine stands at the start is unknown: climb in Z alone first.
      if (first) push(Waypoint::Kind::ClimbZ, Eigen::Vector3d(start.x(), start.y(), plan.index_z_mm));
      else if (cur.z() < plan.index_z_mm) push(Waypoint::Kind::Rapid, Eigen::Vector3d(cur.x(), cur.y(), plan.index_z_mm));
      pose = pt.pose;
      push(Waypoint::Kind::Index, cur);
      push(Waypoint::Kind::Rapid, Eigen::Vector3d(start.x(), start.y(), plan.index_z_mm));
      first = false;
      pose_name = pt.pose_name;
    }
    push(Waypoint::Kind::Rapid, Eigen::Vector3d(start.x(), start.y(), safe_z));
    push(Waypoint::Kind::Position, start);
    push(Waypoint::Kind::Probe, pt.end_m(o), pt.id);
    push(Waypoint::Kind::Retract, start, pt.id);
    push(Waypoint::Kind::Rapid, Eigen::Vector3d(start.x(), start.y(), safe_z));
  }
  push(Waypoint::Kind::Rapid, Eigen::Vector3d(cur.x(), cur.y(), plan.index_z_mm));
  // Drop zero-length moves (e.g. when the start is already at the safe height). After the first
  // climb the real XY is unknown (the climb waypoint carries the first touch's XY only for the
  // stroke check): keep the first XY move at the index height, or the program would go straight
  // down to the first start from wherever it stood.
  std::vector<Waypoint> out;
  bool xy_known = true;
  for (const auto& w : path) {
    if (w.kind == Waypoint::Kind::ClimbZ) xy_known = false;
    else if (xy_known && !out.empty() && w.kind != Waypoint::Kind::Index && w.kind != Waypoint::Kind::Probe &&
             (w.position_m - out.back().position_m).norm() < 1e-9)
      continue;
    out.push_back(w);
    if (w.kind != Waypoint::Kind::ClimbZ && w.kind != Waypoint::Kind::Index) xy_known = true;
  }
  return out;
}

std::vector<std::string> strokeViolations(const ProbePlan& plan) {
  std::vector<std::string> v;
  const MachineModel& m = plan.machine;
  const char names[3] = {'X', 'Y', 'Z'};
  const AxisRange* ranges[3] = {&m.x, &m.y, &m.z};
  for (const auto& w : plannedPath(plan)) {
    for (int i = 0; i < 3; ++i)
      if (!ranges[i]->contains(w.position_m[i]))
        v.push_back(fmt::format("{} = {:.3f} mm is outside the stroke [{:.3f}, {:.3f}]{}", names[i], w.position_m[i],
                                ranges[i]->min, ranges[i]->max,
                                w.point_id ? fmt::format(" (point {})", w.point_id) : std::string()));
  }
  for (const auto& p : plan.poses) {
    for (const auto& r : m.rotary) {
      const double ang = r.name == 'A' ? p.pose.A : (r.name == 'B' ? p.pose.B : p.pose.C);
      if (!r.continuous && !r.stroke_deg.contains(ang))
        v.push_back(fmt::format("pose {}: {} = {:.3f} deg is outside the stroke [{:.3f}, {:.3f}]", p.name, r.name, ang,
                                r.stroke_deg.min, r.stroke_deg.max));
    }
  }
  return v;
}

void estimateTimes(ProbePlan& plan) {
  const auto path = plannedPath(plan);
  const Feeds& f = plan.machine.feeds;
  double t = 0.0;
  Eigen::Vector3d cur = path.empty() ? Eigen::Vector3d::Zero() : path.front().position_m;
  Pose pose = path.empty() ? Pose{} : path.front().pose;
  for (const auto& w : path) {
    const double d = (w.position_m - cur).norm();
    switch (w.kind) {
      case Waypoint::Kind::ClimbZ:
      case Waypoint::Kind::Rapid: t += 60.0 * d / f.rapid_mm_min; break;
      case Waypoint::Kind::Position:
      case Waypoint::Kind::Retract: t += 60.0 * d / f.positioning_mm_min; break;
      case Waypoint::Kind::Index: {
        const double da = std::max({std::abs(w.pose.A - pose.A), std::abs(w.pose.B - pose.B), std::abs(w.pose.C - pose.C)});
        t += 60.0 * da / f.rotary_deg_min;
        pose = w.pose;
        break;
      }
      case Waypoint::Kind::Probe: {
        const double to_trigger = plan.machine.approach_mm;
        t += 60.0 * to_trigger / f.probing_mm_min;
        if (auto* p = const_cast<ProbePoint*>(plan.findPoint(w.point_id))) p->t_s = std::round(t * 1000.0) / 1000.0;
        cur = w.position_m - (plan.machine.overtravel_mm) * plan.findPoint(w.point_id)->approach_m;
        continue;  // the move stops at the trigger
      }
    }
    cur = w.position_m;
  }
}

}  // namespace rotacal
