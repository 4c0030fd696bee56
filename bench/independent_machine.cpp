// The independent machine generator (bench/independent_machine.hpp): 000 Eq. (1) for the table,
// 000 Eq. (22)-(23) for the linear axes, exact ball-plane contact, written without rotacal's
// simulator so that a bench built on it tests rotacal's estimators against a second reading of
// the papers.
#include "bench/independent_machine.hpp"

#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace rotacal::independent {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A normal stream on std::mt19937_64 (the draws of one machine or of its touches).
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : rng_(seed) {}
  double operator()() { return dist_(rng_); }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  std::uint64_t raw() { return rng_(); }

 private:
  std::mt19937_64 rng_;
  std::normal_distribution<double> dist_{0.0, 1.0};
};

double declared(const ContributorSet& c, const char* id, int i = 0) {
  const Contributor* x = c.find(id);
  return x ? x->u[i] : 0.0;
}

// The faces of the square column, by rotacal's Face order (PosX, PosY, NegX, NegY, Top): outward
// normal and the two in-plane axes the form tilts turn about (sides: the horizontal one Z x n,
// then Z; top: X, then Y).
struct FaceFrame {
  Eigen::Vector3d n, u, v;
};
FaceFrame faceFrame(Face face) {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d n;
  switch (face) {
    case Face::PosX: n = Eigen::Vector3d::UnitX(); break;
    case Face::PosY: n = Eigen::Vector3d::UnitY(); break;
    case Face::NegX: n = -Eigen::Vector3d::UnitX(); break;
    case Face::NegY: n = -Eigen::Vector3d::UnitY(); break;
    case Face::Top: return {z, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
  }
  return {n, z.cross(n), z};
}

// The face's centre on the nominal column (workpiece frame, mm): the top's centre, or a side's
// centre half the width out and half the height down.
Eigen::Vector3d faceCentre_w(const SquareColumn& col, Face face) {
  if (face == Face::Top) return col.top_centre_w;
  const FaceFrame f = faceFrame(face);
  const double half_width = std::abs(f.n.x()) > 0.5 ? col.size_mm.x() / 2 : col.size_mm.y() / 2;
  return col.top_centre_w + half_width * f.n - Eigen::Vector3d(0, 0, col.size_mm.z() / 2);
}

// The set-up's turn: about X first, then Y, then Z (exact).
Eigen::Matrix3d setupRotation(const Machine& m) {
  const Eigen::Vector3d& r = m.setup_rotation_rad;
  return (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Matrix3d rotationOf(const Eigen::Matrix4d& T) { return T.topLeftCorner<3, 3>(); }
Eigen::Vector3d apply(const Eigen::Matrix4d& T, const Eigen::Vector3d& p) {
  return T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>();
}

// 000 Eq. (22)-(23) for one machine: per axis a node spacing uniform in the file's range, its
// scale, the node values per error direction, then the three squarenesses (one fixed order).
LinearAxes drawLinearAxes(const ContributorSet& c, const MachineModel& machine, Normal& n) {
  const char* scale_id[3] = {"E_xx_lin", "E_yy_lin", "E_zz_lin"};
  // rand_id[a][b]: E_ba,rand of axis a.
  const char* rand_id[3][3] = {{"E_xx_rand", "E_yx_rand", "E_zx_rand"},
                               {"E_xy_rand", "E_yy_rand", "E_zy_rand"},
                               {"E_xz_rand", "E_yz_rand", "E_zz_rand"}};
  const AxisRange strokes[3] = {machine.x, machine.y, machine.z};
  LinearAxes ax;
  for (int a = 0; a < 3; ++a) {
    const double p = n.uniform(c.node_spacing_min_mm, c.node_spacing_max_mm);
    ax.spacing_mm[a] = p;
    ax.first[a] = static_cast<int>(std::floor(strokes[a].min / p)) - 2;
    const int last = static_cast<int>(std::ceil(strokes[a].max / p)) + 2;
    ax.scale[a] = declared(c, scale_id[a]) * n();
    for (int b = 0; b < 3; ++b) {
      const double u = declared(c, rand_id[a][b]);
      auto& v = ax.node_mm[a][b];
      for (int i = ax.first[a]; i <= last; ++i) v.push_back(u * n());
    }
  }
  ax.S_xy = declared(c, "S_xy") * n();
  ax.S_xz = declared(c, "S_xz") * n();
  ax.S_yz = declared(c, "S_yz") * n();
  return ax;
}

}  // namespace

Eigen::Matrix4d Dx(double mm) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(0, 3) = mm;
  return T;
}
Eigen::Matrix4d Dy(double mm) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(1, 3) = mm;
  return T;
}
Eigen::Matrix4d Dz(double mm) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(2, 3) = mm;
  return T;
}
Eigen::Matrix4d Da(double a) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(1, 1) = std::cos(a), T(1, 2) = -std::sin(a);
  T(2, 1) = std::sin(a), T(2, 2) = std::cos(a);
  return T;
}
Eigen::Matrix4d Db(double b) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(0, 0) = std::cos(b), T(0, 2) = std::sin(b);
  T(2, 0) = -std::sin(b), T(2, 2) = std::cos(b);
  return T;
}
Eigen::Matrix4d Dc(double c) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T(0, 0) = std::cos(c), T(0, 1) = -std::sin(c);
  T(1, 0) = std::sin(c), T(1, 1) = std::cos(c);
  return T;
}

