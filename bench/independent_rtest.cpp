// The independent generator's R-test (bench/independent_rtest.hpp): 002 Eq. (1)-(4) written again,
// with the nest's sensors, the sphere on the spindle and the linear axes of 000 Eq. (22)-(23).
#include "bench/independent_rtest.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace rotacal::independent {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

double declared(const ContributorSet& c, const char* id, int i = 0) {
  const Contributor* x = c.find(id);
  return x ? x->u[i] : 0.0;
}

Eigen::Vector3d apply(const Eigen::Matrix4d& T, const Eigen::Vector3d& p) {
  return T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>();
}

double planNumber(const ProbePlan& plan, const char* key, double otherwise) {
  const auto it = plan.options.find(key);
  return it == plan.options.end() ? otherwise : std::stod(it->second);
}

// The tilt of a B/C plan's pose: B.
double tiltOfPose(const Pose& p) { return p.B; }

// The point at tilt 0, C 0: 002 Eq. (4)'s reset pose.
const ProbePoint& resetPoint(const ProbePlan& plan) {
  for (const ProbePoint& p : plan.points)
    if (tiltOfPose(p.pose) == 0.0 && p.pose.C == 0.0) return p;
  throw std::runtime_error("an rtest plan without a pose at B 0, C 0");
}

// 002 Eq. (1)-(3): the sphere's centre in the workpiece frame at a pose and time (s from the
// series' start).
Eigen::Vector3d sphere_w(const RtestMachine& m, const ProbePoint& p, double t_s) {
  const double B = tiltOfPose(p.pose), C = p.pose.C;
  // Eq. (3): the commanded centre, the nest's position turned to the pose.
  const Eigen::Vector3d rq = apply(Db(-B * kDeg) * Dc(-C * kDeg), p.contact_w_mm);
  if ((rq - p.trigger_m_mm).norm() > 1e-6)
    throw std::runtime_error("point " + std::to_string(p.id) + ": the plan's commanded centre is not 002 Eq. (3)'s");
  Eigen::Vector3d actual = rq + m.sphere_offset_mm + m.drift_mm_per_s * t_s;
  if (m.has_linear_axes) actual += m.axes.error(rq);  // actual minus read, at the read (commanded) position
  // Eq. (1): wq = (rT_w)^-1 rq.
  return apply(tableTransformBC(m.location, B, C).inverse(), actual);
}

}  // namespace

Eigen::Matrix4d tableTransformBC(const LocationErrors& e, double B_deg, double C_deg) {
  if (e.kinematics != Kinematics::TableBC) throw std::invalid_argument("tableTransformBC: not a B/C table's errors");
  const double B = B_deg * kDeg, C = C_deg * kDeg;
  // 002 Eq. (2): rT_w = rT_b bT_c.
  const Eigen::Matrix4d rTb = Da(e.get("a_BY")) * Db(e.get("b_BY")) * Dc(e.get("c_BY")) * Dx(e.get("dx_BY")) *
                              Dy(e.get("dy_CB")) * Dz(e.get("dz_BY")) * Db(-B);
  const Eigen::Matrix4d bTc = Da(e.get("a_CB")) * Dx(e.get("dx_CB")) * Dc(-C);
  return rTb * bTc;
}

Eigen::Vector3d RtestMachine::sensorDirection(int i) const {
  // Sensor i tilted towards the other two axes j < k by direction[2 i], direction[2 i + 1].
  Eigen::Vector3d n = Eigen::Vector3d::Unit(i);
  const int j = i == 0 ? 1 : 0, k = i == 2 ? 1 : 2;
  n[j] += direction[static_cast<size_t>(2 * i)];
  n[k] += direction[static_cast<size_t>(2 * i + 1)];
  return n.normalized();
}

Eigen::Matrix3d RtestMachine::response() const {
  Eigen::Matrix3d S;
  for (int i = 0; i < 3; ++i) S.row(i) = (1.0 + gain[static_cast<size_t>(i)]) * sensorDirection(i).transpose();
  return S;
}

RtestMachine drawRtestMachine(const ContributorSet& c, const ProbePlan& plan, const RtestDrawOptions& o, std::uint64_t seed) {
  if (plan.cycle != "rtest" || plan.machine.kinematics != Kinematics::TableBC)
    throw std::runtime_error("the independent R-test is 002's B/C table: an rtest plan on a table_bc machine");
  // Every value is drawn whatever the options, in one fixed order, so that switching a
  // contributor off leaves every other draw of the machine as it was.
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto n = [&] { return normal(rng); };
  RtestMachine m;
  m.location.kinematics = Kinematics::TableBC;
  const auto& params = locationParameters(Kinematics::TableBC);
  for (int k = 0; k < kNumLocationErrors; ++k) {
    const bool length = params[static_cast<size_t>(k)].kind == ParamKind::Length;
    m.location.setReportValue(k, o.centre[static_cast<size_t>(k)] + (length ? o.sd_um : o.sd_mdeg) * n());
  }
  Eigen::Vector3d s, d;
  for (int i = 0; i < 3; ++i) s[i] = declared(c, "rtest_sphere_offset", i) * n();
  for (int i = 0; i < 3; ++i) d[i] = declared(c, "rtest_cycle_drift", i) * n();
  if (o.sphere) m.sphere_offset_mm = s;
  // The drift is declared over one measuring cycle: its rate is that over the cycle's time.
  if (o.drift) m.drift_mm_per_s = d / rtestCycleTime_s(plan);
  std::array<double, 3> g{};
  std::array<double, 6> dir{};
  for (double& x : g) x = declared(c, "rtest_sensor_gain") * n();
  for (double& x : dir) x = declared(c, "rtest_sensor_direction") * n();
  if (o.sensors) m.gain = g, m.direction = dir;
  const LinearAxes axes = drawLinearAxes(c, plan.machine, static_cast<std::uint64_t>(rng()));
  m.has_linear_axes = o.linear_axes;
  if (o.linear_axes) m.axes = axes;
  if (o.noise) m.sensor_noise_mm = 1e-3 * planNumber(plan, "sensor_noise_um", 0.2);
  if (o.form) m.sphere_form_mm = declared(c, "rtest_sphere_form");
  m.reading_seed = rng();
  return m;
}

