#include "cycles/rtest/plan.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "core/limits.hpp"

#include "core/errors.hpp"
#include "core/rng.hpp"
#include "core/units.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

const std::array<int, kRtestParams>& rtestParameterIndices(Kinematics k) {
  static const std::array<int, kRtestParams> bc = {0, 1, 2, 3, 4, 5};  // dx_BY dy_CB dz_BY a_BY b_BY c_BY
  static const std::array<int, kRtestParams> ac = {0, 1, 2, 4, 5, 6};  // dx_AY dy_AY dz_AY a_AY b_AY c_AY
  return k == Kinematics::TableBC ? bc : ac;
}

std::string rtestParameterName(Kinematics k, int p) {
  return std::string(locationParameters(k)[rtestParameterIndices(k)[p]].name);
}

bool rtestParameterIsLength(int p) { return p < 3; }

char tiltAxis(Kinematics k) { return k == Kinematics::TableBC ? 'B' : 'A'; }
double tiltOf(Kinematics k, const Pose& p) { return k == Kinematics::TableBC ? p.B : p.A; }
Pose tiltPose(Kinematics k, double tilt, double c) {
  Pose p;
  (k == Kinematics::TableBC ? p.B : p.A) = tilt;
  p.C = c;
  return p;
}

int RtestSchedule::cycles() const {
  if (!thermal) return 1;
  // A plan file's options are checked here again: they may have been edited since `plan`.
  const double n = std::floor(duration_s / interval_s + 1e-9) + 1.0;
  if (!(n >= 1.0 && n <= kMaxRepeats))
    throw std::invalid_argument(fmt::format("rtest plan: duration_h / interval_min give {:g} cycles; at most {} repeats "
                                            "are allowed",
                                            n, kMaxRepeats));
  return static_cast<int>(n);
}

double RtestSchedule::strokeTime_s() const {
  return 60.0 * std::abs(recip_to_deg - recip_from_deg) / recip_feed_deg_min;
}

namespace {

std::string opt(const CycleOptions& o, const std::string& key, const std::string& fallback) {
  const auto it = o.find(key);
  return it == o.end() ? fallback : it->second;
}

double optionNumber(const ProbePlan& plan, const std::string& key) {
  const auto it = plan.options.find(key);
  if (it == plan.options.end()) throw std::invalid_argument("rtest plan lacks option '" + key + "'");
  return parseNumber(key, it->second);
}

/// Unit vector of the nest axis (workpiece +Z) in the machine frame at a pose.
Eigen::Vector3d nestAxis_m(Kinematics k, const Pose& pose) {
  return T_m_w_nominal(k, pose).linear() * Eigen::Vector3d::UnitZ();
}

}  // namespace

