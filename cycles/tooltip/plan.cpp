#include "cycles/tooltip/plan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/limits.hpp"

#include "core/errors.hpp"
#include "core/rng.hpp"
#include "core/units.hpp"
#include "cycles/options.hpp"

namespace rotacal {
namespace {

Eigen::Matrix3d rx(double a) {
  Eigen::Matrix3d m;
  m << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return m;
}
Eigen::Matrix3d ry(double b) {
  Eigen::Matrix3d m;
  m << std::cos(b), 0, std::sin(b), 0, 1, 0, -std::sin(b), 0, std::cos(b);
  return m;
}

/// The commanded angles of one sweep, in order.
std::vector<double> sweepAngles(const TooltipOptions& o) {
  const int n = static_cast<int>(std::lround(o.end_deg / o.step_deg));
  std::vector<double> out;
  if (o.sweeps == 0) {
    const int m = static_cast<int>(std::lround(-o.start_deg / o.step_deg));
    for (int k = -m; k <= n; ++k) out.push_back(k * o.step_deg);
    return out;
  }
  out.push_back(0.0);
  for (int s = 0; s < o.sweeps; ++s) {
    for (int k = 1; k <= n; ++k) out.push_back(k * o.step_deg);
    for (int k = n - 1; k >= -n; --k) out.push_back(k * o.step_deg);
    for (int k = -n + 1; k <= 0; ++k) out.push_back(k * o.step_deg);
  }
  return out;
}

Pose poseOf(const TooltipOptions& o, double theta_deg, double other_deg) {
  Pose p;
  (o.axis == 'A' ? p.A : p.B) = theta_deg;
  (o.axis == 'A' ? p.B : p.A) = other_deg;
  return p;
}

/// In-plane unit vectors of the reading: transverse (Y for A, X for B) and Z.
int transverseIndex(char axis) { return axis == 'A' ? 1 : 0; }

}  // namespace

TooltipOptions tooltipOptionsFrom(const CycleOptions& options, const MachineModel& machine) {
  if (machine.kinematics != Kinematics::HeadAB)
    throw std::invalid_argument(fmt::format("tooltip: the fixed-tool-tip cycle needs a spindle-head machine tilting in A "
                                            "and B (kinematics head_ab, e.g. examples/machines/head_ab.json), not a {} one",
                                            kinematicsName(machine.kinematics)));
  TooltipOptions o;
  o.inch = machine.units == LengthUnit::Inch;
  OptionTable("tooltip")
      .on("axis",
          [&](const std::string&, const std::string& v) {
            if (v != "A" && v != "B") throw std::invalid_argument("tooltip: option axis must be A or B, got '" + v + "'");
            o.axis = v[0];
          })
      .number("radius_mm", &o.radius_mm)
      .number("step_deg", &o.step_deg)
      .number("start_deg", &o.start_deg)
      .number("end_deg", &o.end_deg)
      .list("other_deg", &o.other_deg)
      .on("units",
          [&](const std::string&, const std::string& v) {
            if (v != "inch" && v != "mm") throw std::invalid_argument("tooltip: option units must be inch or mm, got '" + v + "'");
            o.inch = v == "inch";
          })
      .number("move_s", &o.move_s)
      .number("dwell_s", &o.dwell_s)
      .count("sweeps", &o.sweeps, 0, kMaxRepeats)
      .count("repeats", &o.repeats, 1, kMaxRepeats)
      .number("laser_noise_um", &o.noise_um)
      .number("max_sag_um", &o.max_sag_um)
      .read(options);
  if (!(o.radius_mm > 0)) throw std::invalid_argument("tooltip: option radius_mm must be positive");
  if (!(o.step_deg > 0) || !(o.end_deg > 0)) throw std::invalid_argument("tooltip: step_deg and end_deg must be positive");
  const double n = o.end_deg / o.step_deg;
  if (std::abs(n - std::round(n)) > 1e-9)
    throw std::invalid_argument(fmt::format("tooltip: end_deg {} is not a whole number of steps of {} deg", o.end_deg,
                                            o.step_deg));
  const double m = -o.start_deg / o.step_deg;
  if (o.start_deg > 0 || std::abs(m - std::round(m)) > 1e-9)
    throw std::invalid_argument("tooltip: start_deg must be <= 0 and a whole number of steps (the reading is zeroed at 0 deg)");
  // Readings per sweep: the static test from start_deg to end_deg; a dynamic test goes out to
  // +end, back to -end and home again, `sweeps` times. All of it once per other_deg angle.
  const double per_sweep = o.sweeps == 0 ? m + n + 1.0 : 1.0 + 4.0 * n * o.sweeps;
  requirePlanSize(fmt::format("tooltip: options step_deg = {:g}, end_deg = {:g}, start_deg = {:g}, sweeps = {}, other_deg "
                              "({} values)",
                              o.step_deg, o.end_deg, o.start_deg, o.sweeps, o.other_deg.size()),
                  per_sweep * static_cast<double>(o.other_deg.size()), static_cast<double>(o.other_deg.size()));
  if (o.start_deg < 0 && o.sweeps > 0) throw std::invalid_argument("tooltip: start_deg is for the static test (sweeps = 0)");
  if (!(o.move_s > 0)) throw std::invalid_argument("tooltip: option move_s must be positive");
  if (!(o.max_sag_um > 0) || !(o.max_sag_um < 1000.0))
    throw std::invalid_argument("tooltip: option max_sag_um must be in (0, 1000) um");
  if (o.sweeps > 0 && tooltipPiecesPerStep(o) > 10000)
    throw std::invalid_argument(fmt::format("tooltip: max_sag_um = {:g} needs {} moves per step: give a larger one",
                                            o.max_sag_um, tooltipPiecesPerStep(o)));
  if (o.dwell_s < 0) throw std::invalid_argument("tooltip: option dwell_s must be >= 0");
  if (!(o.noise_um > 0) || !std::isfinite(o.noise_um))
    throw std::invalid_argument("tooltip: option laser_noise_um (the declared laser noise) must be > 0");
  return o;
}

int tooltipPiecesPerStep(const TooltipOptions& o) {
  if (o.sweeps == 0) return 1;
  // A piece of angle phi moves the pivot along the chord of its circle about the fixed tip: the
  // tip leaves its point by the chord's sagitta, R (1 - cos(phi / 2)), at the piece's middle.
  const double phi_max = 2.0 * std::acos(1.0 - umToMm(o.max_sag_um) / o.radius_mm);
  return std::max(1, static_cast<int>(std::ceil(degToRad(o.step_deg) / phi_max - 1e-12)));
}

double tooltipSagUm(const TooltipOptions& o) {
  const double phi = degToRad(o.step_deg) / tooltipPiecesPerStep(o);
  return mmToUm(o.radius_mm * (1.0 - std::cos(phi / 2.0)));
}

Eigen::Vector3d tipOffset_m(double a_rad, double b_rad, double r_mm) {
  return rx(a_rad) * ry(b_rad) * Eigen::Vector3d(0, 0, -r_mm);
}

ProbePlan makeTooltipPlan(const MachineModel& machine, const CycleOptions& options) {
  const TooltipOptions o = tooltipOptionsFrom(options, machine);
  ProbePlan plan;
  plan.cycle = "tooltip";
  plan.machine = machine;
  plan.options = options;
  plan.options["axis"] = std::string(1, o.axis);
  plan.options["radius_mm"] = fmt::format("{}", o.radius_mm);
  plan.options["step_deg"] = fmt::format("{}", o.step_deg);
  plan.options["end_deg"] = fmt::format("{}", o.end_deg);
  plan.options["units"] = o.inch ? "inch" : "mm";
  // A new static plan runs kTooltipRepeats times unless told; the dynamic test reads every angle
  // several times in one run already. Written out, so the plan says what its program does.
  plan.options["repeats"] = fmt::format("{}", options.count("repeats") ? o.repeats : o.sweeps == 0 ? kTooltipRepeats : 1);
  plan.index_z_mm = 0.0;
  const std::vector<double> angles = sweepAngles(o);
  std::vector<std::string> problems;
  double t = 0.0;
  for (double other : o.other_deg) {
    const std::string name = fmt::format("{}{}", o.otherAxis(), other);
    PlanPose pp;
    pp.name = name;
    pp.pose = poseOf(o, 0.0, other);
    pp.safe_z_mm = 0.0;
    plan.poses.push_back(pp);
    const Pose p0 = poseOf(o, 0.0, other);
    const Eigen::Vector3d t0 = tipOffset_m(degToRad(p0.A), degToRad(p0.B), o.radius_mm);
    for (size_t k = 0; k < angles.size(); ++k) {
      ProbePoint pt;
      pt.id = static_cast<int>(plan.points.size()) + 1;
      pt.pose_name = name;
      pt.pose = poseOf(o, angles[k], other);
      pt.target = 1;
      // The fixed tip: where it was at the sweep's start, pivot at the origin (004: Yp = Zp = 0).
      pt.contact_w_mm = t0;
      pt.trigger_m_mm = t0 - tipOffset_m(degToRad(pt.pose.A), degToRad(pt.pose.B), o.radius_mm);
      // The laser reads the tangential direction of the rotation at theta (004 Fig. 2).
      const double th = degToRad(angles[k]);
      pt.approach_m = o.axis == 'A' ? Eigen::Vector3d(0, std::cos(th), std::sin(th))
                                    : Eigen::Vector3d(-std::cos(th), 0, std::sin(th));
      pt.normal_w = -pt.approach_m;
      if (k > 0) t += o.move_s + (o.sweeps == 0 ? o.dwell_s : 0.0);
      pt.t_s = t;
      const Eigen::Vector3d& c = pt.trigger_m_mm;
      if (!machine.x.contains(c.x()) || !machine.y.contains(c.y()) || !machine.z.contains(c.z()))
        problems.push_back(fmt::format("point {} ({} = {} deg): pivot at ({:.3f}, {:.3f}, {:.3f}) mm is outside the strokes",
                                       pt.id, o.axis, angles[k], c.x(), c.y(), c.z()));
      for (char ax : {'A', 'B'}) {
        const double v = ax == 'A' ? pt.pose.A : pt.pose.B;
        if (!machine.rotaryAxis(ax).continuous && !machine.rotaryAxis(ax).stroke_deg.contains(v))
          problems.push_back(fmt::format("point {}: {} = {} deg is outside its stroke", pt.id, ax, v));
      }
      plan.points.push_back(pt);
    }
    t += 60.0;  // re-positioning between sweeps
  }
  if (!problems.empty())
    throw std::invalid_argument(fmt::format("tooltip plan does not fit the machine: {}{}", problems.front(),
                                            problems.size() > 1 ? fmt::format(" (and {} more)", problems.size() - 1) : ""));
  return plan;
}

std::vector<int> tooltipReferences(const ProbePlan& plan) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  std::vector<int> refs(plan.points.size(), -1);
  std::map<std::string, int> ref_of;
  for (size_t k = 0; k < plan.points.size(); ++k) {
    const Pose& p = plan.points[k].pose;
    if (std::abs(o.axis == 'A' ? p.A : p.B) < 1e-9 && !ref_of.count(plan.points[k].pose_name))
      ref_of[plan.points[k].pose_name] = static_cast<int>(k);
  }
  for (size_t k = 0; k < plan.points.size(); ++k) {
    const auto it = ref_of.find(plan.points[k].pose_name);
    if (it == ref_of.end())
      throw std::invalid_argument("tooltip plan: sweep " + plan.points[k].pose_name + " has no pose at 0 deg");
    refs[k] = it->second;
  }
  return refs;
}

