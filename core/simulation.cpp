#include "core/simulation.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

#include "core/kinematic_model.hpp"
#include "core/limits.hpp"
#include "core/rotary_backlash.hpp"

#include "core/units.hpp"

namespace rotacal {

double ballPlaneContact(const Eigen::Vector3d& c0, const Eigen::Vector3d& u, double r, const Plane& plane) {
  const double nu = plane.normal.dot(u);
  if (nu > -1e-9) throw std::invalid_argument("approach does not move toward the surface");
  return (r - plane.normal.dot(c0 - plane.point)) / nu;
}

double ballSphereContact(const Eigen::Vector3d& c0, const Eigen::Vector3d& u, double r,
                         const Eigen::Vector3d& x, double R) {
  // |d + s u|^2 = rho^2 with d = c0 - x, |u| = 1: s = -d.u -+ sqrt((d.u)^2 - |d|^2 + rho^2).
  const Eigen::Vector3d d = c0 - x;
  const double rho = r + R;
  const double du = d.dot(u);
  const double disc = du * du - d.squaredNorm() + rho * rho;
  if (disc < 0) throw std::invalid_argument("approach line misses the sphere");
  // The first contact on the way in: the smaller root (the ball moves along +u).
  return -du - std::sqrt(disc);
}

namespace {

// The true table transform at a point's pose and time (location errors + drift + pose-dependent,
// or the truth's own full transform).
Eigen::Isometry3d trueTable_m_w(const ProbePoint& point, const Pose& actual, const Truth& truth) {
  const double t = truth.start_time_s + point.t_s;
  if (truth.table_transform) return truth.table_transform(actual, t);
  LocationErrors e = truth.errors;
  if (truth.drift) e.values += truth.drift(t);
  if (truth.pose_dependent) e.values += truth.pose_dependent(actual);
  return T_m_w(e, actual);
}

// Where the rotary axes really are at each point of the plan under the truth's backlash.
std::vector<Pose> actualPoses(const ProbePlan& plan, const Truth& truth) {
  std::vector<Pose> out;
  out.reserve(plan.points.size());
  const Eigen::Vector3d& b = truth.rotary_backlash_deg;
  const std::vector<Eigen::Vector3d> dirs = rotaryApproachDirections(plan, true);
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const Pose& p = plan.points[i].pose;
    const Eigen::Vector3d a = Eigen::Vector3d(p.A, p.B, p.C) - 0.5 * dirs[i].cwiseProduct(b);
    out.push_back(Pose{a[0], a[1], a[2]});
  }
  return out;
}

}  // namespace

Plane truePlane_m(const ProbePlan& plan, const ProbePoint& point, const Truth& truth) {
  const Plane w = truth.artefact.face(*plan.machine.artefact, point.face);
  const Eigen::Isometry3d T = trueTable_m_w(point, point.pose, truth);
  return Plane{T * w.point, T.linear() * w.normal};
}

