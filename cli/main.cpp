// rotacal: the command line of contract.md. Exit 0 on success, 1 on bad input or data (one line
// "rotacal: error: FILE:LINE: what is wrong"), 2 on a usage error. Outputs are written whole
// (temporary file + rename) or not at all, and an existing output is kept as FILE.bak.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "core/identification.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "core/report.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "postproc/probe_program.hpp"

#ifndef ROTACAL_VERSION
#define ROTACAL_VERSION "0.0.0"
#endif

namespace rotacal {
namespace {

/// A failure tied to a file given on the command line, when the core cannot name a line.
[[noreturn]] void failFile(const std::string& file, const std::string& what) { throw InputError(file, 0, what); }

struct Common {
  bool quiet = false;
};

void say(const Common& c, const std::string& text) {
  if (!c.quiet) std::fputs(text.c_str(), stdout);
}

CycleOptions parseSets(const std::vector<std::string>& sets) {
  CycleOptions o;
  for (const auto& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) throw CLI::ValidationError("--set", "expected KEY=VALUE, got '" + s + "'");
    o[s.substr(0, eq)] = s.substr(eq + 1);
  }
  return o;
}

const Dialect& dialectOrFail(const std::string& name) {
  try {
    return dialectByName(name);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--dialect", e.what());
  }
}

int cmdPlan(const Common& c, const std::string& cycle, const std::string& machine_file,
            const std::vector<std::string>& sets, const std::string& out) {
  const MachineModel machine = loadMachine(machine_file);
  ProbePlan plan;
  try {
    plan = makePlan(cycle, machine, parseSets(sets));
  } catch (const std::invalid_argument& e) {
    failFile(machine_file, e.what());
  }
  writeFileAtomic(out, planToJson(plan).dump(1) + "\n");
  say(c, fmt::format("plan {}: {} points in {} poses, about {:.0f} s of machine time -> {}\n", plan.cycle,
                     plan.points.size(), plan.poses.size(), plan.points.empty() ? 0.0 : plan.points.back().t_s, out));
  return 0;
}

int cmdGenerate(const Common& c, const std::string& plan_file, const std::string& dialect_name, const std::string& out) {
  const ProbePlan plan = loadPlan(plan_file);
  const Dialect& d = dialectOrFail(dialect_name);
  std::string text;
  try {
    text = d.writeProgram(probeProgram(plan, dialect_name));
  } catch (const std::invalid_argument& e) {
    failFile(plan_file, e.what());
  }
  const auto problems = d.check(text, plan);
  if (!problems.empty())
    failFile(out, "generated program fails the " + std::string(d.name()) + " checker: " + problems.front());
  writeFileAtomic(out, text);
  say(c, fmt::format("{} program: {} probing moves -> {}\n", d.name(), plan.points.size(), out));
  return 0;
}

int cmdSimulate(const Common& c, const std::string& plan_file, const std::string& truth_file, double noise_um,
                bool noise_given, std::uint64_t seed, double start_s, bool start_given, const std::string& dialect_name,
                const std::string& out) {
  const ProbePlan plan = loadPlan(plan_file);
  Truth truth = loadTruth(truth_file, plan.machine.kinematics);
  if (noise_given) truth.noise_um = noise_um;
  if (start_given) truth.start_time_s = start_s;
  if (truth.noise_um < 0) throw CLI::ValidationError("--noise-um", "must be >= 0");
  const Dialect& d = dialectOrFail(dialect_name);
  MeasurementRun run;
  try {
    run = simulate(plan, truth, {seed});
  } catch (const std::exception& e) {
    failFile(truth_file, e.what());
  }
  writeFileAtomic(out, d.writeResults(plan, run));
  say(c, fmt::format("simulated {} triggers (noise {:.3f} um, seed {}) as {} results -> {}\n", run.points.size(),
                     truth.noise_um, seed, d.name(), out));
  return 0;
}

int cmdAnalyze(const Common& c, const std::string& plan_file, const std::vector<std::string>& results,
               const std::string& dialect_name, const std::string& method_name, const std::string& json_out,
               const std::string& text_out, const std::string& offsets_out, bool force) {
  const ProbePlan plan = loadPlan(plan_file);
  const Dialect& d = dialectOrFail(dialect_name);
  Method method;
  try {
    method = methodFromName(method_name);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--method", e.what());
  }
  std::vector<MeasurementRun> runs;
  for (const auto& f : results) runs.push_back(d.parseResults(readTextFile(f), f, plan));

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
  if (!json_out.empty()) writeFileAtomic(json_out, analysisToJson(a).dump(1) + "\n");
  if (!text_out.empty()) writeFileAtomic(text_out, text);
  if (!offsets_out.empty()) {
    OffsetRequest req;
    req.plan = &plan;
    req.identified = a.main.estimate;
    req.u = a.main.u;
    req.report_file = json_out.empty() ? results.front() : json_out;
    req.force = force;
    if (std::filesystem::exists(offsets_out)) req.previous_text = readTextFile(offsets_out);
    std::string off;
    try {
      off = d.writeOffsets(req);
    } catch (const std::invalid_argument& e) {
      failFile(offsets_out, e.what());
    }
    writeFileAtomic(offsets_out, off);
  }
  say(c, text);
  if (a.main.summary.termination != Termination::Converged)
    std::fprintf(stderr, "rotacal: warning: %s\n", a.main.summary.message.c_str());
  return 0;
}

}  // namespace
}  // namespace rotacal

