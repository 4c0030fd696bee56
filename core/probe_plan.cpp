#include "core/probe_plan.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "core/errors.hpp"
#include "core/limits.hpp"
#include "core/units.hpp"

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
  while (std::getline(ss, item, ',')) {
    if (out.size() == static_cast<size_t>(kMaxListValues))
      throw std::invalid_argument(
          fmt::format("option {}: more than {} values; a list option takes at most {}", key, kMaxListValues, kMaxListValues));
    out.push_back(parseNumber(key, item));
  }
  if (out.empty()) throw std::invalid_argument("option " + key + ": empty list");
  return out;
}

void requirePlanSize(const std::string& options, double points, double poses) {
  if (poses > kMaxPlanPoses)
    throw std::invalid_argument(fmt::format("{}: the plan would have {:.0f} poses; at most {} poses are allowed in one plan",
                                            options, poses, kMaxPlanPoses));
  if (points > kMaxPlanPoints)
    throw std::invalid_argument(fmt::format("{}: the plan would have {:.0f} touches; at most {} are allowed in one plan",
                                            options, points, kMaxPlanPoints));
}

namespace {

Json vec(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

// The machine's own rotary axes, by name.
Json poseJson(const MachineModel& m, const Pose& p) {
  Json j = Json::object();
  for (const auto& r : m.rotary) j[std::string(1, r.name)] = p.angle(r.name);
  return j;
}


Pose poseFrom(const JsonDoc& doc, const Json& obj) {
  const Json& j = requireObject(doc, obj, "pose");
  const Limits angle = Limits::symmetric(kMaxAngleDeg, "deg");
  for (const auto& [key, value] : j.items())
    if (key != "A" && key != "B" && key != "C")
      doc.fail(j, key, "pose axis '" + key + "' is not a rotary axis (A, B or C)");
  Pose p;
  p.A = numberOr(doc, j, "A", 0.0, angle);
  p.B = numberOr(doc, j, "B", 0.0, angle);
  p.C = numberOr(doc, j, "C", 0.0, angle);
  return p;
}

// What the probe moves over between touches must stay below the heights the plan moves at:
// each pose's safe height above what is touched at that pose (the artefact, the spheres), the
// index height above all of it. A hand-edited height would otherwise send rapids through the
// artefact. A cycle without probing moves, or whose artefact is not the machine's, says so in
// its PlanRules.
void checkHeights(const JsonDoc& doc, const Json& j, const ProbePlan& plan, const PlanRules& rules) {
  if (!rules.heights) return;
  const double r = plan.machine.probe.ball_radius_mm();
  const bool artefact = plan.machine.artefact && rules.artefact_touched;
  double highest = -std::numeric_limits<double>::infinity();
  std::string highest_pose;
  for (size_t k = 0; k < plan.poses.size(); ++k) {
    const PlanPose& pp = plan.poses[k];
    const Eigen::Isometry3d T = T_m_w_nominal(plan.machine.kinematics, pp.pose);
    double top = -std::numeric_limits<double>::infinity();
    for (const auto& p : plan.points) {
      if (p.pose_name != pp.name) continue;
      top = std::max(top, (T * p.contact_w_mm).z());
      if (p.sphere) top = std::max(top, (T * p.sphere->center_w_mm).z() + p.sphere->radius_mm);
    }
    const double touched_top = top;
    if (artefact)
      for (const auto& corner : plan.machine.artefact->corners_w()) top = std::max(top, (T * corner).z());
    if (!std::isfinite(top)) continue;
    const double safe_top = rules.safe_height_over_artefact ? top : touched_top;
    // On a head machine Z reads the pivot: the ball hangs below it by the head's offset.
    const double ball_below = -ballFromAxes_m(plan.machine, pp.pose).z();
    if (std::isfinite(safe_top) && pp.safe_z_mm - ball_below < safe_top + r - 1e-6)
      doc.fail(j["poses"][k], "safe_z_mm",
               fmt::format("pose {}: safe_z_mm = {:g} mm is below what the probe moves over: the ball centre must stay "
                           "at z >= {:.3f} mm (the top of what is touched plus the ball radius){}",
                           pp.name, pp.safe_z_mm, safe_top + r,
                           ball_below != 0 ? fmt::format(", {:.3f} mm below Z at this head angle", ball_below) : ""));
    if (top > highest) {
      highest = top;
      highest_pose = pp.name;
    }
  }
  // While the axes index, a head may pass through any angle between: the ball as low as L below Z.
  const double drop = ballDropBelowAxes(plan.machine);
  if (std::isfinite(highest) && plan.index_z_mm - drop < highest + r - 1e-6)
    doc.fail(j, "index_z_mm",
             fmt::format("index_z_mm = {:g} mm is below the artefact: the ball centre must stay at z >= {:.3f} mm (its "
                         "top at pose {} plus the ball radius) while the table indexes{}",
                         plan.index_z_mm, highest + r, highest_pose,
                         drop > 0 ? fmt::format(", and it hangs up to {:g} mm below Z", drop) : ""));
}

// A pose names only the machine's rotary axes, each inside its stroke (a hand-edited pose would
// otherwise reach the program or the analysis unchecked).
void checkPoseOnMachine(const JsonDoc& doc, const Json& obj, const MachineModel& m, const Pose& pose) {
  const Json& j = obj["pose"];
  for (const auto& [key, value] : j.items()) {
    bool known = false;
    for (const auto& r : m.rotary) known = known || std::string(1, r.name) == key;
    if (!known) doc.fail(j, key, "pose axis '" + key + "' is not a rotary axis of this machine (" +
                                     std::string(kinematicsName(m.kinematics)) + ")");
  }
  for (const auto& r : m.rotary) {
    const double ang = pose.angle(r.name);
    if (!r.continuous && !r.stroke_deg.contains(ang))
      doc.fail(j, std::string(1, r.name),
               fmt::format("{} = {:g} deg is outside the {} stroke [{:g}, {:g}] deg", r.name, ang, r.name,
                           r.stroke_deg.min, r.stroke_deg.max));
  }
}

ProbePlan planFrom(const JsonDoc& doc, const PlanRules& rules) {
  const Json& j = doc.value;
  if (!j.is_object() || !j.contains("format") || j["format"] != "rotacal-plan/1")
    doc.fail(j, "format", "not a rotacal plan (expected \"format\": \"rotacal-plan/1\")");
  ProbePlan plan;
  plan.cycle = requireString(doc, j, "cycle");
  if (!j.contains("machine")) doc.fail(j, "", "plan lacks 'machine'");
  plan.machine = machineFromJson(doc, requireObject(doc, j, "machine"));
  // Planned probing moves need the probe ball's place: a head_ab machine declares it in "head"
  // (without, its tool tip is a tester's sphere, and its transforms would throw far from this
  // file's lines).
  if (rules.heights && plan.machine.kinematics == Kinematics::HeadAB && !plan.machine.head)
    doc.fail(j["machine"], "kinematics",
             fmt::format("cycle '{}' probes with a touch probe, whose place on a spindle-head machine (head_ab) "
                         "MACHINE.json declares in \"head\": {{\"pivot_to_ball_mm\": L}}; this one has none (its "
                         "tool tip is calibrated at a fixed point, 004)",
                         plan.cycle));
  if (j.contains("options")) {
    const Json& o = requireObject(doc, j, "options");
    for (const auto& [k, v] : o.items()) plan.options[k] = v.is_string() ? v.get<std::string>() : v.dump();
  }
  const Limits coord = Limits::symmetric(kMaxCoordinateMm, "mm");
  plan.index_z_mm = requireNumber(doc, j, "index_z_mm", coord);
  const Json& poses = requireArray(doc, j, "poses");
  if (poses.size() > static_cast<size_t>(kMaxPlanPoses))
    doc.fail(j, "poses", fmt::format("plan has {} poses; at most {} are allowed", poses.size(), kMaxPlanPoses));
  std::set<std::string> names;
  for (const auto& p : poses) {
    PlanPose pp;
    pp.name = requireString(doc, p, "name");
    pp.pose = poseFrom(doc, p);
    checkPoseOnMachine(doc, p, plan.machine, pp.pose);
    pp.safe_z_mm = requireNumber(doc, p, "safe_z_mm", coord);
    if (!names.insert(pp.name).second) doc.fail(p, "name", "pose name '" + pp.name + "' appears twice");
    plan.poses.push_back(pp);
  }
  if (!j.contains("points") || !j["points"].is_array() || j["points"].empty())
    doc.fail(j, "points", "plan has no points");
  const Json& points = j["points"];
  if (points.size() > static_cast<size_t>(kMaxPlanPoints))
    doc.fail(j, "points", fmt::format("plan has {} points; at most {} are allowed", points.size(), kMaxPlanPoints));
  const Limits unit_component = Limits::symmetric(1.0 + 1e-6);
  for (const auto& q : points) {
    ProbePoint p;
    p.id = requireInt(doc, q, "id", 1, kMaxPlanPoints);
    p.pose_name = stringOr(doc, q, "pose_name", "");
    if (!names.empty() && !names.count(p.pose_name))
      doc.fail(q, "pose_name", fmt::format("point {}: pose '{}' is not among the plan's poses", p.id, p.pose_name));
    p.pose = poseFrom(doc, q);
    checkPoseOnMachine(doc, q, plan.machine, p.pose);
    // A touch is made at its pose (a tool-tip sweep moves within its pose: not a touch).
    for (const auto& pp : plan.poses)
      if (rules.heights && rules.artefact_touched && pp.name == p.pose_name &&
          (std::abs(pp.pose.A - p.pose.A) > 1e-9 || std::abs(pp.pose.B - p.pose.B) > 1e-9 ||
           std::abs(pp.pose.C - p.pose.C) > 1e-9))
        doc.fail(q, "pose", fmt::format("point {}: its pose is not that of pose '{}' it names", p.id, p.pose_name));
    p.target = intOr(doc, q, "target", p.id, 0, kMaxPlanPoints);
    try {
      p.face = faceFromName(stringOr(doc, q, "face", "top"));
    } catch (const std::invalid_argument& e) {
      doc.fail(q, "face", e.what());
    }
    p.contact_w_mm = requireVec3(doc, q, "contact_w_mm", coord);
    p.normal_w = requireVec3(doc, q, "normal_w", unit_component);
    p.trigger_m_mm = requireVec3(doc, q, "trigger_m_mm", coord);
    p.approach_m = requireVec3(doc, q, "approach_m", unit_component);
    if (std::abs(p.normal_w.norm() - 1.0) > 1e-6)
      doc.fail(q, "normal_w", fmt::format("point {}: normal_w must be a unit vector (length {:g})", p.id, p.normal_w.norm()));
    if (std::abs(p.approach_m.norm() - 1.0) > 1e-6)
      doc.fail(q, "approach_m",
               fmt::format("point {}: approach_m must be a unit vector (length {:g})", p.id, p.approach_m.norm()));
    const MachineModel& m = plan.machine;
    const AxisRange* linear[3] = {&m.x, &m.y, &m.z};
    for (int a = 0; a < 3; ++a)
      if (!linear[a]->contains(p.trigger_m_mm[a]))
        doc.fail(q, "trigger_m_mm",
                 fmt::format("point {}: trigger_m_mm {} = {:g} mm is outside the {} stroke [{:g}, {:g}] mm", p.id,
                             "XYZ"[a], p.trigger_m_mm[a], "XYZ"[a], linear[a]->min, linear[a]->max));
    // A probing move goes toward the surface it touches (a reversed one would start inside it).
    if (rules.heights && rules.artefact_touched) {
      const Eigen::Vector3d n_m = T_m_w_nominal(m.kinematics, p.pose).linear() * p.normal_w;
      if (n_m.dot(p.approach_m) > -1e-9)
        doc.fail(q, "approach_m",
                 fmt::format("point {}: approach_m does not move toward the surface (its normal at the pose is "
                             "({:.3f}, {:.3f}, {:.3f}))", p.id, n_m.x(), n_m.y(), n_m.z()));
    }
    p.t_s = numberOr(doc, q, "t_s", 0.0, Limits::nonNegative(kMaxClockSeconds, "s"));
    if (q.contains("sphere")) {
      const Json& sj = requireObject(doc, q, "sphere");
      SphereTarget st;
      st.id = requireInt(doc, sj, "id", 1, kMaxPlanPoints);
      st.center_w_mm = requireVec3(doc, sj, "center_w_mm", coord);
      st.radius_mm = requireNumber(doc, sj, "radius_mm", Limits::positive(kMaxCoordinateMm, "mm"));
      p.sphere = st;
    }
    if (p.id != static_cast<int>(plan.points.size()) + 1)
      doc.fail(q, "id", fmt::format("point ids must run 1, 2, 3, ... in order (found {} at position {})", p.id,
                                    plan.points.size() + 1));
    plan.points.push_back(p);
  }
  if (rules.spheres > 0)
    for (size_t i = 0; i < plan.points.size(); ++i)
      if (!plan.points[i].sphere || plan.points[i].sphere->id > rules.spheres)
        doc.fail(points[i], "sphere",
                 fmt::format("point {}: a touch of this {} plan names a sphere 1 to {}", i + 1, plan.cycle, rules.spheres));
  // A pose without touches has nothing to identify from (a sphere cycle fits each sphere at each
  // pose: at least 4 touches each).
  for (size_t k = 0; k < plan.poses.size(); ++k) {
    std::map<int, int> per_sphere;
    int n = 0;
    for (const auto& p : plan.points)
      if (p.pose_name == plan.poses[k].name) {
        ++n;
        if (p.sphere) ++per_sphere[p.sphere->id];
      }
    if (n == 0) doc.fail(j["poses"][k], "name", "pose '" + plan.poses[k].name + "' has no points");
    for (int sphere = 1; sphere <= rules.spheres; ++sphere)
      if (per_sphere[sphere] < 4)
        doc.fail(j["poses"][k], "name",
                 fmt::format("pose '{}' has {} touches of sphere {}; a {} plan needs at least 4 per sphere at every pose",
                             plan.poses[k].name, per_sphere[sphere], sphere, plan.cycle));
  }
  // The options these cycles read back from the plan when simulating and analysing.
  try {
    if (rules.check_options) rules.check_options(plan);
  } catch (const std::invalid_argument& e) {
    doc.fail(j, "options", e.what());
  } catch (const std::out_of_range& e) {
    doc.fail(j, "options", std::string("a cycle option is missing: ") + e.what());
  }
  checkHeights(doc, j, plan, rules);
  return plan;
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
    poses.push_back({{"name", p.name}, {"pose", poseJson(plan.machine, p.pose)}, {"safe_z_mm", p.safe_z_mm}});
  j["poses"] = poses;
  Json pts = Json::array();
  for (const auto& p : plan.points) {
    pts.push_back({{"id", p.id},
                   {"pose_name", p.pose_name},
                   {"pose", poseJson(plan.machine, p.pose)},
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

ProbePlan planFromJson(const JsonDoc& doc, const PlanRules& rules) {
  return guardJson(doc, [&] { return planFrom(doc, rules); });
}

ProbePlan loadPlan(const std::string& path, const PlanRules& rules) { return planFromJson(readJsonFile(path), rules); }

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

void linearStrokeViolations(const MachineModel& m, const Eigen::Vector3d& position_m, const std::string& where,
                            std::vector<std::string>* out) {
  const char names[3] = {'X', 'Y', 'Z'};
  const AxisRange* ranges[3] = {&m.x, &m.y, &m.z};
  for (int i = 0; i < 3; ++i)
    if (!ranges[i]->contains(position_m[i]))
      out->push_back(fmt::format("{} = {:.3f} mm is outside the stroke [{:.3f}, {:.3f}]{}", names[i], position_m[i],
                                 ranges[i]->min, ranges[i]->max, where));
}

void rotaryStrokeViolations(const MachineModel& m, const Pose& pose, const std::string& pose_name,
                            std::vector<std::string>* out) {
  for (const auto& r : m.rotary) {
    const double ang = pose.angle(r.name);
    if (!r.continuous && !r.stroke_deg.contains(ang))
      out->push_back(fmt::format("pose {}: {} = {:.3f} deg is outside the stroke [{:.3f}, {:.3f}]", pose_name, r.name, ang,
                                 r.stroke_deg.min, r.stroke_deg.max));
  }
}

std::vector<std::string> strokeViolations(const ProbePlan& plan) {
  std::vector<std::string> v;
  for (const auto& w : plannedPath(plan))
    linearStrokeViolations(plan.machine, w.position_m, w.point_id ? fmt::format(" (point {})", w.point_id) : std::string(), &v);
  for (const auto& p : plan.poses) rotaryStrokeViolations(plan.machine, p.pose, p.name, &v);
  return v;
}

double moveTime_s(const Waypoint& w, const Eigen::Vector3d& from_m, const Pose& pose_from, const Feeds& f) {
  const double d = (w.position_m - from_m).norm();
  switch (w.kind) {
    case Waypoint::Kind::ClimbZ:
    case Waypoint::Kind::Rapid: return 60.0 * d / f.rapid_mm_min;
    case Waypoint::Kind::Position:
    case Waypoint::Kind::Retract: return 60.0 * d / f.positioning_mm_min;
    case Waypoint::Kind::Index:
      return 60.0 *
             std::max({std::abs(w.pose.A - pose_from.A), std::abs(w.pose.B - pose_from.B), std::abs(w.pose.C - pose_from.C)}) /
             f.rotary_deg_min;
    case Waypoint::Kind::Dwell: return w.seconds;
    case Waypoint::Kind::Probe:
    case Waypoint::Kind::Read: return 0.0;
  }
  return 0.0;
}

void estimateTimes(ProbePlan& plan) {
  const auto path = plannedPath(plan);
  const Feeds& f = plan.machine.feeds;
  double t = 0.0;
  Eigen::Vector3d cur = path.empty() ? Eigen::Vector3d::Zero() : path.front().position_m;
  Pose pose = path.empty() ? Pose{} : path.front().pose;
  for (const auto& w : path) {
    t += moveTime_s(w, cur, pose, f);
    if (w.kind == Waypoint::Kind::Probe) {
      t += 60.0 * plan.machine.approach_mm / f.probing_mm_min;
      if (auto* p = const_cast<ProbePoint*>(plan.findPoint(w.point_id))) p->t_s = std::round(t * 1000.0) / 1000.0;
      cur = w.position_m - (plan.machine.overtravel_mm) * plan.findPoint(w.point_id)->approach_m;
      continue;  // the move stops at the trigger
    }
    if (w.kind == Waypoint::Kind::Index) pose = w.pose;
    cur = w.position_m;
  }
}

}  // namespace rotacal
