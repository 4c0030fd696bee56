// The touch-cycle commands of contract.md: plan, generate, simulate, analyze.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/cmd_spaceframe.hpp"
#include "cli/cmd_tooltip.hpp"
#include "cli/cmd_rtest.hpp"
#include "cli/command.hpp"
#include "cli/output.hpp"
#include "cli/spheres3_cli.hpp"
#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "core/identification.hpp"
#include "core/json_io.hpp"
#include "core/limits.hpp"
#include "core/machine.hpp"
#include "core/point_deviations.hpp"
#include "core/probe_plan.hpp"
#include "core/report.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "postproc/probe_program.hpp"
#include "postproc/tooltip_program.hpp"
#include "postproc/rtest_program.hpp"

namespace rotacal {
namespace {

CycleOptions parseSets(const std::vector<std::string>& sets) {
  CycleOptions o;
  for (const auto& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) throw CLI::ValidationError("--set", "expected KEY=VALUE, got '" + s + "'");
    o[s.substr(0, eq)] = s.substr(eq + 1);
  }
  return o;
}

int cmdPlan(const Common& c, const std::string& cycle, const std::string& machine_file,
            const std::vector<std::string>& sets, const std::string& out) {
  OutputSet outputs({machine_file});
  checkOutputs({{"-o", out}}, {machine_file});
  const MachineModel machine = loadMachine(machine_file);
  ProbePlan plan;
  try {
    plan = makePlan(cycle, machine, parseSets(sets));
  } catch (const std::invalid_argument& e) {
    failFile(machine_file, e.what());
  }
  outputs.add("-o", out, planToJson(plan).dump(1) + "\n");
  outputs.commit();
  if (out != "-")
    say(c, fmt::format("plan {}: {} points in {} poses, about {:.0f} s of machine time -> {}\n", plan.cycle,
                       plan.points.size(), plan.poses.size(), plan.points.empty() ? 0.0 : plan.points.back().t_s, out));
  return 0;
}

int cmdGenerate(const Common& c, const std::string& plan_file, const std::string& dialect_name, const std::string& out) {
  OutputSet outputs({plan_file});
  checkOutputs({{"-o", out}}, {plan_file});
  const ProbePlan plan = loadPlan(plan_file);
  const Dialect& d = dialectOrFail(dialect_name);
  std::string text;
  try {
    text = d.writeProgram(plan.cycle == "tooltip" ? tooltipProgram(plan, dialect_name)
                          : plan.cycle == "rtest" ? rtestProgram(plan, dialect_name)
                                                  : probeProgram(plan, dialect_name));
  } catch (const std::invalid_argument& e) {
    failFile(plan_file, e.what());
  }
  const auto problems = d.check(text, plan);
  if (!problems.empty())
    failFile(out, "generated program fails the " + std::string(d.name()) + " checker: " + problems.front());
  outputs.add("-o", out, text);
  outputs.commit();
  if (out != "-")
    say(c, fmt::format("{} program: {} {} -> {}\n", d.name(), plan.points.size(),
                       plan.cycle == "tooltip" ? "tool-tip poses"
                       : plan.cycle == "rtest" ? "R-test poses"
                                               : "probing moves",
                       out));
  return 0;
}

int cmdSimulate(const Common& c, const std::string& plan_file, const std::string& truth_file, double noise_um,
                bool noise_given, std::uint64_t seed, double start_s, bool start_given, const std::string& dialect_name,
                const std::string& out) {
  // NaN would pass a "< 0" test and poison every trigger; a clock beyond the controllers' years
  // cannot be printed.
  if (noise_given && !(noise_um >= 0 && noise_um <= kMaxNoiseUm))
    throw CLI::ValidationError("--noise-um",
                               fmt::format("must be a number from 0 to {:g} um (got {})", kMaxNoiseUm, noise_um));
  if (start_given && !(start_s >= 0 && start_s <= kMaxClockSeconds))
    throw CLI::ValidationError("--start-s", fmt::format("must be a number of seconds from 0 to {:g} (got {})",
                                                        kMaxClockSeconds, start_s));
  checkOutputs({{"-o", out}}, {plan_file, truth_file});
  const ProbePlan plan = loadPlan(plan_file);
  if (plan.cycle == "tooltip") {
    (void)start_s, (void)start_given;
    dialectOrFail(dialect_name);
    return simulateTooltipCmd(c, plan, truth_file, noise_um, noise_given, seed, out);
  }
  if (plan.cycle == "rtest") return rtestSimulate(c, plan, truth_file, noise_um, noise_given, seed, start_s, out);
  Truth truth = loadTruth(truth_file, plan.machine.kinematics);
  if (noise_given) truth.noise_um = noise_um;
  if (start_given) truth.start_time_s = start_s;
  const Dialect& d = dialectOrFail(dialect_name);
  MeasurementRun run;
  try {
    run = simulate(plan, truth, {seed});
  } catch (const std::exception& e) {
    failFile(truth_file, e.what());
  }
  std::string text;
  try {
    text = d.writeResults(plan, run);
  } catch (const std::invalid_argument& e) {  // e.g. a clock the controller cannot print
    failFile(truth_file, e.what());
  }
  OutputSet outputs({plan_file, truth_file});
  outputs.add("-o", out, std::move(text));
  outputs.commit();
  if (out != "-")
    say(c, fmt::format("simulated {} triggers (noise {:.3f} um, seed {}) as {} results -> {}\n", run.points.size(),
                       truth.noise_um, seed, d.name(), out));
  return 0;
}

int cmdAnalyze(const Common& c, const std::string& plan_file, const std::vector<std::string>& results,
               const std::string& dialect_name, const std::string& method_name, const std::string& json_out,
               const std::string& text_out, const std::string& offsets_out, bool force,
               const std::string& html_out) {
  std::vector<std::string> inputs = results;
  inputs.push_back(plan_file);
  checkOutputs({{"--json", json_out}, {"--text", text_out}, {"--html", html_out}, {"--offsets", offsets_out}}, inputs);
  const ProbePlan plan = loadPlan(plan_file);
  const Dialect& d = dialectOrFail(dialect_name);
  if (plan.cycle == "tooltip") {
    if (!offsets_out.empty()) failFile(offsets_out, "the tooltip cycle writes no offsets (a head's pivot length and angular "
                                                    "errors go into the machine's kinematics tables by hand)");
    return analyzeTooltipCmd(c, plan, results, json_out, text_out, html_out);
  }
  if (plan.cycle == "rtest") return rtestAnalyze(c, plan, results, json_out, text_out, offsets_out, html_out);
  Method method;
  try {
    method = methodFromName(method_name);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--method", e.what());
  }
  std::vector<MeasurementRun> runs;
  const std::vector<std::string> texts = readResultsFiles(results);
  for (size_t i = 0; i < results.size(); ++i) runs.push_back(d.parseResults(texts[i], results[i], plan));
  if (plan.cycle == "spaceframe") return analyzeSpaceframeCommand(c, plan, runs, results, json_out, text_out, offsets_out, html_out);
  if (plan.cycle == "spheres3") return analyzeSpheres3(c, plan, runs, results, json_out, text_out, offsets_out, html_out);

  IdentificationOptions opt;
  opt.method = method;
  opt.prior_sigma_um = plan.machine.probe.repeatability_um;
  Analysis a;
  a.plan = &plan;
  a.result_files = results;
  a.main = identify(plan, runs, opt);
  if (a.main.summary.termination == Termination::RankDeficient || a.main.summary.termination == Termination::InvalidInput)
    failFile(results.front(), a.main.summary.message);
  if (runs.size() > 1)
    for (const auto& r : runs) a.per_run.push_back(identify(plan, {r}, opt));
  for (Method other : {Method::LeastSquaresPerPoint, Method::LeastSquaresRigidSetup, Method::ClosedForm}) {
    if (other == method) continue;
    IdentificationOptions o = opt;
    o.method = other;
    a.other_methods.push_back(identify(plan, runs, o));
  }
  if (plan.cycle == "touch154") {
    try {
      a.patterns = touch154Patterns(plan, runs.front());
    } catch (const std::invalid_argument&) {
      // a reduced plan has no complete pattern set; the least squares still runs
    }
  }
  const std::string text = analysisText(a);
  Json report_json = analysisToJson(a);
  report_json["points"] = pointDeviationsJson(plan, runs, a.main);  // the HTML report's deviation views
  OutputSet outputs(inputs);
  outputs.add("--json", json_out, report_json.dump(1) + "\n");
  addHtml(outputs, html_out, report_json);
  outputs.add("--text", text_out, text);
  if (!offsets_out.empty()) {
    OffsetRequest req;
    req.plan = &plan;
    req.identified = a.main.estimate;
    req.u = a.main.u;
    req.report_file = json_out.empty() || json_out == "-" ? results.front() : json_out;
    req.force = force;
    req.path = offsets_out;
    if (std::filesystem::exists(offsets_out)) req.previous_text = readTextFile(offsets_out);
    std::string off;
    try {
      off = d.writeOffsets(req);
    } catch (const std::invalid_argument& e) {
      failFile(offsets_out, e.what());
    }
    outputs.add("--offsets", offsets_out, std::move(off));
  }
  outputs.commit();
  sayUnlessPiped(c, text, json_out, html_out);
  if (a.main.summary.termination != Termination::Converged)
    std::fprintf(stderr, "rotacal: warning: %s\n", a.main.summary.message.c_str());
  return 0;
}


}  // namespace

