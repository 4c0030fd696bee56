#include "cycles/one_sphere/plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/contributor_draw.hpp"
#include "core/identifiability.hpp"
#include "core/kinematic_model.hpp"
#include "core/pose_design.hpp"
#include "core/rotary_backlash.hpp"
#include "core/units.hpp"
#include "cycles/one_sphere/design.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

namespace {


std::vector<std::pair<double, double>> parsePoseList(const std::string& key, const std::string& text) {
  std::vector<std::pair<double, double>> out;
  if (text.empty()) return out;
  size_t at = 0;
  while (at <= text.size()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    const size_t slash = item.find('/');
    if (slash == std::string::npos)
      throw std::invalid_argument(fmt::format("option {}: '{}' is not tilt/turn (deg), e.g. -90/0,0/90", key, item));
    out.emplace_back(parseNumber(key, item.substr(0, slash)), parseNumber(key, item.substr(slash + 1)));
    at = comma + 1;
  }
  return out;
}

std::string poseListOption(const std::vector<std::pair<double, double>>& poses) {
  std::string s;
  for (const auto& [t, c] : poses) s += fmt::format("{}{:g}/{:g}", s.empty() ? "" : ",", t, c);
  return s;
}

bool parseSwitch(const std::string& key, const std::string& text) {
  if (text == "1" || text == "true") return true;
  if (text == "0" || text == "false") return false;
  throw std::invalid_argument(fmt::format("option {} must be 0 or 1, not '{}'", key, text));
}

Pose poseOf(char tilt_axis, char turn_axis, double tilt, double turn) {
  Pose p;
  (tilt_axis == 'A' ? p.A : p.B) = tilt;
  (turn_axis == 'A' ? p.A : (turn_axis == 'B' ? p.B : p.C)) = turn;
  return p;
}

}  // namespace

const std::vector<std::pair<const char*, const char*>>& spherePapersNames(Kinematics k) {
  static const std::vector<std::pair<const char*, const char*>> ac = {
      {"dx_AY", "X0C"}, {"dy_AY", "Y0A"}, {"dz_AY", "Z0A"}, {"dy_CA", "Y0C"},
      {"a_AY", "A0A"},  {"b_AY", "B0A"},  {"c_AY", "C0A"},  {"b_CA", "B0C"}};
  static const std::vector<std::pair<const char*, const char*>> bc = {
      {"dx_BY", "X0B"}, {"dy_CB", "Y0C"}, {"dz_BY", "Z0B"}, {"a_BY", "A0B"},
      {"b_BY", "B0B"},  {"c_BY", "C0B"},  {"a_CB", "A0C"},  {"dx_CB", "X0C"}};
  // The A/B table's chain (core/error_model.hpp) carries the model's own factors in the same
  // order but for the B axis's three angles, placed before its translations as in 002.
  static const std::vector<std::pair<const char*, const char*>> ab = {
      {"dx_BY", "X0B"}, {"dy_AB", "Y0A"}, {"dz_BY", "Z0B"}, {"a_BY", "A0B"},
      {"b_BY", "B0B"},  {"c_BY", "C0B"},  {"c_AB", "C0A"},  {"dz_AB", "Z0A"}};
  if (k == Kinematics::TableAB) return ab;
  return k == Kinematics::TableAC ? ac : bc;
}

char sphereTiltAxis(const MachineModel& machine) {
  if (hasPapersLocationErrors(machine.kinematics)) return tableTiltAxis(machine.kinematics);
  if (machine.kinematics == Kinematics::HeadTable && machine.head) return machine.head->axis;
  if (machine.kinematics == Kinematics::HeadAB && machine.head) return 'A';
  // head_cb: the B head tilts the spindle, the C head turns the tilt's direction about Z.
  if (machine.kinematics == Kinematics::HeadCB && machine.head) return 'B';
  throw std::invalid_argument(fmt::format(
      "cycle one_sphere needs the touch probe's place on a {} machine: MACHINE.json \"head\": {{\"pivot_to_ball_mm\": "
      "L}} (without it the tooltip cycle (004) calibrates a tester's sphere at its radius_mm)",
      kinematicsName(machine.kinematics)));
}