ProbePlan makeRtestPlan(const MachineModel& m, const CycleOptions& options) {
  // 002's index poses turn a tilting table; under a head the R-test sensors would read the
  // head's chain, which this cycle's model has not.
  // 002's Table 2 errors are a tilt axis's and the C table's on it: an A/B table has no C.
  if (!hasPapersLocationErrors(m.kinematics) || m.kinematics == Kinematics::TableAB)
    throw std::invalid_argument(fmt::format("cycle rtest calibrates a tilting table carrying a C table (table_bc, table_ac), not a {} machine",
                                            kinematicsName(m.kinematics)));
  const std::string tilt_key = m.kinematics == Kinematics::TableBC ? "b_list" : "a_list";
  // The tilt axis's list is named for the axis (a_list or b_list): the other axis's is unknown.
  requireKnownOptions("rtest", options,
                      {tilt_key, "c_list", "nest_w_mm", "dwell_s", "retract_mm", "thermal", "interval_min", "duration_h",
                       "recip_list", "recip_feed_deg_min", "sensor_noise_um", "reset_reads"});
  if (!m.hasRotary(tiltAxis(m.kinematics)) || !m.hasRotary('C'))
    throw std::invalid_argument(fmt::format("rtest needs the {} and C axes", tiltAxis(m.kinematics)));
  // 002 Sec. 4.1: B = -60..60 step 30, C = 0..288 step 72. An A/C table (ac_trunnion: A in
  // [-110, 20]) gets A = -60..0 step 20 by default (the sphere enters the nest from above, so
  // the tilt stays well short of 90 deg).
  const std::string tilt_default = m.kinematics == Kinematics::TableBC ? "-60,-30,0,30,60" : "-60,-40,-20,0";
  const auto tilts = parseNumberList(tilt_key, opt(options, tilt_key, tilt_default));
  const auto cs = parseNumberList("c_list", opt(options, "c_list", "0,72,144,216,288"));
  for (const auto* list : {&tilts, &cs})
    for (size_t i = 0; i < list->size(); ++i)
      for (size_t j = i + 1; j < list->size(); ++j)
        if ((*list)[i] == (*list)[j]) throw std::invalid_argument(fmt::format("rtest: angle {:g} listed twice", (*list)[i]));
  if (std::find(tilts.begin(), tilts.end(), 0.0) == tilts.end() || std::find(cs.begin(), cs.end(), 0.0) == cs.end())
    throw std::invalid_argument(fmt::format(
        "rtest: {} and c_list must contain 0: the sensors are reset at {} = C = 0 (002 Eq. (4))", tilt_key,
        tiltAxis(m.kinematics)));
  if (cs.size() < 3) throw std::invalid_argument("rtest: c_list needs at least 3 angles to locate the C axis at each tilt");
  // One pose per reading: the tilt list times the C list.
  requirePlanSize(fmt::format("rtest: options {} ({} values) and c_list ({} values)", tilt_key, tilts.size(), cs.size()),
                  static_cast<double>(tilts.size() * cs.size()), static_cast<double>(tilts.size() * cs.size()));
  // 002 Sec. 4.1: the nest at [-0.448, -91.187, 40.567] mm in the workpiece frame.
  const Eigen::Vector3d nest = parseVec3Option("nest_w_mm", opt(options, "nest_w_mm", "-0.448,-91.187,40.567"));
  if (std::hypot(nest.x(), nest.y()) < 10.0)
    throw std::invalid_argument("rtest: nest_w_mm within 10 mm of the C axis: the C-axis tilt would not be seen");
  const double dwell = parseNumber("dwell_s", opt(options, "dwell_s", "2"));
  const double retract = parseNumber("retract_mm", opt(options, "retract_mm", "20"));
  for (double t : tilts)
    if (std::abs(t) > 75.0)
      throw std::invalid_argument(fmt::format("rtest: tilt {:g} deg: the sphere enters the nest from above, keep |tilt| <= 75 deg", t));
  if (!(dwell >= 0) || !(retract > m.probe.ball_radius_mm()))
    throw std::invalid_argument("rtest: dwell_s must be >= 0 and retract_mm larger than the sphere radius");
  const std::string thermal = opt(options, "thermal", "0");
  if (thermal != "0" && thermal != "1") throw std::invalid_argument("rtest: thermal must be 0 or 1");
  const double interval = parseNumber("interval_min", opt(options, "interval_min", "15"));
  const double duration = parseNumber("duration_h", opt(options, "duration_h", "3"));
  const auto recip = parseNumberList("recip_list", opt(options, "recip_list", "-90,-60"));
  const double rfeed = parseNumber("recip_feed_deg_min", opt(options, "recip_feed_deg_min", "5000"));
  if (recip.size() != 2 || recip[0] == recip[1]) throw std::invalid_argument("rtest: recip_list must be two different angles");
  if (!(interval > 0) || !(duration >= 0) || !(rfeed > 0))
    throw std::invalid_argument("rtest: interval_min, recip_feed_deg_min must be > 0 and duration_h >= 0");
  if (60.0 * interval > kMaxClockSeconds || 3600.0 * duration > kMaxClockSeconds)
    throw std::invalid_argument(fmt::format("rtest: interval_min and duration_h must stay within {:g} s", kMaxClockSeconds));
  if (thermal == "1" && 60.0 * duration / interval + 1.0 > kMaxRepeats)
    throw std::invalid_argument(fmt::format(
        "rtest: options duration_h = {:g} and interval_min = {:g} give {:.0f} cycles; at most {} repeats are allowed",
        duration, interval, std::floor(60.0 * duration / interval) + 1.0, kMaxRepeats));
  const std::string reset_reads = opt(options, "reset_reads", "1");
  if (reset_reads != "0" && reset_reads != "1") throw std::invalid_argument("rtest: reset_reads must be 0 or 1");
  const double noise = parseNumber("sensor_noise_um", opt(options, "sensor_noise_um", "0.2"));
  if (!(noise > 0)) throw std::invalid_argument("rtest: sensor_noise_um must be > 0");
  const RotaryAxis& ta = m.rotaryAxis(tiltAxis(m.kinematics));
  for (double r : recip)
    if (!ta.continuous && !ta.stroke_deg.contains(r))
      throw std::invalid_argument(fmt::format("rtest: reciprocation angle {:g} is outside the {} stroke", r, ta.name));

  ProbePlan plan;
  plan.cycle = "rtest";
  plan.machine = m;
  plan.options = {{tilt_key, numberListOption(tilts)},
                  {"c_list", numberListOption(cs)},
                  {"nest_w_mm", fmt::format("{:g},{:g},{:g}", nest.x(), nest.y(), nest.z())},
                  {"dwell_s", fmt::format("{:g}", dwell)},
                  {"retract_mm", fmt::format("{:g}", retract)},
                  {"thermal", thermal},
                  {"interval_min", fmt::format("{:g}", interval)},
                  {"duration_h", fmt::format("{:g}", duration)},
                  {"recip_list", numberListOption(recip)},
                  {"recip_feed_deg_min", fmt::format("{:g}", rfeed)},
                  {"sensor_noise_um", fmt::format("{:g}", noise)},
                  {"reset_reads", reset_reads}};
  double top = -1e9;
  int id = 0;
  for (double t : tilts)
    for (double c : cs) {
      const Pose pose = tiltPose(m.kinematics, t, c);
      const Eigen::Isometry3d T = T_m_w_nominal(m.kinematics, pose);
      ProbePoint p;
      p.id = ++id;
      p.pose_name = fmt::format("{}{:g}C{:g}", tiltAxis(m.kinematics), t, c);
      p.pose = pose;
      p.target = 1;
      p.face = Face::Top;
      p.contact_w_mm = nest;
      p.normal_w = Eigen::Vector3d::UnitZ();
      p.trigger_m_mm = T * nest;                 // 002 Eq. (3): rq = D_b(-B) D_c(-C) wq*
      p.approach_m = -nestAxis_m(m.kinematics, pose);  // the sphere enters along the nest axis
      plan.points.push_back(p);
      top = std::max(top, (p.trigger_m_mm + retract * nestAxis_m(m.kinematics, pose)).z());
    }
  // Index (and reciprocate) with the sphere above anything the turning table can reach: its
  // rim rises to the table radius at a 90 deg tilt, the nest stands nest.z above the table.
  plan.index_z_mm = std::max(top, 0.5 * m.table_diameter_mm + std::max(nest.z(), 0.0)) + m.clearance_mm +
                    m.probe.ball_radius_mm();
  for (const auto& p : plan.points) plan.poses.push_back({p.pose_name, p.pose, plan.index_z_mm});
  // Planned time of each reading: the end of its dwell.
  const std::vector<double> times = rtestReadTimes(plan);
  const size_t first = rtestResetReads(plan) ? 1 : 0;
  for (size_t i = 0; i < plan.points.size(); ++i) plan.points[i].t_s = times[first + i];
  const auto v = rtestStrokeViolations(plan);
  if (!v.empty()) throw std::invalid_argument("rtest plan does not fit the machine: " + v.front());
  return plan;
}