Eigen::Matrix4d tableTransform(const LocationErrors& e, double A_deg, double C_deg) {
  const double A = A_deg * kPi / 180.0, C = C_deg * kPi / 180.0;
  // 000 Eq. (1): rT_w = yT_a aT_c.
  const Eigen::Matrix4d yTa = Dx(e.get("dx_AY")) * Dy(e.get("dy_AY")) * Dz(e.get("dz_AY")) * Da(e.get("a_AY")) *
                              Db(e.get("b_AY")) * Dc(e.get("c_AY")) * Da(-A);
  const Eigen::Matrix4d aTc = Dy(e.get("dy_CA")) * Db(e.get("b_CA")) * Dc(-C);
  return yTa * aTc;
}

double LinearAxes::randomPart(int axis, int direction, double q) const {
  const double p = spacing_mm[axis];
  const auto& v = node_mm[axis][direction];
  const double x = q / p;
  const int i = static_cast<int>(std::floor(x));
  const int k = i - first[axis];
  if (k < 0 || k + 1 >= static_cast<int>(v.size()))
    throw std::out_of_range("linear axis " + std::string(1, "XYZ"[axis]) + " read at " + std::to_string(q) +
                            " mm, beyond its drawn nodes");
  const double f = x - i;
  return (1.0 - f) * v[static_cast<size_t>(k)] + f * v[static_cast<size_t>(k + 1)];
}

double LinearAxes::component(int axis, int direction, double q) const {
  double e = randomPart(axis, direction, q);
  if (direction == axis) e += scale[axis] * q;          // E_aa,lin q (Eq. (22))
  if (axis == 1 && direction == 0) e += S_xy * q;       // Eq. (23)
  if (axis == 2 && direction == 0) e += S_xz * q;
  if (axis == 2 && direction == 1) e += S_yz * q;
  return e;
}

Eigen::Vector3d LinearAxes::error(const Eigen::Vector3d& c) const {
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a) e[b] += component(a, b, c[a]);
  return e;
}

Machine drawMachine(const ContributorSet& c, const MachineModel& machine, const DrawOptions& o, std::uint64_t seed) {
  // Every value is drawn whatever the options, in one fixed order, so that switching a
  // contributor off leaves every other draw of the machine as it was.
  Normal n(seed);
  Machine m;
  m.location.kinematics = Kinematics::TableAC;
  const auto& params = locationParameters(Kinematics::TableAC);
  const char* order[8] = {"dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA"};
  for (int i = 0; i < 8; ++i) {
    const int k = parameterIndex(Kinematics::TableAC, order[i]);
    const bool length = params[static_cast<size_t>(k)].kind == ParamKind::Length;
    m.location.setReportValue(k, o.centre[static_cast<size_t>(i)] + (length ? o.sd_um : o.sd_mdeg) * n());
  }
  Eigen::Vector3d t, r;
  for (int i = 0; i < 3; ++i) t[i] = declared(c, "setup_position", i) * n();
  for (int i = 0; i < 3; ++i) r[i] = declared(c, "setup_orientation", i) * n();
  if (o.setup) m.setup_translation_mm = t, m.setup_rotation_rad = r;
  for (auto& f : m.form) {
    FaceForm d{declared(c, "form_error", 0) * n(), declared(c, "form_error", 1) * n(),
               declared(c, "form_error", 1) * n()};
    if (o.form) f = d;
  }
  LinearAxes ax = drawLinearAxes(c, machine, n);
  m.axes = ax;
  m.has_linear_axes = o.linear_axes;
  if (!o.linear_axes) {
    m.axes.scale = {0, 0, 0};
    m.axes.S_xy = m.axes.S_xz = m.axes.S_yz = 0;
    for (auto& axis : m.axes.node_mm)
      for (auto& dir : axis)
        for (double& v : dir) v = 0;
  }
  for (double& pt : m.pretravel_mm) {
    const double d = declared(c, "probe_pretravel") * n();
    if (o.pretravel) pt = d;
  }
  if (o.repeatability) m.repeatability_mm = declared(c, "probe_repeatability");
  if (o.roughness) m.roughness_mm = declared(c, "surface_roughness");
  m.touch_seed = n.raw();
  return m;
}

