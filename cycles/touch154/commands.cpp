#include "cycles/touch154/commands.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/limits.hpp"
#include "core/units.hpp"
#include "cycles/touch154/design.hpp"
#include "cycles/touch154/uncertainty.hpp"

namespace rotacal {
namespace {

std::vector<UncertaintyMethod> parseMethods(const std::string& list) {
  std::vector<UncertaintyMethod> out;
  if (list.empty()) return out;
  try {
    size_t start = 0;
    while (start <= list.size()) {
      const size_t comma = list.find(',', start);
      out.push_back(uncertaintyMethodFromName(list.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  } catch (const std::invalid_argument& e) {
    throw OptionError("--methods", e.what());
  }
  return out;
}

double toReport(ParamKind k, double v) { return k == ParamKind::Length ? mmToUm(v) : radToMdeg(v); }

/// One row of the comparison: a plan's size, time and Monte Carlo uncertainty.
struct PlanRow {
  std::string name;
  int points = 0, poses = 0;
  double minutes = 0.0;
  ErrorVector u = ErrorVector::Zero();  // least_squares, MC
  ErrorVector u_plain = ErrorVector::Zero();  // lsq_per_point, MC
  double worst_ratio = 0.0;             // max u / reference
};

PlanRow evaluate(const std::string& name, const ProbePlan& plan, const ContributorSet& cs, int runs, std::uint64_t seed) {
  UncertaintyOptions o;
  o.runs = runs;
  o.seed = seed;
  o.combined_only = true;
  o.truth.kinematics = plan.machine.kinematics;
  o.methods = {UncertaintyMethod::LeastSquares, UncertaintyMethod::LsqPerPoint};
  const UncertaintySummary s = runUncertainty(plan, cs, o);
  PlanRow r;
  r.name = name;
  r.points = s.points;
  r.poses = s.poses;
  r.minutes = s.machine_time_s / 60.0;
  r.u.setConstant(NAN);  // stays NaN when least_squares does not apply (printed "-")
  for (const auto& m : s.methods) (m.method == UncertaintyMethod::LeastSquares ? r.u : r.u_plain) = m.combined.u;
  const auto& params = locationParameters(plan.machine.kinematics);
  if (cs.reference)
    for (size_t i = 0; i < params.size(); ++i) {
      const auto it = cs.reference->combined.find(std::string(params[i].name));
      if (it != cs.reference->combined.end() && it->second > 0 && std::isfinite(r.u[static_cast<long>(i)]))
        r.worst_ratio = std::max(r.worst_ratio, toReport(params[i].kind, r.u[static_cast<long>(i)]) / it->second);
    }
  return r;
}

Json rowJson(const PlanRow& r) {
  const auto& params = locationParameters(Kinematics::TableAC);
  Json u = Json::object(), p = Json::object();
  for (size_t i = 0; i < params.size(); ++i) {
    const std::string unit(reportUnit(params[i].kind));
    const double v = r.u[static_cast<long>(i)];
    u[std::string(params[i].name)] = {{"u", std::isfinite(v) ? Json(toReport(params[i].kind, v)) : Json()}, {"unit", unit}};
    p[std::string(params[i].name)] = {{"u", toReport(params[i].kind, r.u_plain[static_cast<long>(i)])}, {"unit", unit}};
  }
  Json j = {{"plan", r.name}, {"points", r.points}, {"poses", r.poses}, {"machine_time_min", r.minutes},
            {"least_squares", u}, {"lsq_per_point", p}};
  if (r.worst_ratio > 0) j["worst_u_over_reference"] = r.worst_ratio;
  return j;
}

std::string rowsText(const std::vector<PlanRow>& rows, const ContributorSet& cs, int runs) {
  const auto& params = locationParameters(Kinematics::TableAC);
  std::string t = fmt::format("\nleast_squares uncertainty (k = 1) by the Monte Carlo ({} runs, linearised):\n", runs);
  t += fmt::format("{:<22}{:>7}{:>6}{:>7}", "plan", "points", "poses", "min");
  for (const auto& p : params) t += fmt::format("{:>7}", p.name);
  t += fmt::format("{:>10}{:>12}\n", "max u/ref", "u x sqrt(t)");
  t += fmt::format("{:<22}{:>7}{:>6}{:>7}", "", "", "", "");
  for (const auto& p : params) t += fmt::format("{:>7}", reportUnit(p.kind));
  t += fmt::format("{:>10}{:>12}\n", "", "(max ratio)");
  for (const auto& r : rows) {
    t += fmt::format("{:<22}{:>7}{:>6}{:>7.1f}", r.name, r.points, r.poses, r.minutes);
    for (size_t i = 0; i < params.size(); ++i) {
      const double v = r.u[static_cast<long>(i)];
      t += std::isfinite(v) ? fmt::format("{:>7.2f}", toReport(params[i].kind, v)) : fmt::format("{:>7}", "-");
    }
    if (r.worst_ratio > 0) t += fmt::format("{:>10.2f}{:>12.2f}", r.worst_ratio, r.worst_ratio * std::sqrt(r.minutes));
    t += "\n";
  }
  if (cs.reference) {
    t += fmt::format("{:<22}{:>7}{:>6}{:>7}", "reference", 154, 7, "~20");
    for (const auto& p : params) {
      const auto it = cs.reference->combined.find(std::string(p.name));
      t += it == cs.reference->combined.end() ? fmt::format("{:>7}", "-") : fmt::format("{:>7.2f}", it->second);
    }
    t += fmt::format("   ({})\n", cs.reference->source);
    t += "max u/ref: the worst ratio to the reference (<= 1: the plan reaches it); u x sqrt(t): that ratio times\n"
         "the square root of the machine minutes, lower is more accuracy per minute.\n";
  }
  return t;
}

}  // namespace

CycleDocuments touch154Uncertainty(const UncertaintyRequest& r) {
  UncertaintyOptions o;
  o.runs = r.runs;
  o.seed = r.seed;
  o.combined_only = r.combined_only;
  o.exact = r.exact;
  o.threads = r.threads;
  o.methods = parseMethods(r.methods);
  std::string why;
  if (!o.validate(&why)) throw OptionError("--runs/--threads", why);
  const ProbePlan& plan = *r.plan;
  o.truth.kinematics = plan.machine.kinematics;
  if (r.truth) o.truth = *r.truth;
  o.progress = r.progress;
  const UncertaintySummary s = runUncertainty(plan, *r.contributors, o);
  CycleDocuments out;
  out.text = uncertaintyText(s, *r.contributors) +
             fmt::format("\ntime: {:.3f} s to linearise the chain, {:.3f} s for {} runs on {} thread(s)\n",
                         s.setup_seconds, s.run_seconds, s.runs, s.threads);
  out.doc = uncertaintyToJson(s, *r.contributors, r.plan_file);
  if (s.failed > 0) out.warnings.push_back(fmt::format("{} least-squares identifications did not converge", s.failed));
  return out;
}

DesignedPlan touch154Design(const DesignRequest& r, const ProbePlan* full_plan) {
  DesignOptions o;
  o.points = r.points;
  if (r.criterion == "A" || r.criterion == "a") o.criterion = DesignOptions::Criterion::A;
  else if (r.criterion == "D" || r.criterion == "d") o.criterion = DesignOptions::Criterion::D;
  else throw OptionError("--criterion", "expected A or D, got '" + r.criterion + "'");
  if (!r.a_deg.empty()) o.a_deg = r.a_deg;
  if (!r.c_deg.empty()) o.c_deg = r.c_deg;
  o.exchange_passes = r.exchange_passes;
  if (r.exchange_passes > kMaxExchangePasses)
    throw OptionError("--exchange-passes", fmt::format("at most {} (got {})", kMaxExchangePasses, r.exchange_passes));
  std::string why;
  if (!o.validate(&why)) throw OptionError("--points", why);
  if (r.runs < 2 || r.runs > kMaxMonteCarloRuns)
    throw OptionError("--runs", fmt::format("must be from 2 to {} (got {})", kMaxMonteCarloRuns, r.runs));
  // The budgets of --sweep, checked before the first design runs.
  std::vector<int> sweep_budgets;
  for (double b : r.sweep) {
    if (b != std::floor(b) || b < 0 || b > kMaxPlanPoints)
      throw OptionError("--sweep", fmt::format("budgets must be whole numbers up to {} (got {:g})", kMaxPlanPoints, b));
    DesignOptions ob = o;
    ob.points = static_cast<int>(b);
    if (!ob.validate(&why)) throw OptionError("--sweep", why);
    sweep_budgets.push_back(ob.points);
  }
  const MachineModel& machine = *r.machine;
  const ContributorSet& cs = *r.contributors;
  const auto t0 = std::chrono::steady_clock::now();
  o.progress = r.progress;
  DesignResult d = designPlan(machine, cs, o);
  if (r.progress) r.progress(o.exchange_passes, o.exchange_passes);  // ends the line
  const double design_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<PlanRow> rows;
  if (full_plan) rows.push_back(evaluate(fmt::format("{} (full plan)", full_plan->cycle), *full_plan, cs, r.runs, r.seed));
  const std::string crit = o.criterion == DesignOptions::Criterion::A ? "A" : "D";
  rows.push_back(evaluate(fmt::format("designed ({}, {})", crit, o.points), d.plan, cs, r.runs, r.seed));
  std::vector<PlanRow> sweep_rows;
  for (int b : sweep_budgets) {
    DesignOptions ob = o;
    ob.points = b;
    sweep_rows.push_back(
        evaluate(fmt::format("designed ({}, {})", crit, ob.points), designPlan(machine, cs, ob).plan, cs, r.runs, r.seed));
  }
  DesignedPlan out;
  std::string t = fmt::format("designed plan: {} touches in {} poses, {:.1f} min of machine time ({}-optimal over {} "
                              "candidate touches, {} exchanges, {:.1f} s) -> {}\n",
                              d.plan.points.size(), d.plan.poses.size(), d.plan.points.back().t_s / 60.0, crit,
                              d.candidates, d.exchanges, design_s, r.plan_file);
  for (const auto& p : d.plan.poses) {
    int n = 0;
    for (const auto& q : d.plan.points) n += q.pose_name == p.name;
    t += fmt::format("  pose {:<10} A = {:>6.1f}  C = {:>6.1f}  {:>3} touches\n", p.name, p.pose.A, p.pose.C, n);
  }
  for (const auto& n : d.notes) t += "  note: " + n + "\n";
  std::vector<PlanRow> all = rows;
  all.insert(all.end(), sweep_rows.begin(), sweep_rows.end());
  t += rowsText(all, cs, r.runs);
  Json j;
  j["format"] = "rotacal-design/1";
  j["plan_file"] = r.plan_file;
  j["criterion"] = crit;
  j["budget"] = o.points;
  j["candidates"] = d.candidates;
  j["exchanges"] = d.exchanges;
  j["notes"] = d.notes;
  Json pred = Json::object();
  const auto& params = locationParameters(machine.kinematics);
  for (size_t i = 0; i < params.size(); ++i)
    pred[std::string(params[i].name)] = {{"u", toReport(params[i].kind, d.predicted_u[static_cast<long>(i)])},
                                         {"unit", std::string(reportUnit(params[i].kind))}};
  j["predicted_least_squares"] = pred;
  j["runs"] = r.runs;
  j["seed"] = r.seed;
  Json cmp = Json::array();
  for (const auto& row : rows) cmp.push_back(rowJson(row));
  j["comparison"] = cmp;
  Json sw = Json::array();
  for (const auto& row : sweep_rows) sw.push_back(rowJson(row));
  if (!sweep_rows.empty()) j["sweep"] = sw;
  out.plan = std::move(d.plan);
  out.doc = std::move(j);
  out.text = std::move(t);
  return out;
}

}  // namespace rotacal
