#include "cycles/touch154/causes.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "core/rotary_backlash.hpp"
#include "core/units.hpp"

namespace rotacal {

namespace {

constexpr int kTranslations[3] = {0, 1, 2};  // dx_AY, dy_AY, dz_AY (A/C) or dx_BY, dy_CB, dz_BY (B/C)

class DriftLinear : public ModelExtension {
 public:
  std::string cause() const override { return "thermal_drift"; }
  std::string variant() const override { return "linear"; }
  std::string describe() const override {
    return "the table's position against the spindle (dx, dy, dz of the first rotary axis) changes at a constant rate";
  }
  std::vector<ExtensionParameter> parameters() const override {
    return {{"dx_AY/h", "um/h", kUmPerMm, 1e-6}, {"dy_AY/h", "um/h", kUmPerMm, 1e-6}, {"dz_AY/h", "um/h", kUmPerMm, 1e-6}};
  }
  LocationErrors errorsAt(const Eigen::VectorXd& p, const ObservationContext& o, const LocationErrors& e) const override {
    LocationErrors out = e;
    for (int i = 0; i < 3; ++i) out.values[kTranslations[i]] += p[i] * o.t_h;
    return out;
  }
};

class DriftPerRepeat : public ModelExtension {
 public:
  explicit DriftPerRepeat(int runs) : runs_(runs) {}
  std::string cause() const override { return "thermal_drift"; }
  std::string variant() const override { return "per_repeat"; }
  std::string describe() const override {
    return "the table's position against the spindle takes its own value in each repeat (any heating or cooling curve)";
  }
  std::vector<ExtensionParameter> parameters() const override {
    std::vector<ExtensionParameter> p;
    for (int r = 1; r < runs_; ++r)
      for (const char* n : {"dx_AY", "dy_AY", "dz_AY"})
        p.push_back({fmt::format("{}@repeat{}", n, r + 1), "um", kUmPerMm, 1e-6});
    return p;
  }
  LocationErrors errorsAt(const Eigen::VectorXd& p, const ObservationContext& o, const LocationErrors& e) const override {
    LocationErrors out = e;
    if (o.run >= 1 && o.run < runs_)
      for (int i = 0; i < 3; ++i) out.values[kTranslations[i]] += p[3 * (o.run - 1) + i];
    return out;
  }