LinearAxes drawLinearAxes(const ContributorSet& c, const MachineModel& machine, std::uint64_t seed) {
  Normal n(seed);
  return drawLinearAxes(c, machine, n);
}

Machine cleanMachine(const LocationErrors& errors) {
  Machine m;
  m.location = errors;
  return m;
}

Eigen::Vector3d sphereCentre_w(const ProbePlan& plan, const ProbePoint& point, const Machine& m) {
  if (!point.sphere) throw std::runtime_error("point " + std::to_string(point.id) + " touches no sphere");
  const Eigen::Vector3d& c = point.sphere->center_w_mm;
  if (plan.cycle != "spaceframe") return c + m.setup_translation_mm;
  // The frame's origin on the table, as the plan states it ("x,y,z" mm).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  const auto it = plan.options.find("origin_w_mm");
  if (it == plan.options.end()) throw std::runtime_error("a spaceframe plan without origin_w_mm");
  {
    std::string text = it->second;
    for (char& ch : text)
      if (ch == ',') ch = ' ';
    std::istringstream in(text);
    if (!(in >> origin.x() >> origin.y() >> origin.z())) throw std::runtime_error("origin_w_mm: " + it->second);
  }
  return setupRotation(m) * (c - origin) + origin + m.setup_translation_mm;
}

FacePlane facePlane_m(const ProbePlan& plan, const ProbePoint& point, const Machine& m) {
  if (!plan.machine.artefact) throw std::runtime_error("the machine has no square column to probe");
  const SquareColumn& col = *plan.machine.artefact;
  const FaceFrame f = faceFrame(point.face);
  if ((f.n - point.normal_w).norm() > 1e-9)
    throw std::runtime_error("point " + std::to_string(point.id) + ": its normal is not its face's");
  const FaceForm& form = m.form[static_cast<size_t>(point.face)];
  // The face as it is on the piece: offset along its normal, tilted about its in-plane axes at
  // its centre (exact rotations).
  const Eigen::Matrix3d tilt = (Eigen::AngleAxisd(form.tilt_u_rad, f.u) * Eigen::AngleAxisd(form.tilt_v_rad, f.v)).toRotationMatrix();
  const Eigen::Vector3d centre = faceCentre_w(col, point.face);
  const Eigen::Vector3d x_piece = centre + form.offset_mm * f.n;
  const Eigen::Vector3d n_piece = tilt * f.n;
  // The set-up: turned about the nominal top centre (X first, then Y, then Z), then shifted.
  const Eigen::Matrix3d R = setupRotation(m);
  const Eigen::Vector3d x_w = R * (x_piece - col.top_centre_w) + col.top_centre_w + m.setup_translation_mm;
  const Eigen::Vector3d n_w = R * n_piece;
  // The table at the commanded pose carries it into the machine frame.
  const Eigen::Matrix4d T = tableTransform(m.location, point.pose.A, point.pose.C);
  return {apply(T, x_w), (rotationOf(T) * n_w).normalized()};
}