char sphereTurnAxis(const MachineModel& machine) {
  if (hasPapersLocationErrors(machine.kinematics)) return tableTurnAxis(machine.kinematics);
  return machine.kinematics == Kinematics::HeadAB ? 'B' : 'C';
}

KinematicModel sphereModel(const MachineModel& machine, const Eigen::Vector3d& center_w_mm) {
  if (machine.head)
    return kinematicModel(kinematicsName(machine.kinematics), center_w_mm, machine.head->pivot_to_ball_mm,
                          machine.head->axis ? machine.head->axis : 'B');
  return kinematicModel(kinematicsName(machine.kinematics), center_w_mm);
}

int sphereUnseenByAnyPlan(const KinematicModel& m, bool squareness) {
  if (m.head_axes.empty()) return 2;
  if (m.table_axes.empty()) return 5;  // head_ab, head_cb: the ball's readings span a sphere of radius L, which shows the shear
  return squareness ? 6 : 5;
}

const std::vector<Eigen::Vector3d>& sphereApproaches() {
  static const std::vector<Eigen::Vector3d> a = {-Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitY(),
                                                 Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                                 -Eigen::Vector3d::UnitZ()};
  return a;
}

SphereLayout SphereLayout::fromOptions(const MachineModel& machine, const CycleOptions& options) {
  SphereLayout l;
  const RotaryAxis& tilt = machine.rotaryAxis(sphereTiltAxis(machine));
  l.turn_axis = sphereTurnAxis(machine);
  const auto designing = options.find("poses");
  const bool fine = designing != options.end() && designing->second != "0";
  // The grid a design picks from is finer than the grid run whole. A head tilts its spindle, and
  // the spindle housing (not modelled, only the probe is) comes down towards the table as the
  // tilt grows: by default a head stays within 60 deg (tilt_list goes further). So does the A/B
  // table's B: with A turned too, B at 90 deg lays the stem across all but three sides.
  const double widest = machine.head || machine.kinematics == Kinematics::TableAB ? 60.0 : 90.0;
  for (double t = -widest; t <= widest; t += fine ? 15.0 : 30.0)
    if (tilt.stroke_deg.contains(t)) l.tilt_deg.push_back(t);
  if (l.turn_axis != 'C') {
    // head_ab's second head axis tilts the spindle too, and table_ab's A table tilts the sphere
    // about X: the same range as the first.
    const RotaryAxis& turn = machine.rotaryAxis(l.turn_axis);
    l.c_deg.clear();
    for (double t = -widest; t <= widest; t += fine ? 15.0 : 30.0)
      if (turn.stroke_deg.contains(t)) l.c_deg.push_back(t);
  } else if (fine) {
    l.c_deg.clear();
    for (double c = 0.0; c < 360.0; c += 30.0) l.c_deg.push_back(c);
  }
  const std::string turn_key = l.turnListOption();
  // The turning axis's list is named for the axis (c_list, b_list on head_ab, a_list on table_ab): another
  // axis's list is unknown on this machine.
  OptionTable("one_sphere")
      .vec3("center_w_mm", &l.center_w_mm)
      .number("radius_mm", &l.radius_mm)
      .number("stem_length_mm", &l.stem_length_mm)
      .number("stem_diameter_mm", &l.stem_diameter_mm)
      .list("tilt_list", &l.tilt_deg)
      .list(turn_key, &l.c_deg)
      .on("pose_list", [&](const std::string& k, const std::string& v) { l.pose_list = parsePoseList(k, v); })
      .count("poses", &l.design_poses, 0, 1000)
      .on("design",
          [&](const std::string& k, const std::string& v) {
            if (v != "D" && v != "A")
              throw std::invalid_argument(fmt::format("option {} must be D or A, not '{}'", k, v));
            l.design_criterion = v[0];
          })
      .on("fit_squareness", [&](const std::string& k, const std::string& v) { l.fit_squareness = parseSwitch(k, v); })
      .on("backlash", [&](const std::string& k, const std::string& v) { l.backlash = parseSwitch(k, v); })
      .read(options);
  if (l.design_criterion != 'D' && l.design_poses == 0)
    throw std::invalid_argument("option design chooses how option poses designs: it needs poses");
  if (!l.pose_list.empty() && l.design_poses > 0)
    throw std::invalid_argument("options pose_list and poses exclude each other (poses designs a pose_list)");
  if (!(l.radius_mm > 0)) throw std::invalid_argument("option radius_mm must be > 0");
  if (!(l.stem_diameter_mm > 0 && l.stem_diameter_mm < l.radius_mm))
    throw std::invalid_argument("option stem_diameter_mm must be > 0 and below the sphere's radius");
  if (!(l.stem_length_mm > l.radius_mm))
    throw std::invalid_argument("option stem_length_mm must exceed the sphere's radius (the sphere stands on its stem)");
  requirePlanSize(fmt::format("options tilt_list and {} ({} x {} poses)", turn_key, l.tilt_deg.size(), l.c_deg.size()),
                  5.0 * static_cast<double>(l.tilt_deg.size() * l.c_deg.size()),
                  static_cast<double>(l.tilt_deg.size() * l.c_deg.size()));
  requirePlanSize(fmt::format("option pose_list ({} poses)", l.pose_list.size()), 5.0 * static_cast<double>(l.pose_list.size()),
                  static_cast<double>(l.pose_list.size()));
  if (l.design_poses > 0 && static_cast<size_t>(l.design_poses) > l.tilt_deg.size() * l.c_deg.size())
    throw std::invalid_argument(fmt::format("option poses = {} exceeds the {} x {} candidate poses of tilt_list x {}",
                                            l.design_poses, l.tilt_deg.size(), l.c_deg.size(), turn_key));
  return l;
}

