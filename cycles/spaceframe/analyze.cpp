#include "cycles/spaceframe/analyze.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/report_envelope.hpp"
#include "core/require_valid.hpp"
#include "core/transforms.hpp"
#include "core/uncertainty_budget.hpp"
#include "core/least_squares.hpp"
#include "core/units.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

namespace {


Eigen::Isometry3d setupTransform(const Eigen::Vector3d& t, const Eigen::Vector3d& w, const Eigen::Vector3d& pivot) {
  return Eigen::Translation3d(t + pivot) * Da(w.x()) * Db(w.y()) * Dc(w.z()) * Eigen::Translation3d(-pivot);
}

}  // namespace

SpaceframeLayout SpaceframeLayout::fromOptions(const CycleOptions& options) {
  SpaceframeLayout l;
  OptionTable("spaceframe")
      .list("theta_list", &l.theta_deg)
      .list("phi_list", &l.phi_deg)
      .vec3("origin_w_mm", &l.origin_w_mm)
      .number("sphere_diameter_mm", &l.sphere_diameter_mm)
      .number("mpe_a_um", &l.spec.A_um)
      .number("mpe_k_um_per_m", &l.spec.K_um_per_m)
      .number("min_touch_angle_deg", &l.min_touch_angle_deg)
      .text("nominal_from", &l.nominal_from)
      .on("frame_file", [&](const std::string&, const std::string& v) { l.frame = loadFrameCalibration(v); })
      .number("frame_u_um", &l.frame.u_um)
      .text("frame_source", &l.frame.source)
      .on("frame_spheres_mm",
          [&](const std::string& k, const std::string& value) {
            const auto v = parseNumberList(k, value);
            if (v.size() != 21) throw std::invalid_argument("option frame_spheres_mm: expected 7 x (x,y,z), 21 numbers");
            for (size_t i = 0; i < 7; ++i) l.frame.spheres_mm[i] = Eigen::Vector3d(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
          })
      .read(options);
  if (options.count("frame_file") && (options.count("frame_spheres_mm") || options.count("frame_u_um")))
    throw std::invalid_argument("option frame_file cannot be combined with frame_spheres_mm or frame_u_um");
  if (!(l.frame.u_um >= 0 && l.frame.u_um <= 1000)) throw std::invalid_argument("option frame_u_um must lie in [0, 1000] um");
  if (!(l.sphere_diameter_mm > 0)) throw std::invalid_argument("option sphere_diameter_mm must be positive");
  if (l.spec.A_um < 0 || l.spec.K_um_per_m < 0 || l.spec.A_um + l.spec.K_um_per_m <= 0)
    throw std::invalid_argument("options mpe_a_um and mpe_k_um_per_m must be >= 0 and not both zero");
  if (l.nominal_from != "table1" && l.nominal_from != "initial")
    throw std::invalid_argument("option nominal_from must be table1 or initial, got '" + l.nominal_from + "'");
  if (!(l.min_touch_angle_deg >= 0 && l.min_touch_angle_deg < 90))
    throw std::invalid_argument("option min_touch_angle_deg must lie in [0, 90)");
  // A pose per (theta, phi) pair, up to five touches on each of the seven spheres.
  const double poses = static_cast<double>(l.theta_deg.size() * l.phi_deg.size());
  requirePlanSize(fmt::format("options theta_list ({} values) and phi_list ({} values)", l.theta_deg.size(),
                              l.phi_deg.size()),
                  35.0 * poses, poses);
  return l;
}

CycleOptions SpaceframeLayout::toOptions() const {
  CycleOptions o = {{"theta_list", numberListOption(theta_deg)},
          {"phi_list", numberListOption(phi_deg)},
          {"origin_w_mm", fmt::format("{:g},{:g},{:g}", origin_w_mm.x(), origin_w_mm.y(), origin_w_mm.z())},
          {"sphere_diameter_mm", fmt::format("{:g}", sphere_diameter_mm)},
          {"mpe_a_um", fmt::format("{:g}", spec.A_um)},
          {"mpe_k_um_per_m", fmt::format("{:g}", spec.K_um_per_m)},
          {"min_touch_angle_deg", fmt::format("{:g}", min_touch_angle_deg)},
          {"nominal_from", nominal_from}};
  if (frame.spheres_mm != FrameCalibration{}.spheres_mm || frame.u_um != 0.0) {
    std::string xyz;
    for (const auto& c : frame.spheres_mm)
      xyz += fmt::format("{}{:.6f},{:.6f},{:.6f}", xyz.empty() ? "" : ",", c.x(), c.y(), c.z());
    o["frame_spheres_mm"] = xyz;
    o["frame_u_um"] = fmt::format("{:g}", frame.u_um);
    o["frame_source"] = frame.source;
  }
  return o;
}

ProbePlan makeSpaceframePlan(const MachineModel& machine, const CycleOptions& options) {
  if (machine.kinematics != Kinematics::TableAC)
    throw std::invalid_argument("cycle spaceframe maps theta onto C and phi onto A: it needs an A/C table (table_ac)");
  const SpaceframeLayout l = SpaceframeLayout::fromOptions(options);
  const RotaryAxis& a_axis = machine.rotaryAxis('A');
  for (double phi : l.phi_deg)
    if (!a_axis.continuous && !a_axis.stroke_deg.contains(phi))
      throw std::invalid_argument(fmt::format(
          "phi = {:g} deg needs A = {:g} deg, outside the A stroke [{:g}, {:g}] deg of machine '{}' (phi maps onto A, "
          "docs/spaceframe.md): set phi_list to tilts within the stroke, e.g. --set phi_list=-90,-45,0",
          phi, phi, a_axis.stroke_deg.min, a_axis.stroke_deg.max, machine.name));
  const double R = l.sphere_diameter_mm / 2.0;
  const double r = machine.probe.ball_radius_mm();
  const double rho = R + r;
  const auto& table1 = l.frame.spheres_mm;

  ProbePlan plan;
  plan.cycle = "spaceframe";
  plan.machine = machine;
  plan.machine.artefact.reset();  // the space frame stands on the table instead of the column
  plan.options = l.toOptions();
  double sweep = 0.0;
  for (const auto& c : table1) sweep = std::max(sweep, (l.origin_w_mm + c).norm());
  plan.index_z_mm = std::max(sweep, machine.table_diameter_mm / 2) + rho + machine.clearance_mm;

  // Touch directions (machine frame, axis-aligned so every dialect can probe them): the ball
  // moves along u and meets the sphere where its outward normal is -u. A sphere stands on a stem
  // along the frame's -Z (003 Fig. 2): touches whose normal lies within min_touch_angle of the
  // stem are left out (the stem, or the plate, is there).
  const std::array<Eigen::Vector3d, 5> approaches = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                                     Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                                     -Eigen::Vector3d::UnitZ()};
  const double cos_limit = std::cos(degToRad(l.min_touch_angle_deg));
  // A touch is kept only when its whole access is clear of the other spheres: the descent from
  // the pose's safe height to the start point, the probing move to its end (overtravel), and the
  // stylus above the ball all along (a capsule of the ball's radius up to the probe body). At
  // A = -90 deg two spheres can stand one above the other; a vertical descent onto the lower one
  // would pass through the upper one (found by rotacal check). Required gap: the machine's
  // clearance, what `rotacal check` holds every non-probing move to.
  const double stylus = machine.probe.stylus_length_mm;
  const double keep_out = rho + machine.clearance_mm;
  const auto capsuleClear = [&](const Eigen::Vector3d& ball, const Eigen::Vector3d& centre) {
    // Distance from the centre to the vertical segment [ball, ball + stylus z].
    const double h = std::clamp(centre.z() - ball.z(), 0.0, stylus);
    return (centre - (ball + h * Eigen::Vector3d::UnitZ())).norm() >= keep_out;
  };
  const auto accessClear = [&](const Eigen::Vector3d& start, const Eigen::Vector3d& end, double safe_z,
                               const std::vector<Eigen::Vector3d>& others) {
    for (const auto& c : others) {
      // The descent: the ball from the safe height down to the start, the stylus above it.
      const double h = std::clamp(c.z() - start.z(), 0.0, safe_z - start.z() + stylus);
      if ((c - (start + h * Eigen::Vector3d::UnitZ())).norm() < keep_out) return false;
      // The probing move, sampled finely enough that a 0.05 mm dip cannot pass unseen.
      const int steps = std::max(1, static_cast<int>(std::ceil((end - start).norm() / 0.05)));
      for (int k = 0; k <= steps; ++k)
        if (!capsuleClear(start + (end - start) * (static_cast<double>(k) / steps), c)) return false;
    }
    return true;
  };
  int id = 1;
  for (double phi : l.phi_deg) {
    for (double theta : l.theta_deg) {
      const Pose pose{phi, 0.0, theta};
      const std::string name = fmt::format("t{:g}p{:g}", theta, phi);
      const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
      const Eigen::Vector3d stem_m = T.linear() * -Eigen::Vector3d::UnitZ();
      double top = -1e300;
      for (const auto& c : table1) top = std::max(top, (T * (l.origin_w_mm + c)).z());
      const double safe_z = top + rho + machine.clearance_mm;
      plan.poses.push_back({name, pose, safe_z});
      for (int s = 1; s <= 7; ++s) {
        const Eigen::Vector3d c_w = l.origin_w_mm + table1[s - 1];
        const Eigen::Vector3d c_m = T * c_w;
        int touches = 0, blocked = 0;
        std::vector<Eigen::Vector3d> others;
        for (int o = 1; o <= 7; ++o)
          if (o != s) others.push_back(T * (l.origin_w_mm + table1[o - 1]));
        for (const auto& u : approaches) {
          if ((-u).dot(stem_m) > cos_limit) continue;
          const Eigen::Vector3d trigger = c_m - rho * u;
          if (!accessClear(trigger - machine.approach_mm * u, trigger + machine.overtravel_mm * u,
                           std::max(safe_z, trigger.z() - machine.approach_mm * u.z()), others)) {
            ++blocked;
            continue;
          }
          ProbePoint p;
          p.id = id++;
          p.pose_name = name;
          p.pose = pose;
          p.target = s;
          p.face = Face::Top;  // not a face: the sphere field says what is touched
          p.normal_w = T.linear().transpose() * -u;
          p.contact_w_mm = c_w + R * p.normal_w;
          p.trigger_m_mm = c_m - rho * u;
          p.approach_m = u;
          p.sphere = SphereTarget{s, c_w, R};
          plan.points.push_back(p);
          ++touches;
        }
        if (touches < 4 && touches + blocked >= 4) {
          // Another sphere stands in the way at this pose: this sphere is left out here (its
          // centre is not measured at this pose; the lengths and the fit use the others).
          plan.points.resize(plan.points.size() - static_cast<size_t>(touches));
          id -= touches;
          continue;
        }
        if (touches < 4)
          throw std::invalid_argument(fmt::format("pose {}: sphere {} has only {} reachable touches (4 needed); lower "
                                                  "min_touch_angle_deg",
                                                  name, s, touches));
      }
    }
  }
  if (l.nominal_from == "initial") {
    bool has_initial = false;
    for (const auto& p : plan.poses) has_initial = has_initial || (p.pose.A == 0.0 && p.pose.C == 0.0);
    if (!has_initial) throw std::invalid_argument("nominal_from=initial needs theta = 0 and phi = 0 in the map");
  }
  finishTouchPlan(plan);
  return plan;
}