RtestSchedule rtestSchedule(const ProbePlan& plan) {
  RtestSchedule s;
  s.thermal = plan.options.count("thermal") && plan.options.at("thermal") == "1";
  s.interval_s = 60.0 * optionNumber(plan, "interval_min");
  s.duration_s = 3600.0 * optionNumber(plan, "duration_h");
  const auto r = parseNumberList("recip_list", plan.options.at("recip_list"));
  s.recip_from_deg = r.at(0);
  s.recip_to_deg = r.at(1);
  s.recip_feed_deg_min = optionNumber(plan, "recip_feed_deg_min");
  return s;
}

void rtestCheckPlanOptions(const ProbePlan& plan) {
  const RtestSchedule s = rtestSchedule(plan);
  if (!(s.interval_s > 0) || !(s.duration_s >= 0) || !(s.recip_feed_deg_min > 0))
    throw std::invalid_argument("rtest: interval_min, recip_feed_deg_min must be > 0 and duration_h >= 0");
  if (s.interval_s > kMaxClockSeconds || s.duration_s > kMaxClockSeconds)
    throw std::invalid_argument(fmt::format("rtest: interval_min and duration_h must stay within {:g} s", kMaxClockSeconds));
  s.cycles();
  if (!(optionNumber(plan, "retract_mm") > plan.machine.probe.ball_radius_mm()) || !(optionNumber(plan, "dwell_s") >= 0))
    throw std::invalid_argument("rtest: dwell_s must be >= 0 and retract_mm larger than the sphere radius");
  if (plan.options.count("sensor_noise_um") && !(optionNumber(plan, "sensor_noise_um") > 0))
    throw std::invalid_argument("rtest: sensor_noise_um must be > 0");
}

