#include "cycles/touch154/point_deviations.hpp"

#include <cmath>
#include <map>
#include <utility>

#include "core/artefact.hpp"

namespace rotacal {

namespace {
double round4(double v) { return std::round(v * 1e4) / 1e4; }
Json vec3(const Eigen::Vector3d& v, double scale) {
  return Json::array({std::round(v.x() * scale) / scale, std::round(v.y() * scale) / scale,
                      std::round(v.z() * scale) / scale});
}
}  // namespace

Json pointDeviationsJson(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                         const IdentificationResult& fit) {
  std::map<std::pair<int, int>, double> residual;  // (run, point) -> um
  for (const auto& r : fit.residuals) residual[{r.run, r.point_id}] = r.residual_um;
  const std::string first_pose = plan.points.empty() ? std::string() : plan.points.front().pose_name;
  const double r_ball_mm = 0.5 * plan.machine.probe.ball_diameter_mm;

  Json out = Json::array();
  for (size_t run = 0; run < runs.size(); ++run) {
    // Deviation of each target at the first pose (000 Eq. (21): p(1,1,k)).
    std::map<int, double> dev_first;
    std::vector<std::pair<const ProbePoint*, const TriggerPoint*>> rows;
    for (const auto& t : runs[run].points) {
      const ProbePoint* p = plan.findPoint(t.point_id);
      if (p == nullptr) continue;
      rows.emplace_back(p, &t);
    }
    auto devOf = [](const ProbePoint& p, const TriggerPoint& t) {
      // The outward normal in the machine frame is against the probing move.
      return (t.position_m_mm - p.trigger_m_mm).dot(-p.approach_m) * 1000.0;
    };
    for (const auto& [p, t] : rows)
      if (p->pose_name == first_pose) dev_first[p->target] = devOf(*p, *t);
    for (const auto& [p, t] : rows) {
      const double dev = devOf(*p, *t);
      Json e;
      e["run"] = static_cast<int>(run) + 1;
      e["point"] = p->id;
      e["pose_name"] = p->pose_name;
      e["pose"] = {{"A", p->pose.A}, {"B", p->pose.B}, {"C", p->pose.C}};
      e["face"] = p->sphere ? std::string("sphere") : std::string(faceName(p->face));
      e["target"] = p->target;
      e["t_s"] = std::isfinite(t->t_s) ? Json(t->t_s) : Json(nullptr);
      e["contact_m_mm"] = vec3(p->trigger_m_mm + r_ball_mm * p->approach_m, 1e4);
      e["normal_m"] = vec3(-p->approach_m, 1e6);
      e["dev_um"] = round4(dev);
      const auto f = dev_first.find(p->target);
      e["rel_dev_um"] = f == dev_first.end() ? Json(nullptr) : Json(round4(dev - f->second));
      const auto r = residual.find({static_cast<int>(run), p->id});
      e["residual_um"] = r == residual.end() ? Json(nullptr) : Json(round4(r->second));
      out.push_back(std::move(e));
    }
  }
  return out;
}

}  // namespace rotacal