MeasurementRun simulate(const ProbePlan& plan, const Truth& truth, const SimulationOptions& options) {
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double r = plan.machine.probe.ball_radius_mm();
  MeasurementRun run;
  run.source = "simulation";
  const std::vector<Pose> actual = actualPoses(plan, truth);
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const ProbePoint& p = plan.points[i];
    if (!p.sphere && !plan.machine.artefact) throw std::invalid_argument("plan has no artefact to simulate");
    // The surface the ball meets: the face plane, or for sphere cycles the true sphere.
    std::function<double(const Eigen::Vector3d&)> contact;
    if (p.sphere) {
      const auto err = truth.sphere_center_error_w_mm.find(p.sphere->id);
      const Eigen::Vector3d c_w =
          p.sphere->center_w_mm + (err == truth.sphere_center_error_w_mm.end() ? Eigen::Vector3d::Zero() : err->second);
      const Eigen::Vector3d c_m = trueTable_m_w(p, actual[i], truth) * c_w;
      const double R = p.sphere->radius_mm;
      contact = [&p, r, c_m, R](const Eigen::Vector3d& c0) {
        try {
          return ballSphereContact(c0, p.approach_m, r, c_m, R);
        } catch (const std::invalid_argument&) {
          throw std::runtime_error(fmt::format("point {} (pose {}, sphere {}): the probe would not trigger: the "
                                               "approach line misses the sphere",
                                               p.id, p.pose_name, p.sphere->id));
        }
      };
    } else {
      const Plane w = truth.artefact.face(*plan.machine.artefact, p.face);
      const Eigen::Isometry3d T = trueTable_m_w(p, actual[i], truth);
      const Plane plane{T * w.point, T.linear() * w.normal};
      contact = [&p, r, plane](const Eigen::Vector3d& c0) { return ballPlaneContact(c0, p.approach_m, r, plane); };
    }
    // A head carries the ball away from the reading: the ball is at reading + b.
    const Eigen::Vector3d b =
        truth.head_ball ? truth.head_ball(actual[i], truth.start_time_s + p.t_s) : Eigen::Vector3d::Zero();
    double s = contact(p.trigger_m_mm + b);
    if (truth.linear_axis_error) {
      // The controller reads c(s) = c0 + s u while the ball is at c(s) + E(c(s)): solve
      // n.(c(s) + E(c(s)) - x) = r by fixed-point iteration (E varies by um per mm: contraction ~1e-3).
      for (int it = 0; it < 50; ++it) {
        const Eigen::Vector3d c = p.trigger_m_mm + s * p.approach_m;
        const double next = contact(p.trigger_m_mm + truth.linear_axis_error(c) + b);
        const bool done = std::abs(next - s) < 1e-13;
        s = next;
        if (done) break;
      }
    }
    if (s < -plan.machine.approach_mm || s > plan.machine.overtravel_mm)
      throw std::runtime_error(fmt::format(
          "point {} (pose {}, {}): the probe would not trigger: the surface is {:.3f} mm from the nominal "
          "trigger, outside the search range [-{:.3f}, +{:.3f}] mm",
          p.id, p.pose_name,
          p.sphere ? fmt::format("sphere {}", p.sphere->id) : fmt::format("face {}", faceName(p.face)), s, plan.machine.approach_mm, plan.machine.overtravel_mm));
    s += umToMm(truth.pretravel_um);
    if (truth.pretravel_by_direction_um) s += umToMm(truth.pretravel_by_direction_um(p.approach_m));
    if (truth.noise_um > 0) s += umToMm(truth.noise_um) * noise(rng);
    TriggerPoint t;
    t.point_id = p.id;
    t.position_m_mm = p.trigger_m_mm + s * p.approach_m;
    t.t_s = truth.start_time_s + p.t_s;
    run.points.push_back(t);
  }
  return run;
}