Eigen::Vector3d rtestNest_w(const ProbePlan& plan) { return plan.points.front().contact_w_mm; }

std::vector<Waypoint> rtestCycleMoves(const ProbePlan& plan) {
  const double retract = optionNumber(plan, "retract_mm");
  const double dwell = optionNumber(plan, "dwell_s");
  // The visits of one cycle: with reset reads the reset pose first and last (read as pose 0:
  // 002 Eq. (4)'s reference before the first pose, and its re-read to catch a sensor step).
  std::vector<std::pair<const ProbePoint*, int>> visits;
  const bool reset = rtestResetReads(plan);
  const ProbePoint* ref = reset ? &plan.points.at(static_cast<size_t>(rtestReferencePoint(plan) - 1)) : nullptr;
  if (reset) visits.emplace_back(ref, 0);
  for (const auto& p : plan.points) visits.emplace_back(&p, p.id);
  if (reset) visits.emplace_back(ref, 0);
  std::vector<Waypoint> out;
  bool first = true;
  Eigen::Vector3d cur = Eigen::Vector3d::Zero();
  for (const auto& [pp, id] : visits) {
    const ProbePoint& p = *pp;
    const Eigen::Vector3d entry = p.trigger_m_mm - retract * p.approach_m;
    if (first) out.push_back({Waypoint::Kind::ClimbZ, Eigen::Vector3d(entry.x(), entry.y(), plan.index_z_mm), p.pose});
    else out.push_back({Waypoint::Kind::Rapid, Eigen::Vector3d(cur.x(), cur.y(), plan.index_z_mm), out.back().pose});
    out.push_back({Waypoint::Kind::Index, out.back().position_m, p.pose});
    out.push_back({Waypoint::Kind::Rapid, Eigen::Vector3d(entry.x(), entry.y(), plan.index_z_mm), p.pose});
    out.push_back({Waypoint::Kind::Rapid, entry, p.pose});
    out.push_back({Waypoint::Kind::Position, p.trigger_m_mm, p.pose});
    out.push_back({Waypoint::Kind::Dwell, p.trigger_m_mm, p.pose, id, dwell});
    out.push_back({Waypoint::Kind::Read, p.trigger_m_mm, p.pose, id});
    out.push_back({Waypoint::Kind::Position, entry, p.pose});
    cur = entry;
    first = false;
  }
  out.push_back({Waypoint::Kind::Rapid, Eigen::Vector3d(cur.x(), cur.y(), plan.index_z_mm), out.back().pose});
  return out;
}

std::vector<double> rtestReadTimes(const ProbePlan& plan) {
  const MachineModel& m = plan.machine;
  std::vector<double> out;
  double t = 0.0;
  Eigen::Vector3d cur(0, 0, plan.index_z_mm);
  const auto moves = rtestCycleMoves(plan);
  Pose pose = moves.front().pose;
  for (const auto& mv : moves) {
    t += moveTime_s(mv, cur, pose, m.feeds);
    if (mv.kind == Waypoint::Kind::Index) pose = mv.pose;
    if (mv.kind == Waypoint::Kind::Read) out.push_back(std::round(t * 1000.0) / 1000.0);
    cur = mv.position_m;
  }
  return out;
}