std::vector<Command> touchCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string cycle, machine_file, plan_file, dialect, out, truth_file, method = "lsq_per_point", json_out, text_out,
        offsets_out, html_out;
    std::vector<std::string> sets, results;
    double noise_um = 0.0, start_s = 0.0;
    std::uint64_t seed = 1;
    bool force = false;
  };
  auto a = std::make_shared<Args>();
  std::vector<Command> cmds;

  auto* plan = app.add_subcommand("plan", "make the probing plan of a cycle for a machine");
  plan->add_option("--cycle", a->cycle,
                   "touch154 (000), spheres3 (001), rtest (002), spaceframe (003), tooltip (004)")->required();
  plan->add_option("--machine", a->machine_file, "MACHINE.json")->required();
  plan->add_option("--set", a->sets, "cycle option KEY=VALUE (repeatable), e.g. side_depth_mm=25");
  plan->add_option("-o,--output", a->out, "PLAN.json")->required();
  cmds.push_back({plan, [a, &common] { return cmdPlan(common, a->cycle, a->machine_file, a->sets, a->out); }});

  auto* gen = app.add_subcommand("generate", "write the NC program of a plan in a controller dialect");
  gen->add_option("--plan", a->plan_file, "PLAN.json")->required();
  gen->add_option("--dialect", a->dialect, "linuxcnc | fanuc | haas | siemens | heidenhain | okuma")->required();
  gen->add_option("-o,--output", a->out, "PROGRAM")->required();
  cmds.push_back({gen, [a, &common] { return cmdGenerate(common, a->plan_file, a->dialect, a->out); }});

  auto* sim = app.add_subcommand("simulate", "what the controller records on a machine with known errors");
  sim->add_option("--plan", a->plan_file, "PLAN.json")->required();
  sim->add_option("--truth", a->truth_file, "TRUTH.json")->required();
  auto* noise_opt = sim->add_option("--noise-um", a->noise_um, "probe repeatability, standard deviation (um)");
  sim->add_option("--seed", a->seed, "random seed");
  auto* start_opt = sim->add_option("--start-s", a->start_s, "clock at the cycle start (s), for repeats");
  sim->add_option("--dialect", a->dialect, "csv | linuxcnc | fanuc | haas | siemens | heidenhain | okuma")->required();
  sim->add_option("-o,--output", a->out, "RESULTS")->required();
  cmds.push_back({sim, [a, &common, noise_opt, start_opt] {
                    return cmdSimulate(common, a->plan_file, a->truth_file, a->noise_um, noise_opt->count() > 0, a->seed,
                                       a->start_s, start_opt->count() > 0, a->dialect, a->out);
                  }});

  auto* ana = app.add_subcommand("analyze", "identify the location errors from the controller's results");
  ana->add_option("--plan", a->plan_file, "PLAN.json")->required();
  ana->add_option("--results", a->results, "RESULTS... (repeats of the plan, in time order)")->required();
  ana->add_option("--dialect", a->dialect, "csv | linuxcnc | fanuc | haas | siemens | heidenhain | okuma")->required();
  ana->add_option("--method", a->method, "lsq_per_point (form-immune, default) | lsq_rigid_setup | closed_form");
  ana->add_option("--json", a->json_out, "REPORT.json (- for stdout)");
  ana->add_option("--html", a->html_out, "REPORT.html: the report to look at, self-contained");
  ana->add_option("--text", a->text_out, "the readable summary, also printed on stdout");
  ana->add_option("--offsets", a->offsets_out, "compensation in the dialect's own form");
  ana->add_flag("--force", a->force, "write offsets beyond the plausibility limit");
  cmds.push_back({ana, [a, &common] {
                    return cmdAnalyze(common, a->plan_file, a->results, a->dialect, a->method, a->json_out, a->text_out,
                                      a->offsets_out, a->force, a->html_out);
                  }});
  return cmds;
}

}  // namespace rotacal