namespace {

Eigen::Vector3d vec3Or(const JsonDoc& doc, const Json& obj, const char* key, const Limits& limits) {
  return obj.contains(key) ? requireVec3(doc, obj, key, limits) : Eigen::Vector3d::Zero();
}

// The plausible size of a simulated error in each unit a truth file may use. Limits keeps its
// unit as a view: `unit` is a literal or the caller's string, never a temporary (a
// `const std::string&` here bound angleLimits("mrad") to one that died at once: fuzz_truth,
// AddressSanitizer stack-use-after-scope in the message of an out-of-range rotation_mrad).
Limits lengthLimits(std::string_view unit) {
  return Limits::symmetric(unit == "mm" ? kMaxLocationErrorUm / 1000.0 : kMaxLocationErrorUm, unit);
}
Limits angleLimits(std::string_view unit) {
  const double mdeg = kMaxAngleErrorMdeg;
  if (unit == "urad") return Limits::symmetric(mdegToRad(mdeg) * 1e6, unit);
  if (unit == "mrad") return Limits::symmetric(mdegToRad(mdeg) * 1e3, unit);
  if (unit == "deg") return Limits::symmetric(mdeg / 1000.0, unit);
  return Limits::symmetric(mdeg, unit);
}

namespace {
// The index of location error `name`, a key of `obj` whose entry must hold the number `field`;
// fails (FILE:LINE) naming an unknown error (`where`: in which table) or a missing number (`needs`).
int locationEntry(const JsonDoc& doc, const Json& obj, const std::string& name, Kinematics kinematics, const char* field,
                  const std::string& where, const std::string& needs) {
  const int i = parameterIndex(kinematics, name);
  if (i < 0) doc.fail(obj, name, "unknown location error '" + name + "' " + where);
  const Json& entry = obj[name];
  if (!entry.is_object() || !entry.contains(field) || !entry[field].is_number()) doc.fail(obj, name, needs);
  return i;
}
}  // namespace

// One location error's value in mm or rad from {"value": v, "unit": u}.
double locationValue(const JsonDoc& doc, const Json& entry, const std::string& name, ParamKind kind) {
  const std::string unit = stringOr(doc, entry, "unit", "");
  if (kind == ParamKind::Length) {
    if (unit != "um" && unit != "mm") doc.fail(entry, "unit", "unit of '" + name + "' must be um or mm");
    const double v = requireNumber(doc, entry, "value", lengthLimits(unit));
    return unit == "um" ? umToMm(v) : v;
  }
  if (unit != "mdeg" && unit != "urad" && unit != "deg")
    doc.fail(entry, "unit", "unit of '" + name + "' must be mdeg, urad or deg");
  const double v = requireNumber(doc, entry, "value", angleLimits(unit));
  return unit == "mdeg" ? mdegToRad(v) : unit == "urad" ? v * 1e-6 : degToRad(v);
}

// A spindle head machine's location errors: the parameters of its exact model, by ISO 230-7 name.
void headLocationErrors(const JsonDoc& doc, const Json& j, const MachineModel& machine, Truth* t) {
  const KinematicModel model = kinematicModel(kinematicsName(machine.kinematics), Eigen::Vector3d::Zero(),
                                              machine.head->pivot_to_ball_mm, machine.head->axis ? machine.head->axis : 'B');
  Eigen::VectorXd p = Eigen::VectorXd::Zero(model.size());
  if (j.contains("location_errors")) {
    const Json& le = requireObject(doc, j, "location_errors");
    for (const auto& [name, entry] : le.items()) {
      const int i = model.parameterIndex(name);
      if (i < 0) {
        std::string known;
        for (const auto& q : model.parameters) known += (known.empty() ? "" : ", ") + q.name;
        doc.fail(le, name, "unknown location error '" + name + "' of a " + model.name + " machine (" + known + ")");
      }
      if (!entry.is_object() || !entry.contains("value") || !entry["value"].is_number())
        doc.fail(le, name, "location error '" + name + "' needs {\"value\": number, \"unit\": ...}");
      p[i] = locationValue(doc, entry, name, model.parameters[static_cast<size_t>(i)].kind);
    }
  }
  const Truth chains = truthOfModel(model, p);
  t->table_transform = chains.table_transform;
  t->head_ball = chains.head_ball;
}

Truth truthFrom(const JsonDoc& doc, Kinematics kinematics, const MachineModel* machine) {
  const Json& j = doc.value;
  if (!j.is_object() || !j.contains("format") || j["format"] != "rotacal-truth/1")
    doc.fail(j, "format", "not a truth file (expected \"format\": \"rotacal-truth/1\")");
  Truth t;
  t.errors.kinematics = kinematics;
  if (kinematics == Kinematics::HeadTable || kinematics == Kinematics::HeadCB ||
      (kinematics == Kinematics::HeadAB && machine && machine->head)) {
    if (!machine || !machine->head)
      doc.fail(j, "format", fmt::format("a {} truth needs its machine's head (MACHINE.json \"head\")", kinematicsName(kinematics)));
    headLocationErrors(doc, j, *machine, &t);
    const std::string kin(kinematicsName(kinematics));
    for (const char* key : {"drift", "rotary_error_motion"})
      if (j.contains(key))
        doc.fail(j, key, std::string(key) + " is written in the papers' table location errors, which a " + kin + " machine has not");
  } else if (j.contains("location_errors")) {
    const Json& le = requireObject(doc, j, "location_errors");
    for (const auto& [name, entry] : le.items()) {
      const int i = locationEntry(doc, le, name, kinematics, "value", "for this machine",
                                  "location error '" + name + "' needs {\"value\": number, \"unit\": ...}");
      t.errors.values[i] = locationValue(doc, entry, name, locationParameters(kinematics)[i].kind);
    }
  }
  const Limits um = Limits::symmetric(kMaxLocationErrorUm, "um");
  const Limits mrad = angleLimits("mrad");
  const Limits um_per_m = Limits::symmetric(kMaxLocationErrorUm, "um/m");
  if (j.contains("setup_error")) {
    const Json& s = requireObject(doc, j, "setup_error");
    t.artefact.setup.translation_mm = vec3Or(doc, s, "translation_mm", lengthLimits("mm"));
    t.artefact.setup.rotation_rad = vec3Or(doc, s, "rotation_mrad", mrad) * 1e-3;
  }
  if (j.contains("form_error")) {
    const Json& fe = requireObject(doc, j, "form_error");
    for (const auto& [face, f] : fe.items()) {
      Face fc;
      try {
        fc = faceFromName(face);
      } catch (const std::invalid_argument& e) {
        doc.fail(fe, face, e.what());
      }
      FaceForm& ff = t.artefact.form[static_cast<size_t>(fc)];
      ff.offset_mm = umToMm(numberOr(doc, f, "offset_um", 0.0, um));
      ff.tilt_u_rad = numberOr(doc, f, "tilt_u_mrad", 0.0, mrad) * 1e-3;
      ff.tilt_v_rad = numberOr(doc, f, "tilt_v_mrad", 0.0, mrad) * 1e-3;
    }
  }
  if (j.contains("drift")) {
    // Linear drift of location errors: {"dz_AY": {"rate": 6.0, "unit": "um/h"}, ...}
    const Json& dr = requireObject(doc, j, "drift");
    ErrorVector rate = ErrorVector::Zero();  // per second, mm or rad
    for (const auto& [name, entry] : dr.items()) {
      const int i = locationEntry(doc, dr, name, kinematics, "rate", "in drift",
                                  "drift of '" + name + "' needs {\"rate\": number, \"unit\": \"um/h\" or \"mdeg/h\"}");
      const std::string unit = stringOr(doc, entry, "unit", "");
      const bool length = locationParameters(kinematics)[i].kind == ParamKind::Length;
      if (length && unit != "um/h") doc.fail(entry, "unit", "drift unit of '" + name + "' must be um/h");
      if (!length && unit != "mdeg/h") doc.fail(entry, "unit", "drift unit of '" + name + "' must be mdeg/h");
      const double v =
          requireNumber(doc, entry, "rate",
                        Limits::symmetric(length ? kMaxLocationErrorUm : kMaxAngleErrorMdeg, unit)) / 3600.0;
      rate[i] = length ? umToMm(v) : mdegToRad(v);
    }
    t.drift = [rate](double ts) { return ErrorVector(rate * ts); };
  }
  if (j.contains("rotary_error_motion")) {
    // Second-order radial error motion of C: {"EXC_cos2C_um": 3.0, "EYC_cos2C_um": 0.0}
    if (kinematics != Kinematics::TableAC) doc.fail(j, "rotary_error_motion", "rotary_error_motion needs an A/C machine");
    const Json& r = requireObject(doc, j, "rotary_error_motion");
    const double ex = umToMm(numberOr(doc, r, "EXC_cos2C_um", 0.0, um)), ey = umToMm(numberOr(doc, r, "EYC_cos2C_um", 0.0, um));
    t.pose_dependent = [ex, ey](const Pose& p) {
      ErrorVector d = ErrorVector::Zero();
      const double c2 = std::cos(2.0 * degToRad(p.C));
      d[0] = ex * c2;  // the C axis rides on A: x in the A frame is machine x
      d[3] = ey * c2;  // y of the C axis in the A frame: dy_CA
      return d;
    };
  }
  if (j.contains("linear_axis_squareness")) {
    // 000 Eq. (23): {"S_xy_um_per_m": 30, "S_xz_um_per_m": 0, "S_yz_um_per_m": 30}
    const Json& s = requireObject(doc, j, "linear_axis_squareness");
    const double sxy = numberOr(doc, s, "S_xy_um_per_m", 0.0, um_per_m) * 1e-6,
                 sxz = numberOr(doc, s, "S_xz_um_per_m", 0.0, um_per_m) * 1e-6,
                 syz = numberOr(doc, s, "S_yz_um_per_m", 0.0, um_per_m) * 1e-6;
    t.linear_axis_error = [sxy, sxz, syz](const Eigen::Vector3d& c) {
      return Eigen::Vector3d(sxy * c.y() + sxz * c.z(), syz * c.z(), 0.0);
    };
  }
  if (j.contains("linear_axis_scale")) {
    // Scale errors of the linear axes (003's scale error): actual = read (1 + s), per axis:
    // {"X_um_per_m": 50, "Y_um_per_m": 0, "Z_um_per_m": 0}. Adds to the squareness above.
    const Json& s = requireObject(doc, j, "linear_axis_scale");
    const Eigen::Vector3d sc(numberOr(doc, s, "X_um_per_m", 0.0, um_per_m) * 1e-6,
                             numberOr(doc, s, "Y_um_per_m", 0.0, um_per_m) * 1e-6,
                             numberOr(doc, s, "Z_um_per_m", 0.0, um_per_m) * 1e-6);
    auto before = t.linear_axis_error;
    t.linear_axis_error = [sc, before](const Eigen::Vector3d& c) {
      return Eigen::Vector3d(sc.cwiseProduct(c) + (before ? before(c) : Eigen::Vector3d::Zero()));
    };
  }
  if (j.contains("rotary_backlash")) {
    // Lost motion of the rotary axes: {"A_mdeg": 10, "B_mdeg": 0, "C_mdeg": 0}.
    const Json& r = requireObject(doc, j, "rotary_backlash");
    const Limits mdeg = Limits::nonNegative(kMaxAngleErrorMdeg, "mdeg");
    t.rotary_backlash_deg = Eigen::Vector3d(numberOr(doc, r, "A_mdeg", 0.0, mdeg), numberOr(doc, r, "B_mdeg", 0.0, mdeg),
                                            numberOr(doc, r, "C_mdeg", 0.0, mdeg)) * 1e-3;
  }
  t.noise_um = numberOr(doc, j, "probe_noise_um", 0.0, Limits::nonNegative(kMaxNoiseUm, "um"));
  t.pretravel_um = numberOr(doc, j, "probe_pretravel_um", 0.0, Limits::symmetric(kMaxNoiseUm, "um"));
  t.start_time_s = numberOr(doc, j, "start_time_s", 0.0, Limits::nonNegative(kMaxClockSeconds, "s"));
  return t;
}

}  // namespace