 private:
  int runs_;
};

/// Direction classes of an approach: +X -X +Y -Y (horizontal) and -Z (reference).
int directionClass(const Eigen::Vector3d& u) {
  int axis = 0;
  u.cwiseAbs().maxCoeff(&axis);
  if (axis == 2) return -1;
  return axis * 2 + (u[axis] > 0 ? 0 : 1);
}

class Pretravel : public ModelExtension {
 public:
  std::string cause() const override { return "probe_pretravel"; }
  std::string variant() const override { return "by_direction"; }
  std::string describe() const override {
    return "the probe triggers after a travel that depends on the approach direction (lobing), relative to -Z";
  }
  std::vector<ExtensionParameter> parameters() const override {
    return {{"pretravel_+X", "um", kUmPerMm, 1e-6},
            {"pretravel_-X", "um", kUmPerMm, 1e-6},
            {"pretravel_+Y", "um", kUmPerMm, 1e-6},
            {"pretravel_-Y", "um", kUmPerMm, 1e-6}};
  }
  double triggerOffset(const Eigen::VectorXd& p, const ObservationContext& o) const override {
    const int c = directionClass(o.point->approach_m);
    return c < 0 ? 0.0 : p[c];
  }
};

class Squareness : public ModelExtension {
 public:
  std::string cause() const override { return "linear_axis_squareness"; }
  std::string variant() const override { return "S_xy_S_xz_S_yz"; }
  std::string describe() const override {
    return "the linear axes are not square (000 Eq. (23)): E_xy = S_xy y, E_xz = S_xz z, E_yz = S_yz z";
  }
  std::vector<ExtensionParameter> parameters() const override {
    // um/m: internal value is rad (mm/mm); 1 um/m = 1e-6.
    return {{"S_xy", "um/m", 1e6, 1e-7}, {"S_xz", "um/m", 1e6, 1e-7}, {"S_yz", "um/m", 1e6, 1e-7}};
  }
  bool hasPositionError() const override { return true; }
  Eigen::Vector3d positionError(const Eigen::VectorXd& p, const Eigen::Vector3d& c) const override {
    return Eigen::Vector3d(p[0] * c.y() + p[1] * c.z(), p[2] * c.z(), 0.0);
  }
};

class Scale : public ModelExtension {
 public:
  std::string cause() const override { return "linear_axis_scale"; }
  std::string variant() const override { return "xyz"; }
  std::string describe() const override {
    return "the linear axes position with a scale error (000 Eq. (22)): E_xx = s_x x, E_yy = s_y y, E_zz = s_z z";
  }
  std::vector<ExtensionParameter> parameters() const override {
    return {{"s_x", "um/m", 1e6, 1e-7}, {"s_y", "um/m", 1e6, 1e-7}, {"s_z", "um/m", 1e6, 1e-7}};
  }
  bool hasPositionError() const override { return true; }
  Eigen::Vector3d positionError(const Eigen::VectorXd& p, const Eigen::Vector3d& c) const override {
    return Eigen::Vector3d(p[0] * c.x(), p[1] * c.y(), p[2] * c.z());
  }
};

class ProbeLength : public ModelExtension {
 public:
  std::string cause() const override { return "probe_length"; }
  std::string variant() const override { return "constant"; }
  std::string describe() const override { return "the probe ball centre sits dL lower than the controller assumes"; }
  std::vector<ExtensionParameter> parameters() const override { return {{"dL", "um", kUmPerMm, 1e-6}}; }
  bool hasPositionError() const override { return true; }
  Eigen::Vector3d positionError(const Eigen::VectorXd& p, const Eigen::Vector3d&) const override {
    return Eigen::Vector3d(0.0, 0.0, -p[0]);
  }
};

class RotaryErrorMotionC2 : public ModelExtension {
 public:
  std::string cause() const override { return "rotary_error_motion"; }
  std::string variant() const override { return "C_radial_2nd"; }
  std::string describe() const override {
    return "the C axis's centre moves with its angle (second-order radial error motion, EXC and EYC in cos 2C)";
  }
  std::vector<ExtensionParameter> parameters() const override {
    return {{"EXC_cos2C", "um", kUmPerMm, 1e-6}, {"EYC_cos2C", "um", kUmPerMm, 1e-6}};
  }
  LocationErrors errorsAt(const Eigen::VectorXd& p, const ObservationContext& o, const LocationErrors& e) const override {
    LocationErrors out = e;
    if (!o.point) return out;
    // The C axis rides on A: its radial motion is a shift in the A frame, i.e. dx_AY (X stays X
    // under A) and dy_CA (Y of the C axis in the A frame).
    const double c2 = std::cos(2.0 * degToRad(o.point->pose.C));
    out.values[0] += p[0] * c2;
    out.values[3] += p[1] * c2;
    return out;
  }
};

// The tilt axis's own angle at a point (A on an A/C table, B on a B/C table): an extra rotation
// delta of the tilt axis about itself is, to first order, a change of its zero a_AY (b_BY) by
// -delta (000 Eq. (1): Da(a_AY) Db Dc Da(-A - delta); the Db Dc in between move it by
// delta x (b, c) ~ 1e-10 rad). Index 4 is a_AY (A/C) and b_BY (B/C).
constexpr int kTiltZero = 4;
double tiltOf(const ProbePlan& plan, const Pose& pose) {
  return plan.machine.kinematics == Kinematics::TableBC ? pose.B : pose.A;
}

/// The distinct tilts of a plan in the order its points first reach them.
std::vector<double> tiltsOf(const ProbePlan& plan) {
  std::vector<double> t;
  for (const auto& pt : plan.points) {
    const double a = tiltOf(plan, pt.pose);
    if (std::find(t.begin(), t.end(), a) == t.end()) t.push_back(a);
  }
  return t;
}

class TiltPositioning : public ModelExtension {
 public:
  TiltPositioning(const ProbePlan& plan, std::vector<double> tilts) : axis_(axisName(plan)), bc_(plan.machine.kinematics == Kinematics::TableBC), tilts_(std::move(tilts)) {}
  std::string cause() const override { return "tilt_axis_positioning"; }
  std::string variant() const override { return "per_tilt"; }
  std::string describe() const override {
    return fmt::format("the {} axis stands at an angle off its command that differs between its tilts (angular "
                       "positioning error E{}{} of ISO 230-7), relative to {} = {:g} deg",
                       axis_, axis_, axis_, axis_, tilts_.front());
  }
  std::vector<ExtensionParameter> parameters() const override {
    std::vector<ExtensionParameter> p;
    for (size_t k = 1; k < tilts_.size(); ++k)
      p.push_back({fmt::format("E{}{}@{}{:g}", axis_, axis_, axis_, tilts_[k]), "mdeg", radToMdeg(1.0), 1e-7});
    return p;
  }
  LocationErrors errorsAt(const Eigen::VectorXd& p, const ObservationContext& o, const LocationErrors& e) const override {
    LocationErrors out = e;
    if (!o.point) return out;
    const double a = bc_ ? o.point->pose.B : o.point->pose.A;
    for (size_t k = 1; k < tilts_.size(); ++k)
      if (a == tilts_[k]) out.values[kTiltZero] -= p[static_cast<long>(k - 1)];
    return out;
  }
  static std::string axisName(const ProbePlan& plan) { return plan.machine.kinematics == Kinematics::TableBC ? "B" : "A"; }