std::vector<FramePoint> framePoints(const ProbePlan& plan) {
  std::vector<FramePoint> out;
  for (const auto& p : plan.points) {
    if (!p.sphere) throw std::invalid_argument(fmt::format("point {}: not a sphere touch", p.id));
    if (out.empty() || out.back().pose_name != p.pose_name || out.back().sphere != p.sphere->id) {
      FramePoint f;
      f.index = static_cast<int>(out.size());
      f.pose_name = p.pose_name;
      f.pose = p.pose;
      f.sphere = p.sphere->id;
      f.center_w_mm = p.sphere->center_w_mm;
      f.nominal_m_mm = T_m_w_nominal(plan.machine.kinematics, p.pose) * p.sphere->center_w_mm;
      out.push_back(f);
    }
    out.back().point_ids.push_back(p.id);
  }
  return out;
}

Eigen::Matrix<double, FrameModel::kSize, 1> FrameModel::toVector() const {
  Eigen::Matrix<double, kSize, 1> v;
  v.head<kRigidSize>() << errors.values, scale, setup_translation_mm, setup_rotation_rad;
  for (int i = 0; i < 7; ++i) v.segment<3>(kRigidSize + 3 * i) = sphere_offset_w_mm[i];
  return v;
}

FrameModel FrameModel::fromVector(Kinematics k, const Eigen::Matrix<double, kSize, 1>& v) {
  FrameModel m;
  m.errors.kinematics = k;
  m.errors.values = v.head<kNumLocationErrors>();
  m.scale = v.segment<3>(kNumLocationErrors);
  m.setup_translation_mm = v.segment<3>(kNumLocationErrors + 3);
  m.setup_rotation_rad = v.segment<3>(kNumLocationErrors + 6);
  for (int i = 0; i < 7; ++i) m.sphere_offset_w_mm[i] = v.segment<3>(kRigidSize + 3 * i);
  return m;
}