Truth truthOfModel(const KinematicModel& model, const Eigen::VectorXd& p) {
  Truth t;
  t.table_transform = [model, p](const Pose& pose, double) { return T_m_w(model, p, pose); };
  t.head_ball = [model, p](const Pose& pose, double) {
    return Eigen::Vector3d(T_c_t(model, p, pose) * Eigen::Vector3d(0.0, 0.0, -model.pivot_to_ball_mm));
  };
  return t;
}

Truth truthFromJson(const JsonDoc& doc, Kinematics kinematics) {
  return guardJson(doc, [&] { return truthFrom(doc, kinematics, nullptr); });
}

Truth truthFromJson(const JsonDoc& doc, const MachineModel& machine) {
  return guardJson(doc, [&] { return truthFrom(doc, machine.kinematics, &machine); });
}

Truth loadTruth(const std::string& path, Kinematics kinematics) { return truthFromJson(readJsonFile(path), kinematics); }

Json truthToJson(const Truth& t) {
  Json j;
  j["format"] = "rotacal-truth/1";
  Json le = Json::object();
  // A head_table truth keeps its model's parameters inside its transforms, not in errors.
  const auto& params = hasPapersLocationErrors(t.errors.kinematics) ? locationParameters(t.errors.kinematics)
                                                                      : std::vector<ParameterInfo>{};
  for (size_t i = 0; i < params.size(); ++i)
    le[std::string(params[i].name)] = {{"value", t.errors.reportValue(static_cast<int>(i))},
                                       {"unit", std::string(reportUnit(params[i].kind))}};
  j["location_errors"] = le;
  const auto& s = t.artefact.setup;
  j["setup_error"] = {{"translation_mm", {s.translation_mm.x(), s.translation_mm.y(), s.translation_mm.z()}},
                      {"rotation_mrad", {s.rotation_rad.x() * 1e3, s.rotation_rad.y() * 1e3, s.rotation_rad.z() * 1e3}}};
  Json form = Json::object();
  for (Face f : kAllFaces) {
    const FaceForm& ff = t.artefact.form[static_cast<size_t>(f)];
    if (ff.offset_mm == 0 && ff.tilt_u_rad == 0 && ff.tilt_v_rad == 0) continue;
    form[std::string(faceName(f))] = {{"offset_um", mmToUm(ff.offset_mm)},
                                      {"tilt_u_mrad", ff.tilt_u_rad * 1e3},
                                      {"tilt_v_mrad", ff.tilt_v_rad * 1e3}};
  }
  if (!form.empty()) j["form_error"] = form;
  if (!t.rotary_backlash_deg.isZero())
    j["rotary_backlash"] = {{"A_mdeg", t.rotary_backlash_deg[0] * 1e3}, {"B_mdeg", t.rotary_backlash_deg[1] * 1e3},
                            {"C_mdeg", t.rotary_backlash_deg[2] * 1e3}};
  if (t.noise_um > 0) j["probe_noise_um"] = t.noise_um;
  if (t.pretravel_um != 0) j["probe_pretravel_um"] = t.pretravel_um;
  return j;
}

}  // namespace rotacal