int main(int argc, char** argv) {
  using namespace rotacal;
  CLI::App app{"rotacal: calibrate the rotary axes of five-axis machine tools with the machine's touch probe"};
  app.set_version_flag("--version", std::string("rotacal ") + ROTACAL_VERSION);
  app.require_subcommand(1);
  Common common;
  app.add_flag("-q,--quiet", common.quiet, "print nothing on success");

  std::string cycle, machine_file, plan_file, dialect, out, truth_file, method = "lsq_per_point", json_out, text_out,
      offsets_out;
  std::vector<std::string> sets, results;
  double noise_um = 0.0, start_s = 0.0;
  std::uint64_t seed = 1;
  bool force = false;

  auto* plan = app.add_subcommand("plan", "make the probing plan of a cycle for a machine");
  plan->add_option("--cycle", cycle, "touch154 (000); rtest, spheres3, tooltip, spaceframe later")->required();
  plan->add_option("--machine", machine_file, "MACHINE.json")->required();
  plan->add_option("--set", sets, "cycle option KEY=VALUE (repeatable), e.g. side_depth_mm=25");
  plan->add_option("-o,--output", out, "PLAN.json")->required();

  auto* gen = app.add_subcommand("generate", "write the NC program of a plan in a controller dialect");
  gen->add_option("--plan", plan_file, "PLAN.json")->required();
  gen->add_option("--dialect", dialect, "linuxcnc | fanuc")->required();
  gen->add_option("-o,--output", out, "PROGRAM")->required();

  auto* sim = app.add_subcommand("simulate", "what the controller records on a machine with known errors");
  sim->add_option("--plan", plan_file, "PLAN.json")->required();
  sim->add_option("--truth", truth_file, "TRUTH.json")->required();
  auto* noise_opt = sim->add_option("--noise-um", noise_um, "probe repeatability, standard deviation (um)");
  sim->add_option("--seed", seed, "random seed");
  auto* start_opt = sim->add_option("--start-s", start_s, "clock at the cycle start (s), for repeats");
  sim->add_option("--dialect", dialect, "csv | linuxcnc | fanuc")->required();
  sim->add_option("-o,--output", out, "RESULTS")->required();

  auto* ana = app.add_subcommand("analyze", "identify the location errors from the controller's results");
  ana->add_option("--plan", plan_file, "PLAN.json")->required();
  ana->add_option("--results", results, "RESULTS... (repeats of the plan, in time order)")->required();
  ana->add_option("--dialect", dialect, "csv | linuxcnc | fanuc")->required();
  ana->add_option("--method", method, "lsq_per_point (form-immune, default) | lsq_rigid_setup | closed_form");
  ana->add_option("--json", json_out, "REPORT.json");
  ana->add_option("--text", text_out, "the readable summary, also printed on stdout");
  ana->add_option("--offsets", offsets_out, "compensation in the dialect's own form");
  ana->add_flag("--force", force, "write offsets beyond the plausibility limit");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (*plan) return cmdPlan(common, cycle, machine_file, sets, out);
    if (*gen) return cmdGenerate(common, plan_file, dialect, out);
    if (*sim)
      return cmdSimulate(common, plan_file, truth_file, noise_um, noise_opt->count() > 0, seed, start_s,
                         start_opt->count() > 0, dialect, out);
    if (*ana) return cmdAnalyze(common, plan_file, results, dialect, method, json_out, text_out, offsets_out, force);
  } catch (const CLI::ValidationError& e) {
    std::fprintf(stderr, "rotacal: usage error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rotacal: error: %s\n", e.what());
    return 1;
  }
  return 2;
}