Eigen::Matrix<double, FrameModel::kSize, 1> FrameModel::reportUnits(Kinematics k) {
  Eigen::Matrix<double, kSize, 1> s;
  const auto& params = locationParameters(k);
  for (int i = 0; i < kNumLocationErrors; ++i) s[i] = params[i].kind == ParamKind::Length ? kUmPerMm : kMdegPerRad;
  s.segment<3>(kNumLocationErrors).setConstant(1e6);
  s.segment<3>(kNumLocationErrors + 3).setConstant(kUmPerMm);
  s.segment<3>(kNumLocationErrors + 6).setConstant(kMdegPerRad);
  s.tail<21>().setConstant(kUmPerMm);
  return s;
}

std::vector<int> activeParameters(bool frame_free) {
  std::vector<int> a;
  for (int i = 0; i < kNumLocationErrors; ++i) a.push_back(i);
  if (!frame_free) {
    for (int i = kNumLocationErrors; i < FrameModel::kRigidSize; ++i) a.push_back(i);
    return a;
  }
  a.push_back(kNumLocationErrors);
  a.push_back(kNumLocationErrors + 1);
  for (int i = FrameModel::kRigidSize; i < FrameModel::kSize; ++i) a.push_back(i);
  return a;
}

Eigen::Vector3d FrameModel::placedCentre_w(const Eigen::Vector3d& center_w, int sphere, const Eigen::Vector3d& origin_w) const {
  return setupTransform(setup_translation_mm, setup_rotation_rad, origin_w) * (center_w + sphere_offset_w_mm.at(sphere - 1));
}

Eigen::Vector3d FrameModel::actualCentre_m(const FramePoint& p, const Eigen::Vector3d& origin_w) const {
  return T_m_w(errors, p.pose) * placedCentre_w(p.center_w_mm, p.sphere, origin_w);
}

namespace {

SphereFitOptions fitOptions(const ProbePlan& plan, const ProbePoint& touch) {
  SphereFitOptions fo;
  fo.rho_mm = touch.sphere->radius_mm + plan.machine.probe.ball_radius_mm();
  return fo;
}

}  // namespace

std::vector<double> FrameModel::readingsAlong(const ProbePlan& plan, const FramePoint& p, const Eigen::Vector3d& origin_w) const {
  const Eigen::Vector3d x = actualCentre_m(p, origin_w);
  const Eigen::Matrix3d K = Eigen::Matrix3d((Eigen::Vector3d::Ones() + scale).asDiagonal()) + shear;  // actual = K read
  std::vector<double> s;
  for (int id : p.point_ids) {
    const ProbePoint& q = *plan.findPoint(id);
    const double rho = q.sphere->radius_mm + plan.machine.probe.ball_radius_mm();
    // The reading moves as c0 + s u, the ball as K (c0 + s u): |a + s b| = rho.
    const Eigen::Vector3d a = K * q.trigger_m_mm - x, b = K * q.approach_m;
    const double bb = b.squaredNorm(), ab = a.dot(b);
    const double disc = ab * ab - bb * (a.squaredNorm() - rho * rho);
    if (disc < 0) throw std::invalid_argument(fmt::format("point {}: the model's probe misses the sphere", id));
    s.push_back((-ab - std::sqrt(disc)) / bb);
  }
  return s;
}

namespace {

/// The triggers the readings `s` along point p's approaches put the ball centre at.
std::vector<Eigen::Vector3d> triggersAt(const ProbePlan& plan, const FramePoint& p, const std::vector<double>& s) {
  std::vector<Eigen::Vector3d> t;
  for (size_t k = 0; k < s.size(); ++k) {
    const ProbePoint& q = *plan.findPoint(p.point_ids[k]);
    t.push_back(q.trigger_m_mm + s[k] * q.approach_m);
  }
  return t;
}

}  // namespace

Eigen::Vector3d FrameModel::fittedCentre_m(const ProbePlan& plan, const FramePoint& p, const Eigen::Vector3d& origin_w) const {
  const std::vector<Eigen::Vector3d> t = triggersAt(plan, p, readingsAlong(plan, p, origin_w));
  return fitSphereCentre(t, p.nominal_m_mm, fitOptions(plan, *plan.findPoint(p.point_ids.front()))).centre_mm;
}