bool rtestResetReads(const ProbePlan& plan) {
  const auto it = plan.options.find("reset_reads");
  return it != plan.options.end() && it->second == "1";
}

std::vector<std::string> rtestStrokeViolations(const ProbePlan& plan) {
  std::vector<std::string> v;
  for (const auto& mv : rtestCycleMoves(plan)) linearStrokeViolations(plan.machine, mv.position_m, {}, &v);
  for (const auto& p : plan.points) rotaryStrokeViolations(plan.machine, p.pose, p.pose_name, &v);
  return v;
}

double rtestCycleTime_s(const ProbePlan& plan) {
  // The last reading plus the withdrawal and climb (small next to the dwell and indexing).
  const MachineModel& m = plan.machine;
  const double retract = optionNumber(plan, "retract_mm");
  const ProbePoint& last = rtestResetReads(plan) ? plan.points.at(static_cast<size_t>(rtestReferencePoint(plan) - 1))
                                                 : plan.points.back();
  return rtestReadTimes(plan).back() + 60.0 * retract / m.feeds.positioning_mm_min +
         60.0 * (plan.index_z_mm - last.trigger_m_mm.z()) / m.feeds.rapid_mm_min;
}

int rtestReciprocations(const ProbePlan& plan) {
  const RtestSchedule s = rtestSchedule(plan);
  const double idle = s.interval_s - rtestCycleTime_s(plan);
  if (idle <= 0) return 0;
  return static_cast<int>(std::floor(idle / (2.0 * s.strokeTime_s())));
}

int rtestReferencePoint(const ProbePlan& plan) {
  const Kinematics k = plan.machine.kinematics;
  for (const auto& p : plan.points)
    if (tiltOf(k, p.pose) == 0.0 && p.pose.C == 0.0) return p.id;
  throw std::invalid_argument("rtest plan has no pose at tilt 0, C 0 (the reset pose of 002 Eq. (4))");
}

double RtestCycle::t_s() const {
  double s = 0.0;
  for (const auto& r : readings) s += r.t_s;
  return readings.empty() ? 0.0 : s / static_cast<double>(readings.size());
}

Eigen::Vector3d rtestSphere_w(const ProbePlan& plan, const Truth& truth, const RtestTruthExtras& extras, const Pose& pose,
                              double t_s) {
  LocationErrors e = truth.errors;
  e.kinematics = plan.machine.kinematics;
  if (truth.pose_dependent) e.values += truth.pose_dependent(pose);
  if (truth.drift) e.values += truth.drift(t_s);
  const Eigen::Vector3d read_q = T_m_w_nominal(e.kinematics, pose) * rtestNest_w(plan);
  Eigen::Vector3d r_q = read_q + extras.sphere_offset_m_mm;
  if (extras.sphere_drift_m_mm) r_q += extras.sphere_drift_m_mm(t_s);
  if (truth.linear_axis_error) r_q += truth.linear_axis_error(read_q);  // actual minus read, at the read position
  return T_m_w(e, pose).inverse() * r_q;  // 002 Eq. (1): wq = (rT_w)^-1 rq
}