CycleOptions SphereLayout::toOptions() const {
  CycleOptions o = {{"center_w_mm", fmt::format("{:g},{:g},{:g}", center_w_mm.x(), center_w_mm.y(), center_w_mm.z())},
          {"radius_mm", fmt::format("{:g}", radius_mm)},
          {"stem_length_mm", fmt::format("{:g}", stem_length_mm)},
          {"stem_diameter_mm", fmt::format("{:g}", stem_diameter_mm)},
          {"tilt_list", numberListOption(tilt_deg)},
          {turnListOption(), numberListOption(c_deg)},
          {"fit_squareness", fit_squareness ? "1" : "0"}};
  if (!pose_list.empty()) o["pose_list"] = poseListOption(pose_list);
  if (backlash) o["backlash"] = "1";
  return o;
}

std::vector<std::pair<double, double>> SphereLayout::poses() const {
  if (!pose_list.empty()) return pose_list;
  std::vector<std::pair<double, double>> grid;
  for (double t : tilt_deg)
    for (double c : c_deg) grid.emplace_back(t, c);
  return grid;
}

SphereLayout sphereLayoutOf(const ProbePlan& plan) { return SphereLayout::fromOptions(plan.machine, plan.options); }

namespace {

// One pose's touches, or std::invalid_argument saying why the pose is refused.
struct PoseTouches {
  PlanPose pose;
  std::vector<ProbePoint> points;
};

PoseTouches touchesAt(const MachineModel& machine, const SphereLayout& l, char tilt_axis, double tilt, double c) {
  const char turn_axis = l.turn_axis;
  const double r = machine.probe.ball_radius_mm();
  const double R = l.radius_mm;
  const double reach = R + r + machine.approach_mm;  // the side touches' starts, from the centre
  const Pose pose = poseOf(tilt_axis, turn_axis, tilt, c);
  const std::string name = fmt::format("{}{:g}{}{:g}", tilt_axis, tilt, turn_axis, c);
  const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
  const Eigen::Vector3d c_m = T * l.center_w_mm;
  const Eigen::Vector3d s_m = T.linear() * -Eigen::Vector3d::UnitZ();  // the stem, from the centre
  const Eigen::Vector3d b_m = ballFromAxes_m(machine, pose);            // a head's ball, from the reading
  const Eigen::Vector3d d_m = stylusAxis_m(machine, pose);              // from the ball to the probe body
  if (s_m.z() > 1e-9)
    throw std::invalid_argument(fmt::format(
        "pose {}: {} = {:g} deg turns the table above the sphere: the probe would reach it past the table "
        "(keep |tilt| <= 90 deg)",
        name, tilt_axis, tilt));
  const std::string near = sphereReachRefusal(machine, T, c_m, R, reach);
  if (!near.empty())
    throw std::invalid_argument(fmt::format("pose {}: {} (move the sphere with center_w_mm or choose other angles with "
                                            "tilt_list, {})", name, near, l.turnListOption()));
  PoseTouches out{{name, pose, c_m.z() + R + r + machine.clearance_mm - b_m.z()}, {}};
  // The side approaches turned about Z until one faces the stylus's lean: a head tilted in two
  // axes leans it diagonally, and of four axis-parallel sides only two would face it. A lean along
  // X or Y (a table, one head axis) turns nothing. Likewise until one faces the stem's lean: an A/B
  // table tilted in both axes leans the stem diagonally, and three axis-parallel sides would touch
  // its half of the sphere; turned, one side does and the other three lie on or off its boundary.
  double turn = 0.0;
  if (std::hypot(d_m.x(), d_m.y()) > 1e-9) turn = std::remainder(std::atan2(d_m.y(), d_m.x()), kPi / 2);
  else if (std::hypot(s_m.x(), s_m.y()) > 1e-9) turn = std::remainder(std::atan2(s_m.y(), s_m.x()), kPi / 2);
  if (std::abs(turn) < 1e-9) turn = 0.0;
  const Eigen::Matrix3d R_turn = Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const auto& approaches = sphereApproaches();
  for (size_t j = 0; j < approaches.size(); ++j) {
    const Eigen::Vector3d u = turn == 0.0 ? approaches[j] : Eigen::Vector3d(R_turn * approaches[j]);
    const Eigen::Vector3d n_m = -u;  // outward normal at the contact
    if (n_m.dot(s_m) > 1e-9) continue;  // the stem's half: the stylus would reach round to the stem
    if (n_m.dot(d_m) < -1e-9) continue;  // the far half from a tilted stylus: it would reach round the sphere
    ProbePoint p;
    p.pose_name = name;
    p.pose = pose;
    p.target = static_cast<int>(j) + 1;
    p.face = faceOfNormal(n_m);
    p.contact_w_mm = T.inverse() * (c_m + R * n_m);
    p.normal_w = T.linear().transpose() * n_m;
    p.trigger_m_mm = c_m + (R + r) * n_m - b_m;
    p.approach_m = u;
    p.sphere = SphereTarget{1, l.center_w_mm, R};
    out.points.push_back(p);
  }
  if (out.points.size() < 4) throw std::invalid_argument(fmt::format("pose {}: fewer than 4 touches clear the stem", name));
  return out;
}

// Whether a pose's path (index, safe height, every approach and overtravel) stays in the strokes.
bool withinStrokes(const MachineModel& machine, double index_z_mm, const PoseTouches& p) {
  ProbePlan one;
  one.machine = machine;
  one.index_z_mm = index_z_mm;
  one.poses = {p.pose};
  one.points = p.points;
  for (size_t k = 0; k < one.points.size(); ++k) one.points[k].id = static_cast<int>(k) + 1;
  return strokeViolations(one).empty();
}

// The fit's Jacobian rows of a pose's touches at nominal, per unit repeatability.
Eigen::MatrixXd touchRows(const KinematicModel& m, bool squareness, const PoseTouches& p, double rho) {
  const auto names = sphereFitParameters(m, squareness);
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(names.size()));
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(p.points.size()), x0.size());
  for (size_t k = 0; k < p.points.size(); ++k) {
    Eigen::RowVectorXd row;
    sphereTouchResidual(m, squareness, x0, p.pose.pose, p.points[k].trigger_m_mm, rho, &row);
    rows.row(static_cast<Eigen::Index>(k)) = row;
  }
  return rows;
}