Eigen::MatrixXd frameJacobian(const ProbePlan& plan, const std::vector<FramePoint>& points, const Eigen::Vector3d& origin_w,
                              const FrameModel& model, const std::vector<int>& active, double step) {
  const Eigen::Matrix<double, FrameModel::kSize, 1> unit = FrameModel::reportUnits(plan.machine.kinematics);
  const Eigen::Matrix<double, FrameModel::kSize, 1> x = model.toVector();
  const int n = static_cast<int>(points.size());
  std::vector<FrameModel> plus, minus;
  for (int c : active) {
    Eigen::Matrix<double, FrameModel::kSize, 1> xp = x, xm = x;
    xp[c] += step / unit[c];
    xm[c] -= step / unit[c];
    plus.push_back(FrameModel::fromVector(plan.machine.kinematics, xp));
    minus.push_back(FrameModel::fromVector(plan.machine.kinematics, xm));
    plus.back().shear = minus.back().shear = model.shear;
  }
  // The chain rule through the sphere fit: a parameter moves the fitted centre only through the
  // readings it moves along their approaches, and the fit's linear map at the model's own triggers
  // carries those to the centre (exact to first order in the fit's residual, which the model's
  // readings leave at the scale errors' size: relative 1e-5). Central differences of the closed-form
  // readings, one sphere fit per point instead of two per parameter and point.
  Eigen::MatrixXd J(3 * n, static_cast<Eigen::Index>(active.size()));
  for (int i = 0; i < n; ++i) {
    const FramePoint& p = points[static_cast<size_t>(i)];
    const std::vector<double> s = model.readingsAlong(plan, p, origin_w);
    const std::vector<Eigen::Vector3d> t = triggersAt(plan, p, s);
    std::vector<Eigen::Vector3d> u;
    for (int id : p.point_ids) u.push_back(plan.findPoint(id)->approach_m);
    const SphereFit fit = fitSphereCentre(t, p.nominal_m_mm, fitOptions(plan, *plan.findPoint(p.point_ids.front())));
    const Eigen::MatrixXd M = linearSphereFit(t, u, fit).centre;
    Eigen::VectorXd ds(static_cast<Eigen::Index>(s.size()));
    for (size_t k = 0; k < active.size(); ++k) {
      const std::vector<double> sp = plus[k].readingsAlong(plan, p, origin_w), sm = minus[k].readingsAlong(plan, p, origin_w);
      for (size_t j = 0; j < s.size(); ++j) ds[static_cast<Eigen::Index>(j)] = (sp[j] - sm[j]) / (2.0 * step);
      J.block<3, 1>(3 * i, static_cast<Eigen::Index>(k)) = M * ds;
    }
  }
  return J;
}

namespace {

using ModelVector = Eigen::Matrix<double, FrameModel::kSize, 1>;


}  // namespace

bool SpaceframeOptions::validate(std::string* why) const {
  if (!(finite_step_scale > 0)) return invalidBecause(why, "finite_step_scale must be > 0");
  if (max_iterations < 1) return invalidBecause(why, "max_iterations must be >= 1");
  if (!(rank_tolerance > 0 && rank_tolerance < 1)) return invalidBecause(why, "rank_tolerance must be in (0, 1)");
  return true;
}