MeasurementRun measure(const ProbePlan& plan, const Machine& m, const std::optional<Chip>& chip) {
  if (plan.machine.kinematics != Kinematics::TableAC)
    throw std::runtime_error("the independent generator models an A/C tilting table (000) only");
  Normal touch(m.touch_seed);
  const double r = plan.machine.probe.ball_radius_mm();
  MeasurementRun run;
  run.source = "independent generator";
  for (const ProbePoint& p : plan.points) {
    // Two draws per touch whatever is declared, so every touch keeps its draws across options.
    const double n_rep = touch(), n_rough = touch();
    double h = m.roughness_mm * n_rough;
    if (chip && chip->point_id == p.id) h += chip->height_mm;
    const Eigen::Vector3d u = p.approach_m.normalized();
    const Eigen::Vector3d& c0 = p.trigger_m_mm;
    // Where along the move the actual ball, at c0 + e when the reading is c0, first touches the
    // surface raised by h: a face plane, or a sphere (its centre placed by the set-up:
    // sphereCentre_w).
    std::function<double(const Eigen::Vector3d&)> contact;
    if (p.sphere) {
      const Eigen::Matrix4d T = tableTransform(m.location, p.pose.A, p.pose.C);
      const Eigen::Vector3d x = apply(T, sphereCentre_w(plan, p, m));
      const double rho = r + p.sphere->radius_mm + h;
      // |d + s u| = rho, d = c0 + e - x: the smaller root (the ball comes from outside).
      contact = [x, rho, u, id = p.id](const Eigen::Vector3d& b0) {
        const Eigen::Vector3d d = b0 - x;
        const double du = d.dot(u), disc = du * du - d.squaredNorm() + rho * rho;
        if (disc < 0) throw std::runtime_error("point " + std::to_string(id) + ": the approach misses the sphere");
        return -du - std::sqrt(disc);
      };
    } else {
      const FacePlane plane = facePlane_m(plan, p, m);
      const double nu = plane.normal_m.dot(u);
      if (std::abs(nu) < 1e-6) throw std::runtime_error("point " + std::to_string(p.id) + ": approach along its face");
      contact = [plane, nu, r, h](const Eigen::Vector3d& b0) { return (r + h - plane.normal_m.dot(b0 - plane.point_m)) / nu; };
    }
    // The actual ball is the read position plus the linear axes' error there: solve for s with
    // the ball at c0 + s u + E(c0 + s u). E varies by well under 1e-3 mm per mm, so the fixed
    // point converges geometrically within a few steps.
    double s = 0.0;
    for (int it = 0;; ++it) {
      const Eigen::Vector3d c = c0 + s * u;
      const Eigen::Vector3d e = m.has_linear_axes ? m.axes.error(c) : Eigen::Vector3d::Zero();
      const double next = contact(c0 + e);
      const bool done = std::abs(next - s) < 1e-13;
      s = next;
      if (done) break;
      if (it > 100) throw std::runtime_error("point " + std::to_string(p.id) + ": contact did not converge");
    }
    // The signal comes late by the pretravel of the probing direction, blended by squared
    // direction cosines, and scatters by the repeatability: both along the move.
    double pretravel = 0.0;
    for (int k = 0; k < 3; ++k) pretravel += u[k] * u[k] * m.pretravel_mm[static_cast<size_t>(2 * k + (u[k] < 0 ? 1 : 0))];
    s += pretravel + m.repeatability_mm * n_rep;
    if (s < -plan.machine.approach_mm || s > plan.machine.overtravel_mm)
      throw std::runtime_error("point " + std::to_string(p.id) + ": no trigger within the probing move (" +
                               std::to_string(s) + " mm from the nominal trigger)");
    TriggerPoint t;
    t.point_id = p.id;
    t.position_m_mm = c0 + s * u;
    t.t_s = p.t_s;
    run.points.push_back(t);
  }
  return run;
}

double Head::angularErrorMdeg(double theta_deg) const {
  const double th = theta_deg * kPi / 180.0;
  return angular_mdeg[0] + angular_mdeg[1] * theta_deg / 90.0 + angular_mdeg[2] * std::sin(th) +
         angular_mdeg[3] * std::sin(2 * th);
}

namespace {
// The read plane of a stepping axis: its transverse axis (Y for A, X for B) and the axis out of
// the plane (the stepping axis itself).
int transverseOf(char axis) { return axis == 'A' ? 1 : 0; }
int outOfPlaneOf(char axis) { return axis == 'A' ? 0 : 1; }
}  // namespace

Eigen::Vector3d Head::beamT(char axis) const {
  Eigen::Vector3d b = Eigen::Vector3d::Unit(transverseOf(axis));
  b.z() += beam_tilt_rad[0];
  b[outOfPlaneOf(axis)] += beam_tilt_rad[1];
  return b.normalized();
}
Eigen::Vector3d Head::beamZ(char axis) const {
  Eigen::Vector3d b = Eigen::Vector3d::UnitZ();
  b[transverseOf(axis)] += beam_tilt_rad[2];
  b[outOfPlaneOf(axis)] += beam_tilt_rad[3];
  return b.normalized();
}