// Option design=A: from the D-optimal poses, the exchange that lowers the location errors'
// variances under the machine's declared contributors, each weighed by its reference (the
// contributors' file's, else 1 um and 1 mdeg). The touches' covariance is the contributors' first
// order (probeAxesCovariance): the linear axes' random errors shared by nearby touches, which
// D-optimality, counting the probe alone, takes for independent.
PoseDesign refineForContributors(const MachineModel& machine, const KinematicModel& model, const SphereLayout& l,
                                 const std::vector<PoseTouches>& candidates,
                                 const std::vector<IdentifiabilityParameter>& names, const std::vector<int>& start,
                                 const std::vector<int>& hold_first) {
  if (!machine.contributors)
    throw std::invalid_argument(
        "option design=A weighs the poses by the machine's declared contributors: MACHINE.json has no \"contributors\"");
  const ContributorSet& cs = *machine.contributors;
  std::vector<Eigen::MatrixXd> rows;
  std::vector<Eigen::Vector3d> t, u;
  for (const auto& c : candidates) {
    rows.push_back(touchRows(model, l.fit_squareness, c, l.radius_mm + machine.probe.ball_radius_mm()));
    for (const auto& p : c.points) t.push_back(p.trigger_m_mm), u.push_back(p.approach_m);
  }
  const Eigen::MatrixXd C = probeAxesCovariance(
      cs, [](const ContributorInfo& i) { return isPerTouchContributor(i) || isProbeAxesContributor(i); }, t, u);
  PoseBudgetOptions o;
  o.hold_first = hold_first;
  o.weight = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(names.size()));
  for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(model.parameters.size()); ++k) {
    const bool length = names[static_cast<size_t>(k)].kind == ParamKind::Length;
    double ref = length ? umToMm(1.0) : mdegToRad(1.0);
    if (cs.reference && hasPapersLocationErrors(machine.kinematics))
      for (const auto& [papers, iso] : spherePapersNames(machine.kinematics)) {
        if (names[static_cast<size_t>(k)].name != iso) continue;
        const auto it = cs.reference->combined.find(papers);
        if (it != cs.reference->combined.end() && it->second > 0) ref = length ? umToMm(it->second) : mdegToRad(it->second);
      }
    o.weight[k] = 1.0 / (ref * ref);
  }
  return refinePosesForBudget(rows, names, C, start, o);
}

}  // namespace