SpaceframeAnalysis analyzeSpaceframe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                     const SpaceframeOptions& options) {
  requireValid(options, "spaceframe options");
  if (plan.cycle != "spaceframe") throw std::invalid_argument("plan is not a spaceframe plan");
  if (runs.empty()) throw std::invalid_argument("no results");
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  SpaceframeAnalysis a;
  a.spec = layout.spec;
  a.points = framePoints(plan);
  a.runs = static_cast<int>(runs.size());
  if (!options.held_out_ids.empty()) {
    // Touches the screen left out: out of their sphere's fit in every run; a sphere whose touches
    // left no longer fix its centre and radius leaves the fit at that pose.
    std::vector<FramePoint> kept;
    for (FramePoint f : a.points) {
      std::vector<int> ids, out;
      for (int id : f.point_ids) (options.held_out_ids.count(id) ? out : ids).push_back(id);
      a.held_out_ids.insert(a.held_out_ids.end(), out.begin(), out.end());
      // Whether the touches left fix a centre and a radius: their approaches and the radius
      // column of rank 4 (four touches on the equator leave the height free).
      bool fixes = ids.size() >= 4;
      if (fixes && !out.empty()) {
        Eigen::MatrixXd H(static_cast<Eigen::Index>(ids.size()), 4);
        for (size_t k = 0; k < ids.size(); ++k)
          H.row(static_cast<Eigen::Index>(k)) << plan.findPoint(ids[k])->approach_m.transpose(), 1.0;
        fixes = Eigen::FullPivLU<Eigen::MatrixXd>(H).rank() == 4;
      }
      if (!fixes && !out.empty()) {
        std::string list;
        for (int id : f.point_ids) list += fmt::format("{}{}", list.empty() ? "" : ", ", id);
        a.points_left_out.push_back(fmt::format("pose {} sphere {} (points {})", f.pose_name, f.sphere, list));
        continue;
      }
      f.point_ids = ids;
      f.index = static_cast<int>(kept.size());
      kept.push_back(f);
    }
    a.points = kept;
    if (a.points.size() < 3) throw std::invalid_argument("spaceframe: fewer than 3 centres left after the held-out touches");
  }

  // Triggers by point id, per run.
  std::vector<std::map<int, Eigen::Vector3d>> by_id(runs.size());
  for (size_t k = 0; k < runs.size(); ++k)
    for (const auto& t : runs[k].points) by_id[k][t.point_id] = t.position_m_mm;

  for (const auto& f : a.points) {
    const SphereFitOptions fo = fitOptions(plan, *plan.findPoint(f.point_ids.front()));
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    SphereFit mean;
    for (size_t k = 0; k < runs.size(); ++k) {
      std::vector<Eigen::Vector3d> t;
      for (int id : f.point_ids) {
        const auto it = by_id[k].find(id);
        if (it == by_id[k].end())
          throw std::invalid_argument(fmt::format("{}: no trigger for point {} (pose {}, sphere {})", runs[k].source, id,
                                                  f.pose_name, f.sphere));
        t.push_back(it->second);
      }
      const SphereFit fit = fitSphereCentre(t, f.nominal_m_mm, fo);
      sum += fit.centre_mm;
      a.triggers += fit.triggers;
      if (k == 0) mean = fit;
      else mean.residual_rms_um = std::max(mean.residual_rms_um, fit.residual_rms_um);
    }
    mean.centre_mm = sum / static_cast<double>(runs.size());
    const double dev_um = mmToUm(mean.rho_mm - fo.rho_mm);  // first run's fit
    a.radius_mean_dev_um += dev_um / static_cast<double>(a.points.size());
    a.radius_max_dev_um = std::max(a.radius_max_dev_um, std::abs(dev_um));
    a.radius_limit_um = std::max(2.0, 6.0 * plan.machine.probe.repeatability_um);
    if (std::abs(dev_um) > a.radius_limit_um) ++a.radius_outside;
    a.fits.push_back(mean);
    a.measured_m_mm.push_back(mean.centre_mm);
  }
  // The L_n points: Table 1 through the map, or (003's self-calibration) the centres measured at
  // theta = phi = 0 through the map.
  auto nominalPoints = [&](const std::vector<Eigen::Vector3d>& centres) {
    std::vector<Eigen::Vector3d> out;
    std::map<int, Eigen::Vector3d> initial_w;  // sphere -> centre at theta = phi = 0, workpiece frame
    if (layout.nominal_from == "initial")
      for (size_t i = 0; i < a.points.size(); ++i)
        if (a.points[i].pose.A == 0.0 && a.points[i].pose.C == 0.0 && !initial_w.count(a.points[i].sphere))
          initial_w[a.points[i].sphere] = T_m_w_nominal(plan.machine.kinematics, a.points[i].pose).inverse() * centres[i];
    for (const auto& f : a.points) {
      if (layout.nominal_from == "table1") {
        out.push_back(f.nominal_m_mm);
        continue;
      }
      const auto it = initial_w.find(f.sphere);
      if (it == initial_w.end())
        throw std::invalid_argument(
            fmt::format("nominal_from=initial: sphere {} was not measured at theta = phi = 0", f.sphere));
      out.push_back(T_m_w_nominal(plan.machine.kinematics, f.pose) * it->second);
    }
    return out;
  };
  a.nominal_m_mm = nominalPoints(a.measured_m_mm);
  a.lengths = lengthErrors(a.measured_m_mm, a.nominal_m_mm);
  // u(dL) for ISO 14253-1's decision: each centre's covariance from its sphere fit, scaled by the
  // per-touch scatter (the declared repeatability, or the fits' pooled residual when larger),
  // divided by the repeats it averages; projected on the length's direction, the two centres
  // independent (different touches). With nominal_from=initial the L_n points are measured too:
  // their part is bounded by the largest eigenvalue of the initial centres' covariance (the
  // rotation to the pose is not needed for a bound). With nominal_from=table1 the L_n points are
  // the frame's calibrated centres (FRAME.json, u per coordinate): an error d_s of sphere s moves
  // L_n by e . (R_j d_sj - R_k d_sk), R the poses' nominal rotations; one sphere seen at two poses
  // is one error, two spheres are independent.
  {
    double rss = 0.0;
    int dof = 0;
    for (const auto& f : a.fits) {
      rss += f.rss_mm2;
      dof += f.dof;
    }
    const double declared_mm = umToMm(plan.machine.probe.repeatability_um);
    const double pooled_mm2 = dof > 0 ? rss / dof : 0.0;
    const double sigma2 = std::max(declared_mm * declared_mm, pooled_mm2) / static_cast<double>(runs.size());
    a.length_sigma_um = mmToUm(std::sqrt(sigma2 * static_cast<double>(runs.size())));
    std::map<int, double> initial_var;  // sphere -> largest eigenvalue of its initial centre's covariance, mm^2
    if (layout.nominal_from == "initial")
      for (size_t i = 0; i < a.points.size(); ++i)
        if (a.points[i].pose.A == 0.0 && a.points[i].pose.C == 0.0 && !initial_var.count(a.points[i].sphere))
          initial_var[a.points[i].sphere] =
              sigma2 * Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(a.fits[i].cov_centre_per_sigma2).eigenvalues().maxCoeff();
    for (auto& l : a.lengths) {
      const Eigen::Vector3d e = (a.measured_m_mm[static_cast<size_t>(l.j)] - a.measured_m_mm[static_cast<size_t>(l.k)]).normalized();
      double var = sigma2 * e.dot((a.fits[static_cast<size_t>(l.j)].cov_centre_per_sigma2 +
                                   a.fits[static_cast<size_t>(l.k)].cov_centre_per_sigma2) * e);
      for (int idx : {l.j, l.k}) {
        const auto it = initial_var.find(a.points[static_cast<size_t>(idx)].sphere);
        if (it != initial_var.end()) var += it->second;
      }
      if (layout.nominal_from == "table1" && layout.frame.u_um > 0) {
        const FramePoint& pj = a.points[static_cast<size_t>(l.j)];
        const FramePoint& pk = a.points[static_cast<size_t>(l.k)];
        const Eigen::Vector3d en = (a.nominal_m_mm[static_cast<size_t>(l.j)] - a.nominal_m_mm[static_cast<size_t>(l.k)]).normalized();
        const Eigen::Vector3d gj = T_m_w_nominal(plan.machine.kinematics, pj.pose).linear().transpose() * en;
        const Eigen::Vector3d gk = -T_m_w_nominal(plan.machine.kinematics, pk.pose).linear().transpose() * en;
        const double u2 = umToMm(layout.frame.u_um) * umToMm(layout.frame.u_um);
        var += pj.sphere == pk.sphere ? u2 * (gj + gk).squaredNorm() : u2 * (gj.squaredNorm() + gk.squaredNorm());
      }
      l.u_um = mmToUm(std::sqrt(std::max(0.0, var)));
    }
  }
  a.verdict = checkLengths(a.lengths, a.spec, kCoverageFactor);

  // Least squares on the measured centres (3 per point): exact model, Gauss-Newton, Jacobian by
  // central differences in report units (um, mdeg, um/m), SVD with a rank check.
  const Kinematics kin = plan.machine.kinematics;
  const ModelVector unit = FrameModel::reportUnits(kin);
  const int n = static_cast<int>(a.points.size());
  const int m = 3 * n;
  ModelVector x = ModelVector::Zero();  // mm / rad / 1
  auto residuals = [&](const ModelVector& v) {
    const FrameModel fm = FrameModel::fromVector(kin, v);
    Eigen::VectorXd res(m);
    for (int i = 0; i < n; ++i) res.segment<3>(3 * i) = a.measured_m_mm[i] - fm.fittedCentre_m(plan, a.points[i], layout.origin_w_mm);
    return res;
  };
  const std::vector<int> active = activeParameters(layout.nominal_from == "initial");
  const int np = static_cast<int>(active.size());
  a.summary.parameters = np;
  // d(model)/d(parameter in report units), mm per unit, and its rank and condition (singular
  // values below rank_tolerance x the largest dropped).
  const auto jacobianAt = [&](const ModelVector& v) {
    return frameJacobian(plan, a.points, layout.origin_w_mm, FrameModel::fromVector(kin, v), active, options.finite_step_scale);
  };
  const auto rankOf = [&](const Eigen::MatrixXd& J) {
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(J).singularValues();
    int rank = 0;
    for (int i = 0; i < sv.size(); ++i) rank += sv[i] > options.rank_tolerance * sv[0] ? 1 : 0;
    a.summary.rank = rank;
    a.summary.condition = rank > 0 && sv[rank - 1] > 0 ? sv[0] / sv[rank - 1] : INFINITY;
    return rank;
  };
  Eigen::VectorXd res = residuals(x);
  Eigen::MatrixXd cov_units;  // (J^T J)^-1 over the active parameters, report units
  if (rankOf(jacobianAt(x)) < np) {
    a.summary.termination = Termination::RankDeficient;
  } else {
    // The shared engine (core/least_squares) over the active parameters in report units, r = the
    // model's centres - the measured ones; converged when no parameter moves by 1e-6 um / mdeg /
    // um/m in a step: far below any resolution, above the floor the sphere fits (converged to
    // 1e-13 mm) leave in the central differences. The engine's own tolerances are off.
    const auto full = [&](const Eigen::VectorXd& p) {
      ModelVector v = ModelVector::Zero();
      for (int k = 0; k < np; ++k) v[active[static_cast<size_t>(k)]] = p[k] / unit[active[static_cast<size_t>(k)]];
      return v;
    };
    LeastSquaresOptions lo;
    lo.max_iterations = options.max_iterations;
    lo.rank_tolerance = options.rank_tolerance;
    lo.step_tolerance = std::numeric_limits<double>::min();
    lo.function_tolerance = 0.0;
    lo.converged = [](const Eigen::VectorXd& before, const Eigen::VectorXd& after) {
      return (after - before).cwiseAbs().maxCoeff() < 1e-6;
    };
    const LeastSquaresResult solved = solveLeastSquares(
        [&](const Eigen::VectorXd& p, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
          const ModelVector v = full(p);
          r = -residuals(v);
          if (J) *J = jacobianAt(v);
        },
        Eigen::VectorXd::Zero(np), lo);
    x = full(solved.x);
    res = residuals(x);
    a.summary.iterations = solved.summary.iterations;
    a.summary.termination = solved.summary.usable() ? Termination::Converged : Termination::MaxIterations;
    if (rankOf(jacobianAt(x)) < np) a.summary.termination = Termination::RankDeficient;
    cov_units = solved.covariance;
  }
  a.summary.observations = m;
  a.summary.dof = m - a.summary.rank;
  a.summary.residual_rms_um = mmToUm(std::sqrt(res.squaredNorm() / m));
  a.summary.sigma_um = a.summary.dof > 0 ? mmToUm(std::sqrt(res.squaredNorm() / a.summary.dof)) : 0.0;
  a.model = FrameModel::fromVector(kin, x);
  if (a.summary.termination != Termination::RankDeficient) {
    // u (k = 1) from the a-posteriori noise: cov = sigma^2 (J^T J)^-1, J in mm per report unit;
    // stored in mm / rad / 1 like the model.
    for (int k = 0; k < np; ++k)
      a.u[active[k]] = umToMm(a.summary.sigma_um) * std::sqrt(cov_units(k, k)) / unit[active[k]];
  }
  // How much of dL the identified model explains: dL minus the dL of the model's readings.
  std::vector<Eigen::Vector3d> predicted;
  for (const auto& f : a.points) predicted.push_back(a.model.fittedCentre_m(plan, f, layout.origin_w_mm));
  const std::vector<Eigen::Vector3d> predicted_nominal = nominalPoints(predicted);
  double s_before = 0.0, s_after = 0.0;
  for (const auto& L : a.lengths) {
    const double dL_model =
        (predicted[L.j] - predicted[L.k]).norm() - (predicted_nominal[L.j] - predicted_nominal[L.k]).norm();
    s_before += L.dL_mm() * L.dL_mm();
    s_after += (L.dL_mm() - dL_model) * (L.dL_mm() - dL_model);
  }
  const double nl = std::max<double>(1.0, static_cast<double>(a.lengths.size()));
  a.dL_rms_um = mmToUm(std::sqrt(s_before / nl));
  a.dL_unexplained_rms_um = mmToUm(std::sqrt(s_after / nl));
  return a;
}