RtestSeries simulateRtest(const ProbePlan& plan, const Truth& truth, const RtestTruthExtras& extras,
                          const RtestSimOptions& o) {
  if (plan.cycle != "rtest") throw std::invalid_argument("not an rtest plan");
  const RtestSchedule s = rtestSchedule(plan);
  const int n = o.cycles > 0 ? o.cycles : s.cycles();
  const Kinematics k = plan.machine.kinematics;
  const ProbePoint& rp = plan.points[rtestReferencePoint(plan) - 1];
  const bool reset = rtestResetReads(plan);
  const std::vector<double> times = rtestReadTimes(plan);  // [reset] poses [re-read]
  // The operator zeroes the sensors at the first reading of the reset pose.
  const Eigen::Vector3d ref =
      rtestSphere_w(plan, truth, extras, rp.pose, o.start_s + (reset ? times.front() : rp.t_s));
  Rng rng(o.seed, 0x7274657374ULL);  // stream "rtest"
  auto read = [&](const ProbePoint& p, int id, double t) {
    RtestReading r;
    r.pose_id = id;
    r.t_s = t;
    r.tilt_deg = tiltOf(k, p.pose);
    r.c_deg = p.pose.C;
    r.dq_w_mm = extras.sensor_response * (rtestSphere_w(plan, truth, extras, p.pose, r.t_s) - ref);
    for (const auto& st : extras.sensor_steps)
      if (r.t_s >= st.t_s) r.dq_w_mm += st.offset_w_mm;
    if (o.noise_um > 0)
      for (int i = 0; i < 3; ++i) r.dq_w_mm[i] += umToMm(o.noise_um * rng.normal());
    return r;
  };
  RtestSeries series;
  series.source = "simulated";
  for (int c = 0; c < n; ++c) {
    RtestCycle cyc;
    const double t0 = o.start_s + c * s.interval_s;
    if (reset) cyc.reset = read(rp, 0, t0 + times.front());
    for (const auto& p : plan.points) cyc.readings.push_back(read(p, p.id, t0 + p.t_s));
    if (reset) cyc.reread = read(rp, 0, t0 + times.back());
    series.cycles.push_back(cyc);
  }
  return series;
}