double TooltipTruth::angularErrorMdeg(double theta_deg) const {
  const double th = degToRad(theta_deg);
  return offset_mdeg + slope_mdeg_per_90deg * theta_deg / 90.0 + sin_mdeg * std::sin(th) + sin2_mdeg * std::sin(2 * th);
}

TooltipTruth tooltipTruthFrom(const JsonDoc& doc, const Json& truth) {
  return guardJson(doc, [&] {
    TooltipTruth t;
    if (!truth.is_object() || !truth.contains("format") || truth["format"] != "rotacal-truth/1")
      doc.fail(truth, "format", "not a truth file (expected \"format\": \"rotacal-truth/1\")");
    if (truth.contains("location_errors") && !truth["location_errors"].empty())
      doc.fail(truth, "location_errors", "a tooltip truth has no table location errors: use the 'tooltip' object");
    t.noise_um = numberOr(doc, truth, "probe_noise_um", 0.0, Limits::nonNegative(kMaxNoiseUm, "um"));
    if (!truth.contains("tooltip")) return t;
    const Json& j = requireObject(doc, truth, "tooltip");
    static const std::set<std::string> known = {"dR_um", "angular_error", "scale_um_m"};
    for (const auto& [k, v] : j.items())
      if (!known.count(k))
        doc.fail(j, k, "unknown tooltip truth field '" + k + "' (expected dR_um, angular_error, scale_um_m)");
    t.dR_um = numberOr(doc, j, "dR_um", 0.0, Limits::symmetric(kMaxLocationErrorUm, "um"));
    // An isotropic scale error of the two linear axes in the read plane.
    t.scale_t_um_m = t.scale_z_um_m = numberOr(doc, j, "scale_um_m", 0.0, Limits::symmetric(1000.0, "um/m"));
    if (j.contains("angular_error")) {
      const Json& e = requireObject(doc, j, "angular_error");
      static const std::set<std::string> ek = {"offset_mdeg", "slope_mdeg_per_90deg", "sin_mdeg", "sin2_mdeg"};
      for (const auto& [k, v] : e.items())
        if (!ek.count(k)) doc.fail(e, k, "unknown angular_error term '" + k + "'");
      const Limits mdeg = Limits::symmetric(kMaxAngleErrorMdeg, "mdeg");
      t.offset_mdeg = numberOr(doc, e, "offset_mdeg", 0.0, mdeg);
      t.slope_mdeg_per_90deg = numberOr(doc, e, "slope_mdeg_per_90deg", 0.0, mdeg);
      t.sin_mdeg = numberOr(doc, e, "sin_mdeg", 0.0, mdeg);
      t.sin2_mdeg = numberOr(doc, e, "sin2_mdeg", 0.0, mdeg);
    }
    return t;
  });
}