namespace {


Json figuresJson(const SpaceframeAnalysis& a) {
  // 003 Fig. 6 (dL against L with the band) as the envelope of dL per 5 mm of L, and 003 Fig. 5
  // (frequency of lengths) per 10 mm: 49455 single points would swamp the report.
  double Lmax = 0.0;
  for (const auto& L : a.lengths) Lmax = std::max(Lmax, L.measured_mm);
  const double w6 = 5.0, w5 = 10.0;
  const int n6 = static_cast<int>(Lmax / w6) + 1, n5 = static_cast<int>(Lmax / w5) + 1;
  std::vector<double> lo(n6, INFINITY), hi(n6, -INFINITY);
  std::vector<int> count(n5, 0);
  for (const auto& L : a.lengths) {
    const int b = static_cast<int>(L.measured_mm / w6);
    const double d = mmToUm(L.dL_mm());
    lo[b] = std::min(lo[b], d);
    hi[b] = std::max(hi[b], d);
    ++count[static_cast<int>(L.measured_mm / w5)];
  }
  Json x = Json::array(), ylo = Json::array(), yhi = Json::array(), bx = Json::array(), blo = Json::array(),
       bhi = Json::array();
  for (int b = 0; b < n6; ++b) {
    if (!std::isfinite(lo[b])) continue;
    const double Lc = (b + 0.5) * w6;
    x.push_back(round6(Lc));
    ylo.push_back(round6(lo[b]));
    yhi.push_back(round6(hi[b]));
  }
  for (int b = 0; b <= n6; ++b) {
    const double L = b * w6;
    bx.push_back(round6(L));
    blo.push_back(round6(-a.spec.limit_um(L)));
    bhi.push_back(round6(a.spec.limit_um(L)));
  }
  Json hx = Json::array(), hy = Json::array();
  for (int b = 0; b < n5; ++b) {
    hx.push_back(round6((b + 0.5) * w5));
    hy.push_back(count[b]);
  }
  Json figs = Json::array();
  figs.push_back({{"id", "spaceframe_dl_vs_l"},
                  {"title", "Length error against length (003 Fig. 6)"},
                  {"x", {{"label", "L (measured)"}, {"unit", "mm"}}},
                  {"y", {{"label", "dL = Lm - Ln"}, {"unit", "um"}}},
                  {"series", Json::array({{{"name", "largest dL per 5 mm of L"}, {"style", "line"}, {"x", x}, {"y", yhi}},
                                          {{"name", "smallest dL per 5 mm of L"}, {"style", "line"}, {"x", x}, {"y", ylo}}})},
                  {"bands", Json::array({{{"name", fmt::format("U = ±({:g} um + {:g} um/m · L)", a.spec.A_um,
                                                               a.spec.K_um_per_m)},
                                          {"x", bx},
                                          {"lo", blo},
                                          {"hi", bhi}}})},
                  {"note", fmt::format("{} of {} lengths outside the band: {}", a.verdict.outside, a.verdict.lengths,
                                       lengthDecisionName(a.verdict.decision))}});
  figs.push_back({{"id", "spaceframe_length_histogram"},
                  {"title", "Frequency of length sizes (003 Fig. 5)"},
                  {"x", {{"label", "L (measured)"}, {"unit", "mm"}}},
                  {"y", {{"label", "lengths per 10 mm"}, {"unit", "1"}}},
                  {"series", Json::array({{{"name", "lengths"}, {"style", "points"}, {"x", hx}, {"y", hy}}})},
                  {"note", "how many of the map's lengths fall in each 10 mm of L"}});
  return figs;
}

}  // namespace

