// The uncertainty commands: `uncertainty` (contract.md: the Monte Carlo of 000 Sec. 5) and
// `design` (a plan for a probe budget that minimises the least-squares uncertainty, compared with
// the full plan of the cycle it designs for, by the same Monte Carlo).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cycles/cycle.hpp"
#include "cli/command.hpp"
#include "cli/output.hpp"
#include "cli/progress.hpp"
#include "core/contributors.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/limits.hpp"
#include "core/machine.hpp"
#include "core/plan_design.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "core/uncertainty.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

std::vector<UncertaintyMethod> parseMethods(const std::string& list) {
  std::vector<UncertaintyMethod> out;
  if (list.empty()) return out;
  try {
    size_t start = 0;
    while (start <= list.size()) {
      const size_t comma = list.find(',', start);
      const std::string name = list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      out.push_back(uncertaintyMethodFromName(name));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--methods", e.what());
  }
  return out;
}

int cmdUncertainty(const Common& c, const std::string& plan_file, const std::string& contrib_file, int runs,
                   std::uint64_t seed, bool combined_only, bool exact, int threads, const std::string& methods,
                   const std::string& truth_file, const std::string& json_out, const std::string& text_out) {
  UncertaintyOptions o;
  o.runs = runs;
  o.seed = seed;
  o.combined_only = combined_only;
  o.exact = exact;
  o.threads = threads;
  o.methods = parseMethods(methods);
  std::string why;
  if (!o.validate(&why)) throw CLI::ValidationError("--runs/--threads", why);
  std::vector<std::string> inputs = {plan_file, contrib_file};
  if (!truth_file.empty()) inputs.push_back(truth_file);
  checkOutputs({{"--json", json_out}, {"--text", text_out}}, inputs);
  const ProbePlan plan = loadPlan(plan_file);
  const ContributorSet cs = loadContributors(contrib_file);
  o.truth.kinematics = plan.machine.kinematics;
  if (!truth_file.empty()) o.truth = loadTruth(truth_file, plan.machine.kinematics).errors;
  o.progress = progressIndicator(c, "rotacal uncertainty");
  UncertaintySummary s;
  try {
    s = runUncertainty(plan, cs, o);
  } catch (const std::invalid_argument& e) {
    failFile(plan_file, e.what());
  } catch (const std::runtime_error& e) {  // a drawn error pushed a trigger out of the search range
    failFile(contrib_file, e.what());
  }
  const std::string text = uncertaintyText(s, cs) +
                           fmt::format("\ntime: {:.3f} s to linearise the chain, {:.3f} s for {} runs on {} thread(s)\n",
                                       s.setup_seconds, s.run_seconds, s.runs, s.threads);
  OutputSet outputs(inputs);
  outputs.add("--json", json_out, uncertaintyToJson(s, cs, plan_file).dump(1) + "\n");
  outputs.add("--text", text_out, text);
  outputs.commit();
  sayUnlessPiped(c, text, json_out);
  if (s.failed > 0) std::fprintf(stderr, "rotacal: warning: %d least-squares identifications did not converge\n", s.failed);
  return 0;
}

std::vector<double> numberList(const std::string& option, const std::string& text) {
  try {
    return parseNumberList(option, text);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError(option, e.what());
  }
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

int cmdDesign(const Common& c, const std::string& machine_file, const std::string& contrib_file, int points,
              const std::string& criterion, const std::string& a_list, const std::string& c_list, int passes,
              const std::string& sweep, int runs, std::uint64_t seed, const std::string& out, const std::string& json_out) {
  DesignOptions o;
  o.points = points;
  if (criterion == "A" || criterion == "a") o.criterion = DesignOptions::Criterion::A;
  else if (criterion == "D" || criterion == "d") o.criterion = DesignOptions::Criterion::D;
  else throw CLI::ValidationError("--criterion", "expected A or D, got '" + criterion + "'");
  if (!a_list.empty()) o.a_deg = numberList("--a-deg", a_list);
  if (!c_list.empty()) o.c_deg = numberList("--c-deg", c_list);
  o.exchange_passes = passes;
  if (passes > kMaxExchangePasses)
    throw CLI::ValidationError("--exchange-passes", fmt::format("at most {} (got {})", kMaxExchangePasses, passes));
  std::string why;
  if (!o.validate(&why)) throw CLI::ValidationError("--points", why);
  if (runs < 2 || runs > kMaxMonteCarloRuns)
    throw CLI::ValidationError("--runs", fmt::format("must be from 2 to {} (got {})", kMaxMonteCarloRuns, runs));
  checkOutputs({{"-o", out}, {"--json", json_out}}, {machine_file, contrib_file});
  // The budgets of --sweep, checked before the first design runs.
  std::vector<int> sweep_budgets;
  if (!sweep.empty())
    for (double b : numberList("--sweep", sweep)) {
      if (b != std::floor(b) || b < 0 || b > kMaxPlanPoints)
        throw CLI::ValidationError("--sweep",
                                   fmt::format("budgets must be whole numbers up to {} (got {:g})", kMaxPlanPoints, b));
      DesignOptions ob = o;
      ob.points = static_cast<int>(b);
      if (!ob.validate(&why)) throw CLI::ValidationError("--sweep", why);
      sweep_budgets.push_back(ob.points);
    }
  const MachineModel machine = loadMachine(machine_file);
  const ContributorSet cs = loadContributors(contrib_file);
  const auto t0 = std::chrono::steady_clock::now();
  DesignResult d;
  const auto progress = progressIndicator(c, "rotacal design", "exchange steps");
  o.progress = progress;
  try {
    d = designPlan(machine, cs, o);
    if (progress) progress(o.exchange_passes, o.exchange_passes);  // ends the line
  } catch (const std::invalid_argument& e) {
    failFile(machine_file, e.what());
  }
  const double design_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<PlanRow> rows;
  try {
    // The designed plan is analyzed by a cycle of the registry: compare with that cycle's full plan.
    const Cycle& full = cycleOfPlan(d.plan);
    rows.push_back(evaluate(fmt::format("{} (full plan)", full.name()), full.plan(machine, {}), cs, runs, seed));
  } catch (const std::invalid_argument&) {
    // no full plan on this machine: compare with the design alone
  }
  const std::string crit = o.criterion == DesignOptions::Criterion::A ? "A" : "D";
  rows.push_back(evaluate(fmt::format("designed ({}, {})", crit, o.points), d.plan, cs, runs, seed));
  std::vector<PlanRow> sweep_rows;
  for (int b : sweep_budgets) {
    DesignOptions ob = o;
    ob.points = b;
    try {
      sweep_rows.push_back(evaluate(fmt::format("designed ({}, {})", crit, ob.points), designPlan(machine, cs, ob).plan,
                                    cs, runs, seed));
    } catch (const std::invalid_argument& e) {
      failFile(machine_file, e.what());
    }
  }
  OutputSet outputs({machine_file, contrib_file});
  outputs.add("-o", out, planToJson(d.plan).dump(1) + "\n");

  std::string t = fmt::format("designed plan: {} touches in {} poses, {:.1f} min of machine time ({}-optimal over {} "
                              "candidate touches, {} exchanges, {:.1f} s) -> {}\n",
                              d.plan.points.size(), d.plan.poses.size(), d.plan.points.back().t_s / 60.0, crit,
                              d.candidates, d.exchanges, design_s, out);
  for (const auto& p : d.plan.poses) {
    int n = 0;
    for (const auto& q : d.plan.points) n += q.pose_name == p.name;
    t += fmt::format("  pose {:<10} A = {:>6.1f}  C = {:>6.1f}  {:>3} touches\n", p.name, p.pose.A, p.pose.C, n);
  }
  for (const auto& n : d.notes) t += "  note: " + n + "\n";
  std::vector<PlanRow> all = rows;
  all.insert(all.end(), sweep_rows.begin(), sweep_rows.end());
  t += rowsText(all, cs, runs);
  if (!json_out.empty()) {
    Json j;
    j["format"] = "rotacal-design/1";
    j["plan_file"] = out;
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
    j["runs"] = runs;
    j["seed"] = seed;
    Json cmp = Json::array();
    for (const auto& r : rows) cmp.push_back(rowJson(r));
    j["comparison"] = cmp;
    Json sw = Json::array();
    for (const auto& r : sweep_rows) sw.push_back(rowJson(r));
    if (!sweep_rows.empty()) j["sweep"] = sw;
    outputs.add("--json", json_out, j.dump(1) + "\n");
  }
  outputs.commit();
  sayUnlessPiped(c, t, json_out);
  return 0;
}

}  // namespace

std::vector<Command> uncertaintyCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string plan_file, contrib_file, json_out, text_out, methods, truth_file, machine_file, out, criterion = "A",
        a_list, c_list, sweep;
    int runs = 1000, threads = 0, points = 77, passes = 2, design_runs = 1000;
    std::uint64_t seed = 1;
    bool combined_only = false, exact = false;
  };
  auto a = std::make_shared<Args>();
  std::vector<Command> cmds;

  auto* unc = app.add_subcommand("uncertainty", "Monte Carlo of the calibration chain (000 Sec. 5): u (k = 1) per "
                                                "location error, per contributor and combined");
  unc->add_option("--plan", a->plan_file, "PLAN.json")->required();
  unc->add_option("--contributors", a->contrib_file, "CONTRIB.json (e.g. examples/contributors/table5.json)")->required();
  unc->add_option("--runs", a->runs, "Monte Carlo runs (000: 1000)")->required();
  unc->add_option("--seed", a->seed, "random seed (results do not depend on the thread count)");
  unc->add_flag("--combined-only", a->combined_only, "skip the per-contributor table");
  unc->add_option("--json", a->json_out, "OUT.json (rotacal-uncertainty/1; - for stdout)")->required();
  unc->add_flag("--exact", a->exact,
                "exact simulation of every point and the estimators themselves in every run (slow; default: the "
                "chain linearised, checked against this in the tests)");
  unc->add_option("--threads", a->threads, "worker threads (default: all cores)");
  unc->add_option("--methods", a->methods,
                  "estimators, comma-separated: closed_form, closed_form_pooled, least_squares, lsq_per_point "
                  "(default: all that apply)");
  unc->add_option("--truth", a->truth_file, "TRUTH.json: location errors of the simulated machine (default: none)");
  unc->add_option("--text", a->text_out, "the tables, also printed on stdout");
  cmds.push_back({unc, [a, &common] {
                    return cmdUncertainty(common, a->plan_file, a->contrib_file, a->runs, a->seed, a->combined_only,
                                          a->exact, a->threads, a->methods, a->truth_file, a->json_out, a->text_out);
                  }});

  auto* des = app.add_subcommand("design", "choose poses and points for a probe budget (A- or D-optimal for the "
                                           "least-squares uncertainty) and compare with the full plan by Monte Carlo");
  des->add_option("--machine", a->machine_file, "MACHINE.json (A/C table with a square_column artefact)")->required();
  des->add_option("--contributors", a->contrib_file, "CONTRIB.json: the uncertainty model the design minimises")->required();
  des->add_option("--points", a->points, "probe budget: number of touches (default 77)");
  des->add_option("--criterion", a->criterion, "A (sum of (u / reference)^2, default) or D (log det)");
  des->add_option("--a-deg", a->a_list, "candidate A angles, e.g. 0,-45,-90 (default 0,-90)");
  des->add_option("--c-deg", a->c_list, "candidate C angles (default 0,90,180,270)");
  des->add_option("--exchange-passes", a->passes, "exchange passes after the greedy selection (default 2)");
  des->add_option("--sweep", a->sweep, "also design and evaluate these budgets, e.g. 28,42,56,77,105");
  des->add_option("--runs", a->design_runs, "Monte Carlo runs of the comparison (default 1000)");
  des->add_option("--seed", a->seed, "random seed of the comparison");
  des->add_option("-o,--output", a->out, "PLAN.json of the designed cycle")->required();
  des->add_option("--json", a->json_out, "DESIGN.json: the design and the comparison (- for stdout)");
  cmds.push_back({des, [a, &common] {
                    return cmdDesign(common, a->machine_file, a->contrib_file, a->points, a->criterion, a->a_list,
                                     a->c_list, a->passes, a->sweep, a->design_runs, a->seed, a->out, a->json_out);
                  }});
  return cmds;
}

}  // namespace rotacal