 private:
  std::string axis_;
  bool bc_;
  std::vector<double> tilts_;
};

/// Lost motion of the tilt axis: it stops b / 2 short of the command in the direction it last
/// moved, read from the plan's order of points as the simulator reads it (core/rotary_backlash.hpp).
class TiltBacklash : public ModelExtension {
 public:
  explicit TiltBacklash(const ProbePlan& plan) : axis_(TiltPositioning::axisName(plan)) {
    const int tilt = plan.machine.kinematics == Kinematics::TableBC ? 1 : 0;
    const std::vector<Eigen::Vector3d> dirs = rotaryApproachDirections(plan, true);
    for (size_t i = 0; i < plan.points.size(); ++i) dir_[plan.points[i].id] = dirs[i][tilt];
  }
  std::string cause() const override { return "tilt_axis_backlash"; }
  std::string variant() const override { return "lost_motion"; }
  std::string describe() const override {
    return fmt::format("the {} axis stops short of its command by half its lost motion, in the direction it last moved",
                       axis_);
  }
  std::vector<ExtensionParameter> parameters() const override {
    return {{fmt::format("backlash_{}", axis_), "mdeg", radToMdeg(1.0), 1e-7}};
  }
  LocationErrors errorsAt(const Eigen::VectorXd& p, const ObservationContext& o, const LocationErrors& e) const override {
    LocationErrors out = e;
    const auto it = o.point ? dir_.find(o.point->id) : dir_.end();
    if (it != dir_.end()) out.values[kTiltZero] += 0.5 * it->second * p[0];  // actual - command = -dir b / 2
    return out;
  }
  /// Whether the plan reaches some tilt from both sides, or only ever moves one way between tilts.
  static bool applies(const ProbePlan& plan) { return tiltsOf(plan).size() >= 2; }

 private:
  std::string axis_;
  std::map<int, double> dir_;  // by point id: the direction of the tilt axis's last move
};

}  // namespace

ExtensionPtr rotaryErrorMotionC2() { return std::make_shared<RotaryErrorMotionC2>(); }

ExtensionPtr thermalDriftLinear() { return std::make_shared<DriftLinear>(); }
ExtensionPtr thermalDriftPerRepeat(int runs) { return std::make_shared<DriftPerRepeat>(runs); }
ExtensionPtr probePretravel() { return std::make_shared<Pretravel>(); }
ExtensionPtr linearAxisSquareness() { return std::make_shared<Squareness>(); }
ExtensionPtr linearAxisScale() { return std::make_shared<Scale>(); }
ExtensionPtr probeLength() { return std::make_shared<ProbeLength>(); }
ExtensionPtr tiltAxisPositioning(const ProbePlan& plan) { return std::make_shared<TiltPositioning>(plan, tiltsOf(plan)); }
ExtensionPtr tiltAxisBacklash(const ProbePlan& plan) { return std::make_shared<TiltBacklash>(plan); }

std::vector<ExtensionPtr> catalogFor(const ProbePlan& plan, int runs) {
  std::vector<ExtensionPtr> c = {thermalDriftLinear()};
  if (runs >= 3) c.push_back(thermalDriftPerRepeat(runs));
  c.push_back(probePretravel());
  c.push_back(linearAxisSquareness());
  c.push_back(linearAxisScale());
  c.push_back(probeLength());
  if (plan.machine.kinematics == Kinematics::TableAC) c.push_back(rotaryErrorMotionC2());
  const bool table = plan.machine.kinematics == Kinematics::TableAC || plan.machine.kinematics == Kinematics::TableBC;
  if (table && TiltBacklash::applies(plan)) {
    c.push_back(tiltAxisPositioning(plan));
    c.push_back(tiltAxisBacklash(plan));
  }
  return c;
}

std::string separationHint(const std::string& cause, const std::vector<std::string>& with) {
  std::string list;
  for (const auto& w : with) list += (list.empty() ? "" : ", ") + w;
  if (cause == "probe_length")
    return "a probe-length error moves every trigger of a table-probing plan like " + list +
           ": no pose separates them; measure the probe length on a tool setter or probe a reference fixed to the "
           "machine bed";
  if (cause == "linear_axis_squareness")
    return "squareness of the linear axes acts like " + list +
           " on a piece that stays near one place: probe the piece at a second location (another X/Y/Z position) or "
           "calibrate the linear axes separately (000 Sec. 2.2)";
  if (cause == "linear_axis_scale")
    return "a scale error of the linear axes acts like " + list +
           " when the probed points span little of the axes' travel: probe the piece at a second location, or "
           "calibrate the axes with a laser interferometer or a step gauge";
  if (cause == "probe_pretravel")
    return "direction-dependent pretravel of 000's 154-point plan shifts the same points as " + list +
           ": calibrate the probe on a reference sphere or ring gauge first (ISO 230-10), or probe each target from "
           "two opposite directions at one pose";
  if (cause == "tilt_axis_backlash" || cause == "tilt_axis_positioning")
    return "a plan that reaches each tilt from one side only sees the tilt axis's lost motion as a positioning error "
           "at that tilt (" + cause + " and " + list + " move the data alike): reach each tilt from above and from "
           "below (a second pass in the other direction), or measure the axis's reversal with an autocollimator and "
           "polygon (ISO 230-2)";
  return "add poses or points where the columns of the Jacobian of " + cause + " and " + list + " differ";
}

}  // namespace rotacal
