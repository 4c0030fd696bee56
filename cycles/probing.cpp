#include "cycles/probing.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "core/contributor_draw.hpp"
#include "core/errors.hpp"
#include "core/report_envelope.hpp"
#include "core/simulation.hpp"

namespace rotacal {

Face faceOfNormal(const Eigen::Vector3d& n_m) {
  if (n_m.z() > 0.5) return Face::Top;
  if (std::abs(n_m.x()) > std::abs(n_m.y())) return n_m.x() > 0 ? Face::PosX : Face::NegX;
  return n_m.y() > 0 ? Face::PosY : Face::NegY;
}

void finishTouchPlan(ProbePlan& plan) {
  const auto bad = strokeViolations(plan);
  if (!bad.empty()) throw std::invalid_argument("plan does not fit the machine: " + bad.front());
  estimateTimes(plan);
}

std::vector<MeasurementRun> readProbeRuns(const ProbePlan& plan, const std::vector<InputFile>& results,
                                          const DialectIO& dialect) {
  std::vector<MeasurementRun> runs;
  for (const auto& f : results) runs.push_back(dialect.read_results(f.text, f.path, plan));
  return runs;
}

Simulated simulateProbing(const SimulateRequest& r) {
  const ProbePlan& plan = *r.plan;
  const JsonDoc doc = parseJsonText(r.truth.text, r.truth.path);
  Truth truth = truthFromJson(doc, plan.machine);
  Json truth_json = doc.value;
  std::string drawn;
  if (r.contributors) {
    const DrawnMachine m = drawMachine(plan, *r.contributors, r.machine_seed, &truth);
    truth_json["drawn"] = m.record;
    drawn = fmt::format(", a machine drawn from {} (machine seed {})",
                        r.contributors->file.empty() ? std::string("the machine's contributors") : r.contributors->file,
                        r.machine_seed);
  }
  if (r.noise_um) truth.noise_um = *r.noise_um;
  if (r.start_s) truth.start_time_s = *r.start_s;
  truth_json["noise_um"] = truth.noise_um;
  const MeasurementRun run = onTruthFile(r.truth, [&] { return simulate(plan, truth, {r.seed}); });
  Simulated s{r.dialect->write_results(plan, run),
              fmt::format("simulated {} triggers (noise {:.3f} um, seed {}{}) as {} results", run.points.size(),
                          truth.noise_um, r.seed, drawn, r.dialect->name),
              truth_json};
  if (locationErrorsAreConstant(truth)) s.injected["location_errors"] = locationErrorValues(truth.errors);
  // The mean pretravel is the truth's own only when no direction adds its part.
  if (!truth.pretravel_by_direction_um) s.injected["mean_pretravel"] = truth.pretravel_um;
  return s;
}

std::string sphereReachRefusal(const MachineModel& machine, const Eigen::Isometry3d& T, const Eigen::Vector3d& c_m,
                               double R, double reach) {
  if (!machine.artefact) return "";
  const double r = machine.probe.ball_radius_mm();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (const auto& corner : machine.artefact->corners_w()) {
    const Eigen::Vector3d q = T * corner;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double dx = std::max({lo.x() - c_m.x(), 0.0, c_m.x() - hi.x()});
  const double dy = std::max({lo.y() - c_m.y(), 0.0, c_m.y() - hi.y()});
  if (std::hypot(dx, dy) < reach + r + machine.clearance_mm && hi.z() > c_m.z() - R - r - machine.clearance_mm)
    return fmt::format("the test piece stands within {:.1f} mm of the probe's way to the sphere", reach + r + machine.clearance_mm);
  return "";
}

double tableSweepRadius(const MachineModel& machine, const Eigen::Vector3d& c_w, double R) {
  // A table that only turns in C keeps every height: the highest thing it carries.
  if (hasSpindleHead(machine.kinematics)) {
    double top = c_w.z() + R;
    if (machine.artefact)
      for (const auto& corner : machine.artefact->corners_w()) top = std::max(top, corner.z());
    return top;
  }
  double sweep = std::max(machine.table_diameter_mm / 2, c_w.norm() + R);
  if (machine.artefact)
    for (const auto& corner : machine.artefact->corners_w()) sweep = std::max(sweep, corner.norm());
  return sweep;
}

std::vector<PlannedTrigger> triggersInPlanOrder(const ProbePlan& plan, const std::vector<MeasurementRun>& runs) {
  std::vector<PlannedTrigger> out;
  const double cycle_s = plan.points.empty() ? 0.0 : plan.points.back().t_s;
  for (size_t k = 0; k < runs.size(); ++k) {
    std::map<int, const TriggerPoint*> by_id;
    for (const auto& t : runs[k].points) by_id[t.point_id] = &t;
    for (size_t i = 0; i < plan.points.size(); ++i) {
      const ProbePoint& p = plan.points[i];
      const auto it = by_id.find(p.id);
      if (it == by_id.end()) throw InputError(runs[k].source, 0, fmt::format("no trigger for plan point {}", p.id));
      const double t = std::isfinite(it->second->t_s) ? it->second->t_s : static_cast<double>(k) * cycle_s + p.t_s;
      out.push_back({i, static_cast<int>(k), it->second, t});
    }
  }
  return out;
}

CycleDocuments judgedFitDocuments(std::string_view cycle, const DiagnoseRequest& r,
                                  JudgedFit (*judged)(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                                      const JudgeOptions& options)) {
  const ProbePlan& plan = *r.plan;
  JudgeOptions o;
  o.alpha = r.alpha;
  const JudgedFit d = judged(plan, readProbeRuns(plan, r.results, *r.dialect), o);
  return documents(judgedDiagnosisJson(std::string(cycle), plan, d), judgeText(d.summary, d.separate_with));
}

}  // namespace rotacal