TooltipRun simulateTooltip(const ProbePlan& plan, const TooltipTruth& truth, std::uint64_t seed) {
  return simulateTooltip(plan, truth, seed, TooltipMachine{});
}

TooltipRun simulateTooltip(const ProbePlan& plan, const TooltipTruth& truth, std::uint64_t seed, const TooltipMachine& machine,
                           double start_s) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const double r_true = o.radius_mm + umToMm(truth.dR_um);
  const int ti = transverseIndex(o.axis);
  Rng rng(seed, 4);
  TooltipRun run;
  std::vector<Eigen::Vector3d> devs;
  for (const auto& pt : plan.points) {
    // Exact: the pivot goes where commanded; the head turns to the commanded angle plus its
    // angular positioning error; the tip hangs at the true R.
    Pose actual = pt.pose;
    double& th = o.axis == 'A' ? actual.A : actual.B;
    th += truth.angularErrorMdeg(th) / 1000.0;  // mdeg -> deg
    // The linear axes put the pivot at (1 + s) x its command in the read plane.
    Eigen::Vector3d pivot = pt.trigger_m_mm;
    pivot[ti] *= 1.0 + 1e-6 * truth.scale_t_um_m;
    pivot.z() *= 1.0 + 1e-6 * truth.scale_z_um_m;
    if (machine.pivot_error_mm) pivot += machine.pivot_error_mm(pt.trigger_m_mm);
    Eigen::Vector3d tip = pivot + tipOffset_m(degToRad(actual.A), degToRad(actual.B), r_true);
    tip[ti] += umToMm(truth.drift_t_um_h * (start_s + pt.t_s) / 3600.0);
    tip.z() += umToMm(truth.drift_z_um_h * (start_s + pt.t_s) / 3600.0);
    devs.push_back(tip - pt.contact_w_mm);
  }
  Eigen::Vector3d beam_t = machine.beam_t;
  if (beam_t.isZero()) beam_t = Eigen::Vector3d::Unit(ti);
  const std::vector<int> refs = tooltipReferences(plan);
  // The laser is zeroed on a reading of each sweep's zero pose, as noisy as any other: every
  // later reading of the sweep is its own reading less that one. Drawn from a stream of its own,
  // so that the other readings' draws are those of a zero taken as exact.
  Rng zero_rng(seed, 5);
  std::vector<Eigen::Vector2d> zero_noise(plan.points.size(), Eigen::Vector2d::Zero());
  for (size_t k = 0; k < plan.points.size(); ++k)
    if (truth.noise_um > 0 && refs[k] == static_cast<int>(k)) {
      zero_noise[k].x() = truth.noise_um * zero_rng.normal();
      zero_noise[k].y() = truth.noise_um * zero_rng.normal();
    }
  for (size_t k = 0; k < plan.points.size(); ++k) {
    const ProbePoint& pt = plan.points[k];
    const Eigen::Vector3d rel = mmToUm(1.0) * (devs[k] - devs[refs[k]]);
    TooltipReading r;
    r.angle_deg = o.axis == 'A' ? pt.pose.A : pt.pose.B;
    r.t_um = beam_t.dot(rel);
    r.z_um = machine.beam_z.dot(rel);
    if (truth.noise_um > 0 && refs[k] != static_cast<int>(k)) {
      r.t_um += truth.noise_um * rng.normal() - zero_noise[static_cast<size_t>(refs[k])].x();
      r.z_um += truth.noise_um * rng.normal() - zero_noise[static_cast<size_t>(refs[k])].y();
    }
    run.push_back(r);
  }
  return run;
}