Json spaceframeReportJson(const SpaceframeAnalysis& a, const ProbePlan& plan, const std::vector<std::string>& files) {
  Json j = documentEnvelope("rotacal-report/1", plan, files);
  j["method"] = "lsq_frame_centres";
  ErrorVector ue = a.u.head<kNumLocationErrors>();
  j["location_errors"] = locationErrorsJson(a.model.errors, ue);
  const char* ax[3] = {"X", "Y", "Z"};
  Json sc = Json::object(), st = Json::object();
  for (int i = 0; i < 3; ++i) {
    sc[ax[i]] = {{"value", round6(a.model.scale[i] * 1e6)}, {"unit", "um/m"}, {"u", round6(a.u[kNumLocationErrors + i] * 1e6)}};
    st[std::string("translation_") + ax[i]] = {{"value", round6(mmToUm(a.model.setup_translation_mm[i]))},
                                               {"unit", "um"},
                                               {"u", round6(mmToUm(a.u[kNumLocationErrors + 3 + i]))}};
    st[std::string("rotation_") + ax[i]] = {{"value", round6(radToMdeg(a.model.setup_rotation_rad[i]))},
                                            {"unit", "mdeg"},
                                            {"u", round6(radToMdeg(a.u[kNumLocationErrors + 6 + i]))}};
  }
  const bool frame_free = SpaceframeLayout::fromOptions(plan.options).nominal_from == "initial";
  j["frame"] = frame_free ? "self_calibration" : "calibrated";
  if (frame_free) {
    // Scale Z is the reference (an isotropic scale is the frame's size); the setup is in the offsets.
    sc["Z"]["note"] = "reference: X and Y are relative to Z (self-calibration cannot see an isotropic scale)";
    Json sp = Json::object();
    for (int i = 0; i < 7; ++i) {
      const Eigen::Vector3d d = a.model.sphere_offset_w_mm[i];
      const Eigen::Vector3d ud = a.u.segment<3>(FrameModel::kRigidSize + 3 * i);
      sp[std::to_string(i + 1)] = {{"offset_w_um", {round6(mmToUm(d.x())), round6(mmToUm(d.y())), round6(mmToUm(d.z()))}},
                                   {"u_um", {round6(mmToUm(ud.x())), round6(mmToUm(ud.y())), round6(mmToUm(ud.z()))}}};
    }
    j["frame_spheres"] = sp;
  } else {
    j["frame_setup"] = st;
  }
  j["linear_axis_scale"] = sc;
  j["residual_rms_um"] = round6(a.summary.residual_rms_um);
  j["points_used"] = a.triggers;
  j["summary"] = fitSummaryJson(a.summary);
  const auto& w = a.verdict.worst_index >= 0 ? a.lengths[a.verdict.worst_index] : LengthError{};
  const SpaceframeLayout lay = SpaceframeLayout::fromOptions(plan.options);
  j["lengths"] = {{"points", a.points.size()},
                  {"nominal_from", lay.nominal_from},
                  {"frame", {{"source", lay.frame.source}, {"u_um", lay.frame.u_um}}},
                  {"count", a.lengths.size()},
                  {"A_um", a.spec.A_um},
                  {"K_um_per_m", a.spec.K_um_per_m},
                  {"verdict", std::string(lengthDecisionName(a.verdict.decision))},
                  {"decision_rule",
                   fmt::format("ISO 14253-1: pass when every |dL| <= A + K L - U, fail when any |dL| > A + K L + U, "
                               "inconclusive otherwise; U = 2 u(dL) from the sphere fits{}",
                               lay.nominal_from == "initial" ? " (self-calibrated: the initial centres' own u)"
                               : lay.frame.u_um > 0      ? fmt::format(" and the frame's calibration ({:g} um per "
                                                                       "coordinate, {})", lay.frame.u_um, lay.frame.source)
                                                         : std::string(" (the frame's calibration taken as exact: " +
                                                                       lay.frame.source + ")"))},
                  {"conforming", a.verdict.conforming},
                  {"nonconforming", a.verdict.nonconforming},
                  {"inconclusive", a.verdict.undecided},
                  {"max_U_um", round6(a.verdict.max_U_um)},
                  {"per_touch_sigma_um", round6(a.length_sigma_um)},
                  {"outside", a.verdict.outside},
                  {"max_abs_dL_um", round6(a.verdict.max_abs_dL_um)},
                  {"rms_dL_um", round6(a.verdict.rms_dL_um)},
                  {"worst_ratio", round6(a.verdict.worst_ratio)},
                  {"worst", {{"from_point", w.j + 1}, {"to_point", w.k + 1}, {"L_mm", round6(w.measured_mm)},
                             {"dL_um", round6(mmToUm(w.dL_mm()))}, {"limit_um", round6(a.spec.limit_um(w.measured_mm))}}},
                  {"unexplained_rms_dL_um", round6(a.dL_unexplained_rms_um)}};
  Json pts = Json::array();
  for (size_t i = 0; i < a.points.size(); ++i) {
    const auto& f = a.points[i];
    const auto& fit = a.fits[i];
    const Eigen::Vector3d d = a.measured_m_mm[i] - a.nominal_m_mm[i];
    pts.push_back({{"point", i + 1},
                   {"pose", f.pose_name},
                   {"sphere", f.sphere},
                   {"touches", fit.triggers},
                   {"centre_m_mm", {round6(a.measured_m_mm[i].x()), round6(a.measured_m_mm[i].y()), round6(a.measured_m_mm[i].z())}},
                   {"deviation_um", {round6(mmToUm(d.x())), round6(mmToUm(d.y())), round6(mmToUm(d.z()))}},
                   {"fit_rms_um", round6(fit.residual_rms_um)},
                   {"fitted_radius_mm", fit.radius_fitted ? Json(round6(fit.rho_mm - plan.machine.probe.ball_radius_mm()))
                                                          : Json(nullptr)}});
  }
  j["frame_points"] = pts;
  j["sphere_radius_check"] = {{"nominal_mm", a.points.empty() ? 0.0 : plan.findPoint(a.points.front().point_ids.front())->sphere->radius_mm},
                              {"mean_deviation_um", round6(a.radius_mean_dev_um)},
                              {"max_abs_deviation_um", round6(a.radius_max_dev_um)},
                              {"limit_um", round6(a.radius_limit_um)},
                              {"outside", a.radius_outside}};
  j["figures"] = figuresJson(a);
  return j;
}