std::vector<int> sphereHeldFirst(const KinematicModel& m) {
  if (m.table_axes.empty()) return {};  // head_ab, head_cb: the rule's own choice (plan.hpp)
  if (!m.head_axes.empty()) return {m.parameterIndex("C0C")};
  // The inner table axis's zero, and its tilt about the outer axis's direction.
  const std::string inner(1, m.table_axes.back());
  return {m.parameterIndex(inner + "0" + inner), m.parameterIndex(std::string(1, m.table_axes.front()) + "0" + inner)};
}

ProbePlan makeSpherePlan(const MachineModel& machine, const CycleOptions& options) {
  const char tilt_axis = sphereTiltAxis(machine);
  SphereLayout l = SphereLayout::fromOptions(machine, options);
  if (!machine.hasRotary(l.turn_axis))
    throw std::invalid_argument(fmt::format("cycle one_sphere needs a {} axis on this machine", l.turn_axis));
  const double r = machine.probe.ball_radius_mm();
  const double R = l.radius_mm;
  if (machine.probe.stylus_length_mm < R + machine.probe.body_clearance_mm)
    throw std::invalid_argument(fmt::format(
        "the stylus ({:g} mm) is too short for a side touch at the equator of a {:g} mm sphere: the probe body would "
        "come within {:g} mm of its top",
        machine.probe.stylus_length_mm, 2 * R, machine.probe.body_clearance_mm));
  const KinematicModel model = sphereModel(machine, l.center_w_mm);
  auto names = sphereFitParameters(model, l.fit_squareness);

  // The axes index with the ball above everything the table carries, whatever the pose (a head
  // may swing the ball down to L below Z on the way).
  const double index_z_mm =
      tableSweepRadius(machine, l.center_w_mm, R) + r + machine.clearance_mm + ballDropBelowAxes(machine);

  std::vector<PoseTouches> poses;
  if (l.design_poses > 0) {
    // The candidates the machine allows (a refused one is simply not a candidate), then the
    // D-optimal n of them, run in the grid's order (tilt, then C: the shortest rotary moves).
    std::vector<PoseTouches> candidates;
    std::vector<Eigen::MatrixXd> rows;
    const double sd_mm = umToMm(machine.probe.repeatability_um);
    for (const auto& [t, c] : l.poses()) {
      try {
        candidates.push_back(touchesAt(machine, l, tilt_axis, t, c));
      } catch (const std::invalid_argument&) {
        continue;
      }
      if (!withinStrokes(machine, index_z_mm, candidates.back())) {
        candidates.pop_back();
        continue;
      }
      rows.push_back(touchRows(model, l.fit_squareness, candidates.back(), R + r) / sd_mm);
    }
    PoseDesignOptions o;
    o.poses = l.design_poses;
    o.hold_first = sphereHeldFirst(model);
    if (static_cast<int>(candidates.size()) < o.poses)
      throw std::invalid_argument(fmt::format("option poses = {}: only {} candidate poses of tilt_list x {} are allowed",
                                              o.poses, candidates.size(), l.turnListOption()));
    PoseDesign d = designPoses(rows, names, o);
    if (l.design_criterion == 'A') d = refineForContributors(machine, model, l, candidates, names, d.chosen, o.hold_first);
    std::sort(d.chosen.begin(), d.chosen.end());
    for (int k : d.chosen) {
      poses.push_back(candidates[static_cast<size_t>(k)]);
      const Pose& q = poses.back().pose.pose;
      l.pose_list.emplace_back(q.angle(tilt_axis), q.angle(l.turn_axis));
    }
    l.design_poses = 0;
  } else {
    for (const auto& [t, c] : l.poses()) poses.push_back(touchesAt(machine, l, tilt_axis, t, c));
  }

  if (l.backlash) {
    // There and back: each pose but the turning one is reached again with every moving axis
    // coming the other way. The return visits are named with an R.
    if (poses.size() < 2) throw std::invalid_argument("option backlash needs at least 2 poses to run there and back");
    for (size_t k = poses.size() - 1; k-- > 0;) {
      PoseTouches back = poses[k];
      back.pose.name += "R";
      for (auto& q : back.points) q.pose_name = back.pose.name;
      poses.push_back(back);
    }
  }

  ProbePlan plan;
  plan.cycle = "one_sphere";
  plan.machine = machine;
  plan.options = l.toOptions();
  plan.index_z_mm = index_z_mm;
  int id = 1;
  for (auto& p : poses) {
    plan.poses.push_back(p.pose);
    for (auto& q : p.points) {
      q.id = id++;
      plan.points.push_back(q);
    }
  }

  // The plan must see every parameter the sphere can show (core/identifiability.hpp): the tilt
  // axis needs two tilts and the C axis three angles, and some layouts lose more; with the
  // squareness fitted, the sphere's positions must span the shear too.
  // A backlash plan's lost-motion terms come from its order of touches.
  const std::vector<Eigen::Vector3d> directions = rotaryApproachDirections(plan, false);
  const SphereBacklashTerms terms =
      l.backlash ? appendBacklashParameters(machine, directions, &names) : SphereBacklashTerms{};
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(names.size()));
  Eigen::MatrixXd J(static_cast<Eigen::Index>(plan.points.size()), x0.size());
  for (size_t k = 0; k < plan.points.size(); ++k) {
    Eigen::RowVectorXd row;
    sphereTouchResidual(model, l.fit_squareness, terms, x0, plan.points[k].pose, directions[k],
                        plan.points[k].trigger_m_mm, R + r, &row);
    J.row(static_cast<Eigen::Index>(k)) = row;
  }
  const Identifiability id_ = identifiability(J, names, sphereHeldFirst(model));
  const int unseen = sphereUnseenByAnyPlan(model, l.fit_squareness);
  if (id_.rank < static_cast<int>(names.size()) - unseen) {
    std::string lost;
    for (const auto& c : id_.combinations) lost += (lost.empty() ? "" : "; ") + c.text;
    throw std::invalid_argument(fmt::format(
        "the {} poses leave {} directions of the fit unseen, beyond the {} no sphere shows: {}{}", poses.size(),
        static_cast<int>(names.size()) - id_.rank, unseen, lost,
        l.fit_squareness ? " (the linear axes' squareness is fitted: fit_squareness=0 drops it)" : ""));
  }
  finishTouchPlan(plan);
  return plan;
}

PlanRules spherePlanRules() {
  PlanRules r;
  r.spheres = 1;  // one sphere, at least 4 touches at every pose
  r.safe_height_over_artefact = false;  // the plan keeps the test piece out of reach sideways (plan.cpp)
  r.check_options = [](const ProbePlan& p) { (void)sphereLayoutOf(p); };
  return r;
}

}  // namespace rotacal