double tooltipRunSeconds(const ProbePlan& plan) {
  // makeTooltipPlan's re-positioning between sweeps: the next run starts as a next sweep would.
  return plan.points.empty() ? 0.0 : plan.points.back().t_s + 60.0;
}

std::vector<TooltipRun> simulateTooltipRepeats(const ProbePlan& plan, const TooltipTruth& truth, std::uint64_t seed,
                                               const TooltipMachine& machine, double start_s) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  std::vector<TooltipRun> runs;
  std::uint64_t next = seed;
  for (int r = 0; r < o.repeats; ++r) {
    // Run 0 reads with `seed` itself, so a plan of one run simulates as before repeats existed.
    const std::uint64_t s = r == 0 ? seed : splitmix64(next);
    runs.push_back(simulateTooltip(plan, truth, s, machine, start_s + r * tooltipRunSeconds(plan)));
  }
  return runs;
}

std::string tooltipResultsText(const ProbePlan& plan, const std::vector<TooltipRun>& runs) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  std::string out = o.axis == 'A' ? "angle_deg,dy_um,dz_um\n" : "angle_deg,dx_um,dz_um\n";
  for (size_t k = 0; k < runs.size(); ++k) {
    if (k > 0) out += fmt::format("# run {}\n", k + 1);
    for (const auto& r : runs[k]) out += fmt::format("{:.4f},{:.4f},{:.4f}\n", r.angle_deg, r.t_um, r.z_um);
  }
  return out;
}

