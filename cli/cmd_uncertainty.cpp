// The uncertainty commands: `uncertainty` (contract.md: the Monte Carlo of 000 Sec. 5) and
// `design` (a plan for a probe budget that minimises the least-squares uncertainty, compared with
// the full plan of the cycle it designs for, by the same Monte Carlo).
#include <unistd.h>

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
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"

namespace rotacal {
namespace {

std::vector<double> numberList(const std::string& option, const std::string& text) {
  try {
    return parseNumberList(option, text);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError(option, e.what());
  }
}

int cmdUncertainty(const Common& c, const std::string& plan_file, const std::string& contrib_file, int runs,
                   std::uint64_t seed, bool combined_only, bool exact, int threads, const std::string& methods,
                   const std::string& truth_file, const std::string& json_out, const std::string& text_out) {
  std::vector<std::string> inputs = {plan_file, contrib_file};
  if (!truth_file.empty()) inputs.push_back(truth_file);
  checkOutputs({{"--json", json_out}, {"--text", text_out}}, inputs);
  const ProbePlan plan = loadCyclePlan(plan_file);
  const ContributorSet cs = loadContributors(contrib_file);
  UncertaintyRequest r;
  r.plan = &plan;
  r.plan_file = plan_file;
  r.contributors = &cs;
  r.runs = runs;
  r.seed = seed;
  r.combined_only = combined_only;
  r.exact = exact;
  r.threads = threads;
  r.methods = methods;
  if (!truth_file.empty()) r.truth = loadTruth(truth_file, plan.machine.kinematics).errors;
  r.progress = progressIndicator(c, "rotacal uncertainty");
  CycleDocuments d;
  try {
    const Cycle& cycle = cycleOfPlan(plan);
    d = cycle.uncertainty(r);
  } catch (const OptionError& e) {
    throw CLI::ValidationError(e.option, e.what());
  } catch (const std::invalid_argument& e) {
    failFile(plan_file, e.what());
  } catch (const std::runtime_error& e) {  // a drawn error pushed a trigger out of the search range
    failFile(contrib_file, e.what());
  }
  OutputSet outputs(inputs);
  outputs.add("--json", json_out, d.doc.dump(1) + "\n");
  outputs.add("--text", text_out, d.text);
  outputs.commit();
  sayUnlessPiped(c, d.text, json_out);
  for (const auto& w : d.warnings) std::fprintf(stderr, "rotacal: warning: %s\n", w.c_str());
  return 0;
}

/// The cycle `design` works for: the one named, else the only one that designs plans.
const Cycle& designingCycle(const std::string& name) {
  if (!name.empty()) {
    try {
      return cycleByName(name);
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("--cycle", e.what());
    }
  }
  std::vector<const Cycle*> designing;
  for (const Cycle* cy : cycles())
    if (cy->hasDesign()) designing.push_back(cy);
  if (designing.size() != 1) {
    std::string names;
    for (const Cycle* cy : designing) names += (names.empty() ? "" : ", ") + std::string(cy->name());
    throw CLI::ValidationError("--cycle", "name the cycle to design for (" + names + ")");
  }
  return *designing.front();
}

int cmdDesign(const Common& c, const std::string& cycle_name, const std::string& machine_file,
              const std::string& contrib_file, int points, const std::string& criterion, const std::string& a_list,
              const std::string& c_list, int passes, const std::string& sweep, int runs, std::uint64_t seed,
              const std::string& out, const std::string& json_out) {
  const Cycle& cycle = designingCycle(cycle_name);
  DesignRequest r;
  r.points = points;
  r.criterion = criterion;
  if (!a_list.empty()) r.a_deg = numberList("--a-deg", a_list);
  if (!c_list.empty()) r.c_deg = numberList("--c-deg", c_list);
  if (!sweep.empty()) r.sweep = numberList("--sweep", sweep);
  r.exchange_passes = passes;
  r.runs = runs;
  r.seed = seed;
  r.plan_file = out;
  checkOutputs({{"-o", out}, {"--json", json_out}}, {machine_file, contrib_file});
  const MachineModel machine = loadMachine(machine_file);
  const ContributorSet cs = loadContributors(contrib_file);
  r.machine = &machine;
  r.contributors = &cs;
  r.progress = progressIndicator(c, "rotacal design", "exchange steps");
  DesignedPlan d;
  try {
    d = cycle.design(r);
  } catch (const OptionError& e) {
    throw CLI::ValidationError(e.option, e.what());
  } catch (const std::invalid_argument& e) {
    failFile(machine_file, e.what());
  }
  OutputSet outputs({machine_file, contrib_file});
  outputs.add("-o", out, planToJson(d.plan).dump(1) + "\n");
  if (!json_out.empty()) outputs.add("--json", json_out, d.doc.dump(1) + "\n");
  outputs.commit();
  sayUnlessPiped(c, d.text, json_out);
  return 0;
}

}  // namespace

std::vector<Command> uncertaintyCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string plan_file, contrib_file, json_out, text_out, methods, truth_file, machine_file, out, criterion = "A", cycle,
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
  des->add_option("--cycle", a->cycle, "the cycle to design for (default: the only cycle that designs plans)");
  des->add_option("--machine", a->machine_file, "MACHINE.json (one the cycle suits)")->required();
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
                    return cmdDesign(common, a->cycle, a->machine_file, a->contrib_file, a->points, a->criterion, a->a_list,
                                     a->c_list, a->passes, a->sweep, a->design_runs, a->seed, a->out, a->json_out);
                  }});
  return cmds;
}

}  // namespace rotacal