RtestMachine cleanRtestMachine(const LocationErrors& errors) {
  RtestMachine m;
  m.location = errors;
  return m;
}

RtestSeries measureRtest(const ProbePlan& plan, const RtestMachine& m, const std::optional<RtestChip>& chip) {
  if (plan.cycle != "rtest" || plan.machine.kinematics != Kinematics::TableBC)
    throw std::runtime_error("measureRtest reads an rtest plan on a B/C table (002)");
  const RtestSchedule schedule = rtestSchedule(plan);
  const int cycles = schedule.cycles();
  const bool reset = rtestResetReads(plan);
  // When each reading of a cycle is taken, from the cycle's start: [reset] poses [re-read].
  const std::vector<double> times = rtestReadTimes(plan);
  if (times.size() != plan.points.size() + (reset ? 2u : 0u)) throw std::runtime_error("rtest plan: reading times");
  const ProbePoint& rp = resetPoint(plan);
  // 002 Eq. (4): the sensors are zeroed at the first cycle's reset reading.
  const Eigen::Vector3d zero = sphere_w(m, rp, reset ? times.front() : rp.t_s);
  const Eigen::Matrix3d S = m.response();
  std::mt19937_64 rng(m.reading_seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto read = [&](int cycle, const ProbePoint& p, int pose_id, double t) {
    RtestReading r;
    r.pose_id = pose_id;
    r.t_s = t;
    r.tilt_deg = tiltOfPose(p.pose);
    r.c_deg = p.pose.C;
    r.dq_w_mm = S * (sphere_w(m, p, t) - zero);
    for (int i = 0; i < 3; ++i) {
      const double n_sensor = normal(rng), n_form = normal(rng);
      r.dq_w_mm[i] += m.sensor_noise_mm * n_sensor + m.sphere_form_mm * n_form;
    }
    if (chip && chip->cycle == cycle && chip->pose_id == pose_id && pose_id != 0) r.dq_w_mm[chip->axis] += chip->mm;
    return r;
  };
  RtestSeries series;
  series.source = "independent generator";
  for (int k = 0; k < cycles; ++k) {
    const double t0 = k * schedule.interval_s;
    RtestCycle cy;
    const size_t first = reset ? 1 : 0;
    if (reset) cy.reset = read(k, rp, 0, t0 + times.front());
    for (size_t i = 0; i < plan.points.size(); ++i)
      cy.readings.push_back(read(k, plan.points[i], plan.points[i].id, t0 + times[first + i]));
    if (reset) cy.reread = read(k, rp, 0, t0 + times.back());
    series.cycles.push_back(cy);
  }
  return series;
}

PerTiltTruth perTiltTruth(const ProbePlan& plan, const RtestMachine& m) {
  const LocationErrors& e = m.location;
  PerTiltTruth out;
  for (const ProbePoint& p : plan.points) {
    const double B = tiltOfPose(p.pose);
    bool seen = false;
    for (double b : out.tilt_deg) seen = seen || b == B;
    if (!seen) out.tilt_deg.push_back(B);
  }
  std::sort(out.tilt_deg.begin(), out.tilt_deg.end());
  // The table's pose at each tilt: rT_b bT_c at C = 0, written as P(B) Db(-B).
  std::vector<Eigen::Vector3d> t, r;
  for (double B : out.tilt_deg) {
    const Eigen::Matrix4d P = tableTransformBC(e, B, 0.0) * Db(B * kDeg);
    const Eigen::Matrix3d R = P.topLeftCorner<3, 3>();
    // R = Rx(a) Ry(b) Rz(c).
    const double b = std::asin(R(0, 2)), a = std::atan2(-R(1, 2), R(2, 2)), c = std::atan2(-R(0, 1), R(0, 0));
    r.emplace_back(a, b, c);
    t.push_back(R.transpose() * P.topRightCorner<3, 1>());
  }
  // The reset's convention: dz and c at tilt 0 are 0.
  size_t zero = out.tilt_deg.size();
  for (size_t i = 0; i < out.tilt_deg.size(); ++i)
    if (out.tilt_deg[i] == 0.0) zero = i;
  if (zero == out.tilt_deg.size()) throw std::runtime_error("an rtest plan without tilt 0");
  const double e0 = t[zero].z(), c0 = r[zero].z();
  for (size_t i = 0; i < out.tilt_deg.size(); ++i) {
    const double B = out.tilt_deg[i] * kDeg;
    const Eigen::Vector3d axis(-std::sin(B), 0.0, std::cos(B));  // the C axis at tilt B: Db(-B) z
    const Eigen::Vector3d ti = 1e3 * (t[i] - e0 * axis), ri = 1e3 / kDeg * (r[i] - c0 * axis);
    out.value.push_back({ti.x(), ti.y(), ti.z(), ri.x(), ri.y(), ri.z()});
  }
  return out;
}

}  // namespace rotacal::independent