std::string spaceframeText(const SpaceframeAnalysis& a, const ProbePlan& plan, const UncertaintyBudget* budget) {
  std::string s;
  s += fmt::format("rotacal analysis: cycle spaceframe (003), machine {}\n", plan.machine.name);
  s += fmt::format("{} sphere centres from {} touches, {} lengths (003 Eq. (5))\n", a.points.size(), a.triggers,
                   a.lengths.size());
  s += fmt::format("length error dL = Lm - Ln: max |dL| {:.3f} um, rms {:.3f} um\n", a.verdict.max_abs_dL_um,
                   a.verdict.rms_dL_um);
  s += fmt::format("sphere fits: fitted radius - nominal {:+.3f} um on average, at most {:.3f} um{}\n",
                   a.radius_mean_dev_um, a.radius_max_dev_um,
                   a.radius_outside ? fmt::format(" ({} beyond {:.1f} um: probe pretravel, ball size or a dirty sphere?)",
                                                  a.radius_outside, a.radius_limit_um)
                                    : std::string());
  s += fmt::format("MPE = +-({:g} um + {:g} um/m L): {} lengths outside, worst |dL|/MPE = {:.3f}\n", a.spec.A_um,
                   a.spec.K_um_per_m, a.verdict.outside, a.verdict.worst_ratio);
  s += fmt::format("ISO 14253-1 decision with U = 2 u(dL) (up to {:.3f} um; per-touch scatter {:.3f} um): {} ({} conforming, "
                   "{} non-conforming, {} inside the guard bands)\n\n",
                   a.verdict.max_U_um, a.length_sigma_um, lengthDecisionName(a.verdict.decision), a.verdict.conforming,
                   a.verdict.nonconforming, a.verdict.undecided);
  s += fmt::format("identification ({}, rank {}/{}, {} dof), what explains dL ({}):\n", terminationName(a.summary.termination),
                   a.summary.rank, a.summary.parameters, a.summary.dof,
                   budget ? "+- u_c, k = 1" : "+- the fit's u, k = 1");
  const auto uOf = [&](const std::string& name, double fit) { return budget ? budget->uCOr(name, fit) : fit; };
  const auto& params = locationParameters(a.model.errors.kinematics);
  const ModelVector unit = FrameModel::reportUnits(a.model.errors.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i)
    s += fmt::format("  {:<8} {:<5} {:>10.3f} +- {:.3f} {}\n", params[i].name, params[i].iso, a.model.errors.reportValue(i),
                     uOf(std::string(params[i].name), a.u[i] * unit[i]), reportUnit(params[i].kind));
  const char* ax = "XYZ";
  for (int i = 0; i < 3; ++i)
    s += fmt::format("  scale {}        {:>10.3f} +- {:.3f} um/m\n", ax[i], a.model.scale[i] * 1e6,
                     uOf(std::string("scale_") + ax[i], a.u[kNumLocationErrors + i] * 1e6));
  if (SpaceframeLayout::fromOptions(plan.options).nominal_from == "initial") {
    s += "  (self-calibration: scale Z is the reference; the frame's spheres are fitted too:)\n";
    for (int i = 0; i < 7; ++i)
      s += fmt::format("  sphere {} offset {:>8.3f} {:>8.3f} {:>8.3f} um\n", i + 1,
                       mmToUm(a.model.sphere_offset_w_mm[i].x()), mmToUm(a.model.sphere_offset_w_mm[i].y()),
                       mmToUm(a.model.sphere_offset_w_mm[i].z()));
  }
  s += fmt::format("centre residual rms {:.3f} um; dL rms {:.3f} um, left unexplained {:.3f} um\n",
                   a.summary.residual_rms_um, a.dL_rms_um, a.dL_unexplained_rms_um);
  return s;
}

}  // namespace rotacal
