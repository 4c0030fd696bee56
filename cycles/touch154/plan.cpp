#include "cycles/touch154/plan.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/units.hpp"
#include "cycles/probing.hpp"
#include "cycles/touch154/targets.hpp"

namespace rotacal {

Touch154Layout Touch154Layout::fromOptions(const CycleOptions& options) {
  Touch154Layout l;
  OptionTable("touch154")
      .list("top_offsets_mm", &l.top_offsets_mm)
      .on("top_ring", [&](const std::string& k, const std::string& v) { l.top_ring = parseNumber(k, v) != 0.0; })
      .list("side_offsets_mm", &l.side_offsets_mm)
      .number("side_depth_mm", &l.side_depth_mm)
      .read(options);
  if (l.side_depth_mm <= 0) throw std::invalid_argument("option side_depth_mm must be positive");
  // Seven poses, each touching up to four sides and the whole top grid: refuse before building.
  const double top = static_cast<double>(l.top_offsets_mm.size());
  requirePlanSize(fmt::format("options top_offsets_mm ({} values) and side_offsets_mm ({} values)",
                              l.top_offsets_mm.size(), l.side_offsets_mm.size()),
                  7.0 * (4.0 * static_cast<double>(l.side_offsets_mm.size()) + top * top), 7.0);
  return l;
}

CycleOptions Touch154Layout::toOptions() const {
  auto list = [](const std::vector<double>& v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + fmt::format("{:g}", v[i]);
    return s;
  };
  return {{"top_offsets_mm", list(top_offsets_mm)},
          {"top_ring", top_ring ? "1" : "0"},
          {"side_offsets_mm", list(side_offsets_mm)},
          {"side_depth_mm", fmt::format("{:g}", side_depth_mm)}};
}

namespace {

using touch154::Target;

std::vector<Target> targets(const SquareColumn& col, const Touch154Layout& l) {
  touch154::Targets t(col);
  t.addSides(l.side_depth_mm, l.side_offsets_mm);
  const double hx = col.size_mm.x() / 2, hy = col.size_mm.y() / 2;
  auto check_in = touch154::requireOnFace;
  const auto& g = l.top_offsets_mm;
  const double inner = g.size() >= 4 ? std::min(std::abs(g[g.size() / 2 - 1]), std::abs(g[g.size() / 2])) : 0.0;
  for (size_t row = 0; row < g.size(); ++row) {
    check_in(g[row], hy, "top");
    for (size_t i = 0; i < g.size(); ++i) {
      const size_t col_i = row % 2 == 0 ? i : g.size() - 1 - i;  // serpentine
      const double ox = g[col_i], oy = g[row];
      check_in(ox, hx, "top");
      if (l.top_ring && std::abs(ox) <= inner + 1e-9 && std::abs(oy) <= inner + 1e-9) continue;
      t.addTop(ox, oy);
    }
  }
  return t.list;
}

}  // namespace

namespace touch154 {

void requireOnFace(double off, double half, const char* what) {
  if (std::abs(off) >= half) throw std::invalid_argument(fmt::format("{} offset {:g} mm lies off the face", what, off));
}

void Targets::addSides(double depth, const std::vector<double>& offsets) {
  const Eigen::Vector3d c = col_.top_centre_w;
  const double hx = col_.size_mm.x() / 2, hy = col_.size_mm.y() / 2;
  const double z = c.z() - depth;
  for (double o : offsets) { requireOnFace(o, hy, "side"); list.push_back({k_++, Face::PosX, {c.x() + hx, c.y() + o, z}}); }
  for (double o : offsets) { requireOnFace(o, hx, "side"); list.push_back({k_++, Face::PosY, {c.x() - o, c.y() + hy, z}}); }
  for (double o : offsets) { requireOnFace(o, hy, "side"); list.push_back({k_++, Face::NegX, {c.x() - hx, c.y() - o, z}}); }
  for (double o : offsets) { requireOnFace(o, hx, "side"); list.push_back({k_++, Face::NegY, {c.x() + o, c.y() - hy, z}}); }
}

ProbePoint touchPoint(int id, const std::string& pose_name, const Pose& pose, const Eigen::Isometry3d& T,
                      const Target& t, double r) {
  const Eigen::Vector3d n_w = faceNormal_w(t.face);
  ProbePoint p;
  p.id = id;
  p.pose_name = pose_name;
  p.pose = pose;
  p.target = t.k;
  p.face = t.face;
  p.contact_w_mm = t.contact_w;
  p.normal_w = n_w;
  p.trigger_m_mm = T * (t.contact_w + r * n_w);
  p.approach_m = -(T.linear() * n_w);
  return p;
}

void Targets::addTop(double ox, double oy) {
  requireOnFace(ox, col_.size_mm.x() / 2, "top");
  requireOnFace(oy, col_.size_mm.y() / 2, "top");
  const Eigen::Vector3d& c = col_.top_centre_w;
  list.push_back({k_++, Face::Top, {c.x() + ox, c.y() + oy, c.z()}});
}

}  // namespace touch154

ProbePlan makeTouch154Plan(const MachineModel& machine, const CycleOptions& options) {
  if (machine.kinematics != Kinematics::TableAC)
    throw std::invalid_argument("cycle touch154 needs an A/C tilting table (kinematics table_ac)");
  if (!machine.artefact) throw std::invalid_argument("cycle touch154 needs a square_column artefact in the machine file");
  const Touch154Layout layout = Touch154Layout::fromOptions(options);
  const SquareColumn& col = *machine.artefact;
  const double r = machine.probe.ball_radius_mm();

  ProbePlan plan;
  plan.cycle = "touch154";
  plan.machine = machine;
  plan.options = layout.toOptions();
  // 000 Sec. 4.2: (I)-(IV) A = 0, C = 0..270; (V)-(VII) A = -90, C = 90..270.
  const std::vector<std::pair<std::string, Pose>> poses = {
      {"I", {0, 0, 0}},    {"II", {0, 0, 90}},   {"III", {0, 0, 180}}, {"IV", {0, 0, 270}},
      {"V", {-90, 0, 90}}, {"VI", {-90, 0, 180}}, {"VII", {-90, 0, 270}}};

  double sweep = machine.table_diameter_mm / 2;
  for (const auto& corner : col.corners_w()) sweep = std::max(sweep, corner.norm());
  plan.index_z_mm = sweep + r + machine.clearance_mm;

  const auto tg = targets(col, layout);
  int id = 1;
  for (const auto& [name, pose] : poses) {
    const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
    double top_z = -1e300;
    for (const auto& corner : col.corners_w()) top_z = std::max(top_z, (T * corner).z());
    plan.poses.push_back({name, pose, top_z + r + machine.clearance_mm});
    for (const auto& t : tg) {
      const Eigen::Vector3d n_w = faceNormal_w(t.face);
      const Eigen::Vector3d n_m = T.linear() * n_w;
      const Eigen::Vector3d contact_m = T * t.contact_w;
      if (n_m.z() < -0.05) continue;  // faces pointing down: a vertical stylus cannot reach them
      const bool from_above = n_m.z() > 0.95;
      const double depth = top_z - contact_m.z();
      if (!from_above && depth > machine.probe.stylus_length_mm - machine.probe.body_clearance_mm) continue;
      plan.points.push_back(touch154::touchPoint(id++, name, pose, T, t, r));
    }
  }
  finishTouchPlan(plan);
  return plan;
}

PlanRules touch154PlanRules() {
  PlanRules r;
  // The layout options a touch154 plan records (a designed plan records its design instead).
  r.check_options = [](const ProbePlan& p) {
    if (p.cycle == "touch154") (void)Touch154Layout::fromOptions(p.options);
  };
  return r;
}

}  // namespace rotacal