std::string tooltipResultsText(const ProbePlan& plan, const TooltipRun& run) {
  return tooltipResultsText(plan, std::vector<TooltipRun>{run});
}

std::vector<TooltipRun> parseTooltipResults(const std::string& text, const std::string& file, const ProbePlan& plan) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  const size_t points = plan.points.size();
  const std::string header = o.axis == 'A' ? "angle_deg,dy_um,dz_um" : "angle_deg,dx_um,dz_um";
  // 004's laser reads one direction: the transverse column alone is a results file too.
  const std::string header_t = o.axis == 'A' ? "angle_deg,dy_um" : "angle_deg,dx_um";
  int columns = 3;
  std::vector<TooltipRun> runs;
  size_t read = 0;
  int line_no = 0;
  size_t pos = 0;
  bool seen_header = false;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (!seen_header) {
      if (line != header && line != header_t)
        throw InputError(file, line_no,
                         "expected the header '" + header + "' (or '" + header_t + "' for one direction), got '" + line + "'");
      columns = line == header ? 3 : 2;
      seen_header = true;
      continue;
    }
    double v[3] = {0.0, 0.0, std::numeric_limits<double>::quiet_NaN()};
    size_t p = 0;
    for (int i = 0; i < columns; ++i) {
      const size_t comma = i < columns - 1 ? line.find(',', p) : line.size();
      if (comma == std::string::npos || (i == columns - 1 && line.find(',', p) != std::string::npos))
        throw InputError(file, line_no, fmt::format("expected {} comma-separated numbers", columns));
      const std::string cell = line.substr(p, comma - p);
      try {
        size_t used = 0;
        v[i] = std::stod(cell, &used);
        if (used != cell.size() || !std::isfinite(v[i])) throw std::invalid_argument("");
      } catch (const std::exception&) {
        throw InputError(file, line_no, "'" + cell + "' is not a number");
      }
      p = comma + 1;
    }
    if (read >= points * static_cast<size_t>(o.repeats))
      throw InputError(file, line_no,
                       fmt::format("more readings than the plan's {} run{} of {} poses", o.repeats, o.repeats == 1 ? "" : "s",
                                   points));
    const size_t k = read % points;
    if (k == 0) runs.emplace_back();
    const Pose& pose = plan.points[k].pose;
    const double want = o.axis == 'A' ? pose.A : pose.B;
    if (std::abs(v[0] - want) > 1e-3)
      throw InputError(file, line_no,
                       fmt::format("reading {}{} is at {} = {} deg, the plan says {} deg", k + 1,
                                   runs.size() > 1 ? fmt::format(" of run {}", runs.size()) : std::string(), o.axis, v[0], want));
    runs.back().push_back({v[0], v[1], v[2]});
    ++read;
  }
  if (!seen_header) throw InputError(file, std::max(line_no, 1), "empty results file (expected the header '" + header + "')");
  if (runs.empty() || runs.back().size() != points)
    throw InputError(file, line_no,
                     runs.size() > 1 ? fmt::format("run {} has {} readings, the plan has {} poses", runs.size(),
                                                   runs.back().size(), points)
                                     : fmt::format("{} readings, the plan has {} poses", read, points));
  return runs;
}

PlanRules tooltipPlanRules() {
  PlanRules r;
  r.heights = false;  // no probing moves: the tool tip stays at the laser's target
  r.check_options = [](const ProbePlan& p) { (void)tooltipOptionsFrom(p.options, p.machine); };
  return r;
}

}  // namespace rotacal