static void rtestTruthFrom(const JsonDoc& doc, Kinematics k, Truth& truth, RtestTruthExtras& extras) {
  const Json& j = doc.value;
  const Limits um = Limits::symmetric(kMaxLocationErrorUm, "um");
  if (j.contains("rtest")) {
    const Json& r = requireObject(doc, j, "rtest");
    extras.sphere_offset_m_mm.z() = umToMm(numberOr(doc, r, "tool_length_error_um", 0.0, um));
    if (r.contains("sensor_steps")) {
      const Json& steps = r["sensor_steps"];
      if (!steps.is_array()) doc.fail(r, "sensor_steps", "rtest.sensor_steps must be an array of {\"t_s\", \"offset_um\"}");
      if (steps.size() > static_cast<size_t>(kMaxListValues))
        doc.fail(r, "sensor_steps", fmt::format("rtest.sensor_steps has {} entries; at most {}", steps.size(), kMaxListValues));
      for (const auto& st : steps) {
        if (!st.is_object()) doc.fail(r, "sensor_steps", "rtest.sensor_steps: each entry is {\"t_s\", \"offset_um\"}");
        RtestSensorStep step;
        step.t_s = requireNumber(doc, st, "t_s", Limits::symmetric(kMaxClockSeconds, "s"));
        if (!st.contains("offset_um") || !st["offset_um"].is_array() || st["offset_um"].size() != 3)
          doc.fail(st, "offset_um", "rtest.sensor_steps: offset_um must be [dx, dy, dz] (um, workpiece frame)");
        for (int i = 0; i < 3; ++i) {
          if (!st["offset_um"][static_cast<size_t>(i)].is_number())
            doc.fail(st, "offset_um", "rtest.sensor_steps: offset_um must hold numbers");
          step.offset_w_mm[i] = umToMm(checkNumber(doc, st, "offset_um", st["offset_um"][static_cast<size_t>(i)].get<double>(), um));
        }
        extras.sensor_steps.push_back(step);
      }
    }
  }
  if (!j.contains("component_errors")) return;
  const Json& ce = requireObject(doc, j, "component_errors");
  const std::string key = std::string(1, tiltAxis(k)) + "_deg";
  if (!ce.contains(key) || !ce[key].is_array() || ce[key].empty())
    doc.fail(j, "component_errors", "component_errors needs \"" + key + "\": [angles...]");
  if (ce[key].size() > static_cast<size_t>(kMaxListValues))
    doc.fail(ce, key, fmt::format("{} has {} angles; at most {}", key, ce[key].size(), kMaxListValues));
  std::vector<double> grid;
  for (const auto& v : ce[key]) {
    if (!v.is_number()) doc.fail(ce, key, key + " must hold numbers");
    grid.push_back(checkNumber(doc, ce, key, v.get<double>(), Limits::symmetric(kMaxAngleDeg, "deg")));
    if (grid.size() > 1 && !(grid.back() > grid[grid.size() - 2])) doc.fail(ce, key, key + " must increase");
  }
  std::vector<std::vector<double>> values(kRtestParams, std::vector<double>(grid.size(), 0.0));
  for (const auto& [name, entry] : ce.items()) {
    if (name == key) continue;
    int p = -1;
    for (int q = 0; q < kRtestParams; ++q)
      if (rtestParameterName(k, q) == name) p = q;
    if (p < 0)
      doc.fail(ce, name, "component_errors: '" + name + "' is not one of the six errors of 002 Table 2 for this machine");
    if (!entry.is_object() || !entry.contains("values") || !entry["values"].is_array() ||
        entry["values"].size() != grid.size())
      doc.fail(ce, name, fmt::format("component_errors.{} needs \"values\" with {} numbers", name, grid.size()));
    const std::string unit = stringOr(doc, entry, "unit", "");
    const bool len = rtestParameterIsLength(p);
    if ((len && unit != "um") || (!len && unit != "mdeg"))
      doc.fail(entry, "unit", fmt::format("component_errors.{}: unit must be {}", name, len ? "um" : "mdeg"));
    const Limits lim = len ? um : Limits::symmetric(kMaxAngleErrorMdeg, "mdeg");
    for (size_t i = 0; i < grid.size(); ++i) {
      if (!entry["values"][i].is_number()) doc.fail(entry, "values", "component_errors." + name + ": values must be numbers");
      const double v = checkNumber(doc, entry, "values", entry["values"][i].get<double>(), lim);
      values[p][i] = len ? umToMm(v) : mdegToRad(v);
    }
  }
  const auto idx = rtestParameterIndices(k);
  auto previous = truth.pose_dependent;
  truth.pose_dependent = [grid, values, idx, k, previous](const Pose& pose) {
    ErrorVector d = previous ? previous(pose) : ErrorVector::Zero();
    const double t = tiltOf(k, pose);
    size_t i = 0;
    while (i + 2 < grid.size() && t > grid[i + 1]) ++i;
    const double w = grid.size() == 1 ? 0.0 : std::clamp((t - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0);
    for (int p = 0; p < kRtestParams; ++p)
      d[idx[p]] += grid.size() == 1 ? values[p][0] : (1.0 - w) * values[p][i] + w * values[p][i + 1];
    return d;
  };
}

void rtestTruthFromJson(const JsonDoc& doc, Kinematics k, Truth& truth, RtestTruthExtras& extras) {
  guardJson(doc, [&] { rtestTruthFrom(doc, k, truth, extras); });
}

std::string rtestResultsCsv(const ProbePlan& plan, const RtestSeries& series) {
  const char ax = tiltAxis(plan.machine.kinematics);
  std::string out = fmt::format("pose,t_s,{}_deg,C_deg,dx_um,dy_um,dz_um\n", ax);
  auto row = [&](const RtestReading& r) {
    out += fmt::format("{},{:.3f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f}\n", r.pose_id, r.t_s, r.tilt_deg, r.c_deg,
                       mmToUm(r.dq_w_mm.x()), mmToUm(r.dq_w_mm.y()), mmToUm(r.dq_w_mm.z()));
  };
  for (const auto& c : series.cycles) {
    if (c.reset) row(*c.reset);
    for (const auto& r : c.readings) row(r);
    if (c.reread) row(*c.reread);
  }
  return out;
}

RtestSeries parseRtestResults(const std::string& text, const std::string& file, const ProbePlan& plan) {
  const char ax = tiltAxis(plan.machine.kinematics);
  const std::string header = fmt::format("pose,t_s,{}_deg,C_deg,dx_um,dy_um,dz_um", ax);
  RtestSeries s;
  s.source = file;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  bool have_header = false;
  RtestCycle cur;
  double last_t = -1e300;
  const size_t N = plan.points.size();
  const ProbePoint& rp = plan.points[static_cast<size_t>(rtestReferencePoint(plan) - 1)];
  auto close = [&](int at) {
    if (cur.readings.empty()) {
      if (cur.reset) throw InputError(file, at, "a reset reading (pose 0) with no poses after it");
      return;
    }
    if (cur.readings.size() != N)
      throw InputError(file, at, fmt::format("cycle {} has {} readings, the plan has {} poses", s.cycles.size() + 1,
                                             cur.readings.size(), N));
    if (cur.reset && !cur.reread)
      throw InputError(file, at, fmt::format("cycle {} has a reset reading (pose 0) before pose 1 but no re-read "
                                             "(pose 0) after pose {}",
                                             s.cycles.size() + 1, N));
    s.cycles.push_back(cur);
    cur = RtestCycle{};
  };
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (n == 1 && line.size() >= 3 && static_cast<unsigned char>(line[0]) == 0xEF) line = line.substr(3);
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (!have_header) {
      if (line != header) throw InputError(file, n, fmt::format("expected the header '{}', got '{}'", header, line));
      have_header = true;
      continue;
    }
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string item;
    while (std::getline(ss, item, ',')) f.push_back(item);
    if (f.size() != 7) throw InputError(file, n, fmt::format("expected 7 fields '{}', got {}", header, f.size()));
    double v[7];
    for (int i = 0; i < 7; ++i) {
      try {
        v[i] = parseNumber("field", f[i]);
      } catch (const std::invalid_argument&) {
        throw InputError(file, n, fmt::format("field {} '{}' is not a number", i + 1, f[i]));
      }
    }
    // Range first: casting 2e41 to int is undefined (fuzz_rtest_results, UBSan). 0 is the reset reading.
    if (!(v[0] >= 0 && v[0] <= static_cast<double>(N)) || v[0] != std::floor(v[0]))
      throw InputError(file, n, fmt::format("pose '{}' is not a pose id of the plan (0 = the reset reading, 1..{})", f[0], N));
    const int id = static_cast<int>(v[0]);
    if (id != v[0] || id < 0 || id > static_cast<int>(N))
      throw InputError(file, n, fmt::format("pose '{}' is not a pose id of the plan (0 = the reset reading, 1..{})", f[0], N));
    const ProbePoint& p = id == 0 ? rp : plan.points[static_cast<size_t>(id - 1)];
    if (std::abs(v[2] - tiltOf(plan.machine.kinematics, p.pose)) > 1e-3 || std::abs(v[3] - p.pose.C) > 1e-3)
      throw InputError(file, n, fmt::format("pose {}: angles {:g}, {:g} deg differ from the plan's {}{}", id, v[2], v[3],
                                            p.pose_name, id == 0 ? " (the reset pose)" : ""));
    if (v[1] < last_t) throw InputError(file, n, fmt::format("time {:g} s runs backwards", v[1]));
    last_t = v[1];
    RtestReading r;
    r.pose_id = id;
    r.t_s = v[1];
    r.tilt_deg = v[2];
    r.c_deg = v[3];
    r.dq_w_mm = Eigen::Vector3d(umToMm(v[4]), umToMm(v[5]), umToMm(v[6]));
    if (id == 0) {
      if (cur.readings.empty() && !cur.reset) {
        cur.reset = r;
      } else if (cur.readings.size() == N && cur.reset) {
        cur.reread = r;
        close(n);
      } else if (cur.readings.size() == N) {
        throw InputError(file, n, fmt::format("a re-read (pose 0) after cycle {} whose reset reading (pose 0 before "
                                              "pose 1) is missing",
                                              s.cycles.size() + 1));
      } else {
        throw InputError(file, n, fmt::format("pose 0 (the reset reading) comes before pose 1 or after pose {} of a "
                                              "cycle, not after pose {}",
                                              N, cur.readings.size()));
      }
      continue;
    }
    if (id != static_cast<int>(cur.readings.size()) + 1) {
      if (id == 1) close(n);
      else
        throw InputError(file, n, fmt::format("pose {} out of order: expected {} (each cycle lists poses 1..{} in order)",
                                              id, cur.readings.size() + 1, N));
    }
    cur.readings.push_back(r);
  }
  if (!have_header) throw InputError(file, 1, "empty results file: expected the header '" + header + "'");
  close(n);
  if (s.cycles.empty()) throw InputError(file, n, "no readings");
  return s;
}

PlanRules rtestPlanRules() {
  PlanRules r;
  r.artefact_touched = false;  // the R-test's sphere sits in its nest, not on the machine's artefact
  r.check_options = rtestCheckPlanOptions;
  return r;
}

}  // namespace rotacal