Head drawHead(const ContributorSet& c, const MachineModel& machine, const HeadDrawOptions& o, std::uint64_t seed) {
  // Every value is drawn whatever the options, in one fixed order (as drawMachine).
  Normal n(seed);
  Head h;
  h.dR_mm = 1e-3 * (o.dR_um + o.sd_dR_um * n());
  if (!o.pivot) h.dR_mm = 0.0;
  for (size_t i = 0; i < 4; ++i) h.angular_mdeg[i] = o.angular_mdeg[i] + o.sd_mdeg * n();
  const LinearAxes axes = drawLinearAxes(c, machine, n);
  h.has_linear_axes = o.linear_axes;
  if (o.linear_axes) h.axes = axes;
  for (double& t : h.beam_tilt_rad) {
    const double d = declared(c, "laser_alignment") * n();
    if (o.alignment) t = d;
  }
  if (o.per_reading) {
    h.laser_resolution_mm = declared(c, "laser_resolution");
    h.sphere_form_mm = declared(c, "laser_sphere_form");
    h.lateral_coupling_mm = declared(c, "laser_lateral_coupling");
  }
  h.reading_seed = n.raw();
  return h;
}

TooltipRun measureHead(const ProbePlan& plan, const Head& h, const std::optional<ReadingChip>& chip) {
  if (plan.cycle != "tooltip") throw std::runtime_error("measureHead reads a tooltip plan");
  const auto option = [&](const char* key) {
    const auto it = plan.options.find(key);
    if (it == plan.options.end()) throw std::runtime_error(std::string("a tooltip plan without ") + key);
    return it->second;
  };
  const char axis = option("axis").at(0);
  if (axis != 'A' && axis != 'B') throw std::runtime_error("tooltip plan: axis " + option("axis"));
  const double R = std::stod(option("radius_mm"));
  const Eigen::Vector3d bt = h.beamT(axis), bz = h.beamZ(axis);
  Normal draw(h.reading_seed);
  // Per point: the tip where the head really puts it, and the two beams' raw readings of it.
  struct Raw {
    double angle_deg = 0, t_mm = 0, z_mm = 0;
  };
  std::vector<Raw> raw;
  std::map<std::string, size_t> zero;  // the sweep's zero reading: its first pose at 0 deg
  for (const ProbePoint& p : plan.points) {
    const double theta = axis == 'A' ? p.pose.A : p.pose.B;
    // 004 Sec. V: the tip hangs at R + dR below the pivot, the head turned to its command plus
    // its angular positioning error; the pivot goes where the linear axes put its command.
    double A = p.pose.A, B = p.pose.B;
    (axis == 'A' ? A : B) += h.angularErrorMdeg(theta) / 1000.0;
    const Eigen::Vector3d pivot = p.trigger_m_mm + (h.has_linear_axes ? h.axes.error(p.trigger_m_mm) : Eigen::Vector3d::Zero());
    const Eigen::Vector3d tip = apply(Da(A * kPi / 180.0) * Db(B * kPi / 180.0), Eigen::Vector3d(0, 0, -(R + h.dR_mm))) + pivot;
    const Eigen::Vector3d dev = tip - p.contact_w_mm;
    Raw r;
    r.angle_deg = theta;
    r.t_mm = bt.dot(dev);
    r.z_mm = bz.dot(dev);
    for (double* v : {&r.t_mm, &r.z_mm}) {
      const double n_res = draw(), n_form = draw(), n_coupling = draw();
      *v += h.laser_resolution_mm * n_res + h.sphere_form_mm * n_form + h.lateral_coupling_mm * n_coupling;
    }
    if (chip && chip->point_id == p.id) (chip->z ? r.z_mm : r.t_mm) += chip->mm;
    if (std::abs(theta) < 1e-9 && !zero.count(p.pose_name)) zero[p.pose_name] = raw.size();
    raw.push_back(r);
  }
  TooltipRun run;
  for (size_t k = 0; k < plan.points.size(); ++k) {
    const auto it = zero.find(plan.points[k].pose_name);
    if (it == zero.end()) throw std::runtime_error("tooltip plan: sweep " + plan.points[k].pose_name + " has no pose at 0 deg");
    const Raw& z = raw[it->second];
    TooltipReading r;
    r.angle_deg = raw[k].angle_deg;
    r.t_um = 1e3 * (raw[k].t_mm - z.t_mm);
    r.z_um = 1e3 * (raw[k].z_mm - z.z_mm);
    run.push_back(r);
  }
  return run;
}

}  // namespace rotacal::independent
