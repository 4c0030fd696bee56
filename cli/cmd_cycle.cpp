// The verbs of contract.md that every cycle answers: plan, generate, simulate, analyze, diagnose.
// Each asks the registry (cycles/cycle.hpp) for the cycle and hands it the dialect's reader and
// writer; no cycle is named here.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/command.hpp"
#include "cli/output.hpp"
#include "cli/progress.hpp"
#include "controllers/dialect.hpp"
#include "core/compensation.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/judge.hpp"
#include "core/limits.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "core/verdict.hpp"
#include "cycles/cycle.hpp"
#include "history/store.hpp"
#include "postproc/compensate_program.hpp"
#include "postproc/report_errors.hpp"

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

std::string cycleList() {
  std::string s;
  // Each summary opens with its source: a paper's number ("000: ..."), a standard ("ISO 230-10: ...") or "rotacal's own".
  for (const Cycle* c : cycles())
    s += fmt::format("{}{} ({})", s.empty() ? "" : ", ", c->name(), c->summary().substr(0, c->summary().find(':')));
  return s;
}

const Cycle& cycleOfPlanFile(const ProbePlan& plan, const std::string& plan_file) {
  try {
    return cycleOfPlan(plan);
  } catch (const std::invalid_argument& e) {
    failFile(plan_file, e.what());
  }
}

DialectIO dialectIO(const Dialect& d) {
  return {std::string(d.name()),
          [&d](const std::string& text, const std::string& file, const ProbePlan& plan) {
            return d.parseResults(text, file, plan);
          },
          [&d](const ProbePlan& plan, const MeasurementRun& run) { return d.writeResults(plan, run); }};
}

// What simulate and diagnose read first, in this order: the plan (a bad one is named before a bad
// dialect), its cycle, the dialect and its results I/O.
struct PlanReader {
  PlanReader(const std::string& plan_file, const std::string& dialect_name)
      : plan(loadCyclePlan(plan_file)),
        cycle(cycleOfPlanFile(plan, plan_file)),
        dialect(dialectOrFail(dialect_name)),
        io(dialectIO(dialect)) {}
  /// A request of the plan's cycle on this plan, its results in this dialect.
  template <class Request>
  Request request() const {
    Request r;
    r.plan = &plan;
    r.dialect = &io;
    return r;
  }
  const ProbePlan plan;
  const Cycle& cycle;
  const Dialect& dialect;
  const DialectIO io;
};

// Each results file a distinct repeat (readResultsFiles refuses one measurement given twice).
std::vector<InputFile> readInputs(const std::vector<std::string>& paths) {
  const std::vector<std::string> texts = readResultsFiles(paths);
  std::vector<InputFile> files;
  for (size_t i = 0; i < paths.size(); ++i) files.push_back({paths[i], texts[i]});
  return files;
}

// Core and cycles throw std::invalid_argument for data that cannot be analyzed without naming a
// file: the results are what was analyzed.
template <class F>
auto onResults(const std::vector<std::string>& results, F&& f) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    failFile(results.front(), e.what());
  }
}

void warn(const std::vector<std::string>& warnings) {
  for (const auto& w : warnings) std::fprintf(stderr, "rotacal: warning: %s\n", w.c_str());
}

int cmdPlan(const Common& c, const std::string& cycle_name, const std::string& machine_file,
            const std::vector<std::string>& sets, const std::string& out, bool show_options) {
  if (out.empty() && !show_options) throw CLI::ValidationError("-o", "PLAN.json is required (or --show-options)");
  const Cycle* cycle = nullptr;
  try {
    cycle = &cycleByName(cycle_name);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--cycle", e.what());
  }
  OutputSet outputs({machine_file});
  checkOutputs({{"-o", out}}, {machine_file});
  const MachineModel machine = loadMachine(machine_file);
  ProbePlan plan;
  const CycleOptions options = parseSets(sets);
  try {
    plan = makePlan(std::string(cycle->name()), machine, options);
  } catch (const std::invalid_argument& e) {
    // An option given with --set that the cycle refuses is named as such, not as a fault of the
    // machine file at line 0; a plan that does not fit the machine is the machine file's.
    const std::string what = e.what();
    for (const auto& [key, value] : options)
      if (what.find(key) != std::string::npos) throw std::runtime_error("--set: " + what);
    failFile(machine_file, what);
  }
  // The options this plan uses, defaults included: what --set can change, on this machine.
  if (show_options) {
    std::string text = fmt::format("{} options on {} (the values this plan uses; change with --set KEY=VALUE):\n",
                                   plan.cycle, machine.name);
    for (const auto& [key, value] : plan.options) text += fmt::format("  {}={}\n", key, value);
    std::fputs(text.c_str(), stdout);
    if (out.empty()) return 0;
  }
  outputs.add("-o", out, planToJson(plan).dump(1) + "\n");
  outputs.commit();
  if (out != "-")
    say(c, fmt::format("plan {}: {} points in {} poses, about {:.0f} s of machine time -> {}\n", plan.cycle,
                       plan.points.size(), plan.poses.size(), cycleOfPlan(plan).machineSeconds(plan), out));
  return 0;
}

int cmdGenerate(const Common& c, const std::string& plan_file, const std::string& dialect_name, const std::string& out) {
  OutputSet outputs({plan_file});
  checkOutputs({{"-o", out}}, {plan_file});
  const ProbePlan plan = loadCyclePlan(plan_file);
  const Cycle& cycle = cycleOfPlanFile(plan, plan_file);
  const Dialect& d = dialectOrFail(dialect_name);
  std::string text;
  nc::Shape shape;
  try {
    const nc::Program program = cycle.program(plan, dialect_name);
    shape = nc::shapeOf(program);
    text = d.writeProgram(program);
  } catch (const std::invalid_argument& e) {
    failFile(plan_file, e.what());
  }
  const auto problems = d.check(text, plan, shape);
  if (!problems.empty())
    failFile(out, "generated program fails the " + std::string(d.name()) + " checker: " + problems.front());
  // The program verifier (`rotacal check`): clearances, guards, strokes, feeds, number.
  requireSafeProgram(text, out, dialect_name, plan.machine, &plan, true);
  outputs.add("-o", out, text);
  outputs.commit();
  if (out != "-") say(c, fmt::format("{} program: {} {} -> {}\n", d.name(), plan.points.size(), cycle.pointNoun(), out));
  return 0;
}

int cmdSimulate(const Common& c, const std::string& plan_file, const std::string& truth_file,
                std::optional<double> noise_um, std::uint64_t seed, std::optional<double> start_s,
                const std::string& dialect_name, const std::string& out, const std::string& contributors_file,
                std::uint64_t machine_seed, const std::string& truth_out) {
  // NaN would pass a "< 0" test and poison every trigger; a clock beyond the controllers' years
  // cannot be printed.
  if (noise_um && !(*noise_um >= 0 && *noise_um <= kMaxNoiseUm))
    throw CLI::ValidationError("--noise-um",
                               fmt::format("must be a number from 0 to {:g} um (got {})", kMaxNoiseUm, *noise_um));
  if (start_s && !(*start_s >= 0 && *start_s <= kMaxClockSeconds))
    throw CLI::ValidationError("--start-s", fmt::format("must be a number of seconds from 0 to {:g} (got {})",
                                                        kMaxClockSeconds, *start_s));
  std::vector<std::string> inputs = {plan_file, truth_file};
  if (!contributors_file.empty()) inputs.push_back(contributors_file);
  if (!truth_out.empty() && contributors_file.empty())
    throw CLI::ValidationError("--truth-out", "writes the machine drawn from --contributors: give --contributors");
  checkOutputs({{"-o", out}, {"--truth-out", truth_out}}, inputs);
  const PlanReader in(plan_file, dialect_name);
  auto r = in.request<SimulateRequest>();
  r.truth = {truth_file, readTextFile(truth_file)};
  r.noise_um = noise_um;
  r.start_s = start_s;
  r.seed = seed;
  std::optional<ContributorSet> declared;
  if (!contributors_file.empty()) declared = loadContributors(contributors_file);
  r.contributors = declared ? &*declared : nullptr;
  r.machine_seed = machine_seed;
  Simulated s;
  try {
    s = in.cycle.simulate(r);
  } catch (const std::invalid_argument& e) {
    failFile(truth_file, e.what());
  }
  if (declared && s.truth.is_null())
    throw CLI::ValidationError("--contributors", "the " + in.plan.cycle + " cycle's simulator draws no machine from "
                                                 "contributors (its truth file declares the machine)");
  OutputSet outputs(inputs);
  outputs.add("-o", out, std::move(s.results_text));
  if (!truth_out.empty()) outputs.add("--truth-out", truth_out, s.truth.dump(1) + "\n");
  outputs.commit();
  if (out != "-") say(c, s.message + " -> " + out + "\n");
  return 0;
}

int cmdAnalyze(const Common& c, const std::string& plan_file, const std::vector<std::string>& results,
               const std::string& dialect_name, const std::string& method, const std::string& json_out,
               const std::string& text_out, const std::string& offsets_out, bool force, const std::string& html_out,
               const std::string& contributors_file, int mc_runs, std::uint64_t mc_seed,
               const std::vector<std::string>& compensated_with, bool write_insignificant,
               const std::string& tolerance_text) {
  std::vector<std::string> inputs = results;
  inputs.push_back(plan_file);
  if (!contributors_file.empty()) inputs.push_back(contributors_file);
  for (const auto& r : compensated_with) inputs.push_back(r);
  if (mc_runs < 100 || mc_runs > 1000000) throw CLI::ValidationError("--mc-runs", "must be in [100, 1000000]");
  checkOutputs({{"--json", json_out}, {"--text", text_out}, {"--html", html_out}, {"--offsets", offsets_out}}, inputs);
  const ProbePlan plan = loadCyclePlan(plan_file);
  const Cycle& cycle = cycleOfPlanFile(plan, plan_file);
  const Dialect& d = dialectOrFail(dialect_name);
  if (!offsets_out.empty() && !cycle.noOffsetsReason().empty())
    throw CLI::ValidationError("--offsets", std::string(cycle.noOffsetsReason()));
  const auto methods = cycle.methods();
  if (!method.empty() && std::find(methods.begin(), methods.end(), method) == methods.end()) {
    std::string known;
    for (const auto& m : methods) known += (known.empty() ? "" : ", ") + m;
    throw CLI::ValidationError("--method", "the " + plan.cycle + " cycle has no method '" + method + "'" +
                                               (known.empty() ? std::string(" (it has one estimator)")
                                                              : " (known: " + known + ")"));
  }
  DialectIO io = dialectIO(d);
  // Results of a program rewritten by `compensate`: read back as the original program's, so that
  // the analysis identifies what the compensation left (docs/compensation.md).
  bool undone = false;
  if (!compensated_with.empty()) {
    std::vector<JsonDoc> reports;
    for (const auto& f : compensated_with) reports.push_back(readJsonFile(f));
    const GeometricErrors errors = errorsFromReports(reports, plan.machine.kinematics, true).errors;
    io.read_results = [&d, errors, &undone, name = dialect_name](const std::string& text, const std::string& file,
                                                               const ProbePlan& p) {
      undone = true;
      // The compensated program commands each pose's compensated angles and moves each probing
      // line with the table's error (compensatedPosition, as compensate rewrites it), and the
      // controller logs those: the reader holds each record to the pose and line as compensated,
      // not as planned (they differ by as much as the rotary axes' errors move the table, beyond
      // the reader's 1 mdeg and 0.1 mm).
      ProbePlan logged = p;
      for (auto& q : logged.points) {
        const Pose qc = compensatePose(errors, q.pose).pose;
        const Eigen::Vector3d through = q.trigger_m_mm + q.approach_m;
        q.trigger_m_mm = compensatedPosition(errors, q.pose, q.trigger_m_mm, qc);
        q.approach_m = (compensatedPosition(errors, q.pose, through, qc) - q.trigger_m_mm).normalized();
        q.pose = qc;
      }
      for (auto& q : logged.poses) q.pose = compensatePose(errors, q.pose).pose;
      return undoCompensation(p, d.parseResults(text, file, logged), errors, NcSyntax{name});
    };
  }
  AnalyzeRequest r;
  r.plan = &plan;
  r.results = readInputs(results);
  r.dialect = &io;
  r.method = method;
  std::optional<ContributorSet> declared;
  if (!contributors_file.empty()) declared = loadContributors(contributors_file);
  else declared = plan.machine.contributors;
  r.contributors = declared ? &*declared : nullptr;
  r.mc_runs = mc_runs;
  r.mc_seed = mc_seed;
  CycleDocuments docs = onResults(results, [&] { return cycle.analyze(r); });
  if (!compensated_with.empty()) {
    if (!undone)
      throw CLI::ValidationError("--compensated-with", "the " + plan.cycle + " cycle's results are not the controller's "
                                                      "trigger coordinates: there is no compensation to undo");
    Json list = Json::array();
    for (const auto& f : compensated_with) list.push_back(f);
    docs.doc["compensated_with"] = list;
    docs.doc["compensated_with_note"] =
        "results of the program compensated for these reports' errors, read back as the original program's: the "
        "errors identified are what the compensation left";
  }
  // The answer first: per parameter, adjust or leave, against the tolerance (--tolerance, else
  // MACHINE.json's) by ISO 14253-1 with the report's own U.
  {
    LocationTolerance tol = plan.machine.tolerance;
    if (!tolerance_text.empty()) {
      const size_t comma = tolerance_text.find(',');
      auto number = [&](const std::string& t) -> std::optional<double> {
        if (t.empty()) return std::nullopt;
        try {
          size_t used = 0;
          const double v = std::stod(t, &used);
          if (used == t.size() && v > 0) return v;
        } catch (const std::exception&) {
        }
        throw CLI::ValidationError("--tolerance", "expected LENGTH_UM,ANGLE_MDEG (positive; either may be empty), got '" +
                                                      tolerance_text + "'");
      };
      if (comma == std::string::npos) throw CLI::ValidationError("--tolerance", "expected LENGTH_UM,ANGLE_MDEG, got '" +
                                                                                    tolerance_text + "'");
      tol.length_um = number(tolerance_text.substr(0, comma));
      tol.angle_mdeg = number(tolerance_text.substr(comma + 1));
    }
    const Json& judged = docs.doc.contains("location_errors") ? docs.doc["location_errors"]
                         : docs.doc.contains("kinematic_parameters") ? docs.doc["kinematic_parameters"]
                                                                    : Json(nullptr);
    Json verdict = verdictJson(judged, tol);
    if (!verdict.is_null()) {
      docs.text = verdictText(verdict) + "\n" + docs.text;
      docs.doc["verdict"] = std::move(verdict);
    }
  }
  // When the data were analyzed: compensate flags a report that has grown old.
  docs.doc["analyzed_utc"] = history::isoTime(nowUnixS());
  OutputSet outputs(inputs);
  outputs.add("--json", json_out, docs.doc.dump(1) + "\n");
  addHtml(outputs, html_out, docs.doc);
  outputs.add("--text", text_out, docs.text);
  // No corrections at all (a machine no offsets writer serves): --force cannot help.
  if (!offsets_out.empty() && !docs.offsets)
    failFile(offsets_out, "not written: " + (docs.offsets_refused.empty() ? std::string("this analysis has no offsets")
                                                                          : docs.offsets_refused));
  if (!offsets_out.empty() && !docs.offsets_refused.empty() && !force)
    failFile(offsets_out, "not written: " + docs.offsets_refused + " (--force writes it)");
  // Offsets that would change values only inside their own U move the machine by what the
  // measurement cannot tell from zero: the data do not show the machine differs from its nominal.
  if (!offsets_out.empty() && docs.offsets && !write_insignificant && docs.doc.contains("location_errors")) {
    std::string beyond;
    bool judged = false;
    for (const auto& [name, e] : docs.doc["location_errors"].items()) {
      if (!e.contains("U") || !e.contains("value") || !e["U"].is_number() || !e["value"].is_number()) continue;
      judged = true;
      if (std::abs(e["value"].get<double>()) > e["U"].get<double>()) beyond += (beyond.empty() ? "" : ", ") + name;
    }
    if (judged && beyond.empty())
      failFile(offsets_out, "not written: every location error lies within its own U (REPORT.json): the data do not "
                            "show the machine differs from its nominal, so the offsets would move it by noise; leave "
                            "them as they are (--write-insignificant writes them anyway)");
  }
  if (!offsets_out.empty() && docs.offsets) {
    OffsetRequest req;
    req.plan = &plan;
    req.identified = docs.offsets->identified;
    req.u = docs.offsets->u;
    req.parameters = docs.offsets->parameters;
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
  sayUnlessPiped(c, docs.text, json_out, html_out);
  warn(docs.warnings);
  return 0;
}

int cmdDiagnose(const Common& c, const std::string& plan_file, const std::vector<std::string>& results,
                const std::string& dialect_name, double alpha, const std::string& json_out, const std::string& text_out,
                const std::string& html_out, const std::string& contributors_file) {
  if (!(alpha > 0 && alpha < 0.5)) throw CLI::ValidationError("--alpha", "alpha must be in (0, 0.5)");
  std::vector<std::string> inputs = results;
  inputs.push_back(plan_file);
  if (!contributors_file.empty()) inputs.push_back(contributors_file);
  checkOutputs({{"--json", json_out}, {"--text", text_out}, {"--html", html_out}}, inputs);
  const PlanReader in(plan_file, dialect_name);
  auto r = in.request<DiagnoseRequest>();
  r.results = readInputs(results);
  r.alpha = alpha;
  std::optional<ContributorSet> declared;
  if (!contributors_file.empty()) declared = loadContributors(contributors_file);
  else declared = in.plan.machine.contributors;
  r.contributors = declared ? &*declared : nullptr;
  const auto progress = progressIndicator(c, "rotacal diagnose", "candidate fits");
  auto total = std::make_shared<int>(0);
  if (progress)
    r.progress = [progress, total](int done, int all) {
      *total = all;
      progress(done, all);
    };
  const CycleDocuments docs = onResults(results, [&] { return in.cycle.diagnose(r); });
  if (progress && *total > 0) progress(*total, *total);  // ends the line
  writeDocuments(c, docs.doc, docs.text, json_out, text_out, html_out);
  warn(docs.warnings);
  return 0;
}

}  // namespace

std::vector<Command> cycleCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string cycle, machine_file, plan_file, dialect, out, truth_file, method, json_out, text_out, offsets_out,
        html_out, contributors_file, truth_out, tolerance;
    int mc_runs = 2000;
    std::uint64_t mc_seed = 1;
    std::vector<std::string> sets, results, compensated_with;
    double noise_um = 0.0, start_s = 0.0, alpha = JudgeOptions{}.alpha;
    std::uint64_t seed = 1, machine_seed = 1;
    bool force = false, write_insignificant = false, show_options = false;
  };
  auto a = std::make_shared<Args>();
  std::vector<Command> cmds;
  // The neutral results first, then the controllers'.
  const std::string results_dialects = [] {
    std::string neutral, controllers;
    for (const Dialect* d : dialects())
      (d->hasPrograms() ? controllers : neutral) += (" | " + std::string(d->name()));
    return (neutral + controllers).substr(3);
  }();

  auto* plan = app.add_subcommand("plan", "make the probing plan of a cycle for a machine");
  plan->add_option("--cycle", a->cycle, cycleList())->required();
  plan->add_option("--machine", a->machine_file, "MACHINE.json")->required();
  plan->add_option("--set", a->sets, "cycle option KEY=VALUE (repeatable), e.g. side_depth_mm=25");
  plan->add_option("-o,--output", a->out, "PLAN.json (required unless --show-options)");
  plan->add_flag("--show-options", a->show_options,
                 "print the cycle's options with the values this plan uses (its defaults on this machine)");
  cmds.push_back({plan, [a, &common] {
                    return cmdPlan(common, a->cycle, a->machine_file, a->sets, a->out, a->show_options);
                  }});

  auto* gen = app.add_subcommand("generate", "write the NC program of a plan in a controller dialect");
  gen->add_option("--plan", a->plan_file, "PLAN.json")->required();
  gen->add_option("--dialect", a->dialect, programDialectChoices())->required();
  gen->add_option("-o,--output", a->out, "PROGRAM")->required();
  cmds.push_back({gen, [a, &common] { return cmdGenerate(common, a->plan_file, a->dialect, a->out); }});

  auto* sim = app.add_subcommand("simulate", "what the controller records on a machine with known errors");
  sim->add_option("--plan", a->plan_file, "PLAN.json")->required();
  sim->add_option("--truth", a->truth_file, "TRUTH.json")->required();
  auto* noise_opt = sim->add_option("--noise-um", a->noise_um, "probe repeatability, standard deviation (um)");
  sim->add_option("--seed", a->seed, "random seed");
  auto* start_opt = sim->add_option("--start-s", a->start_s, "clock at the cycle start (s), for repeats");
  sim->add_option("--contributors", a->contributors_file,
                  "CONTRIB.json: draw a whole machine from these declared contributors on top of the truth (linear "
                  "axes, pretravel, set-up, form, per-touch scatter)");
  sim->add_option("--machine-seed", a->machine_seed, "seed of the machine drawn from --contributors (default 1)");
  sim->add_option("--truth-out", a->truth_out, "TRUTH.json: the truth simulated, with what was drawn");
  sim->add_option("--dialect", a->dialect, results_dialects)->required();
  sim->add_option("-o,--output", a->out, "RESULTS")->required();
  cmds.push_back({sim, [a, &common, noise_opt, start_opt] {
                    return cmdSimulate(common, a->plan_file, a->truth_file,
                                       noise_opt->count() ? std::optional<double>(a->noise_um) : std::nullopt, a->seed,
                                       start_opt->count() ? std::optional<double>(a->start_s) : std::nullopt,
                                       a->dialect, a->out, a->contributors_file, a->machine_seed, a->truth_out);
                  }});

  auto* ana = app.add_subcommand("analyze", "identify the errors of a cycle from the controller's results");
  ana->add_option("--plan", a->plan_file, "PLAN.json")->required();
  ana->add_option("--results", a->results, "RESULTS... (repeats of the plan, in time order)")->required();
  ana->add_option("--dialect", a->dialect, results_dialects)->required();
  ana->add_option("--method", a->method, "the estimator, for cycles that have several (touch: lsq_per_point, "
                                         "lsq_rigid_setup, closed_form)");
  ana->add_option("--json", a->json_out, "REPORT.json (- for stdout)");
  ana->add_option("--html", a->html_out, "REPORT.html: the report to look at, self-contained");
  ana->add_option("--text", a->text_out, "the readable summary, also printed on stdout");
  ana->add_option("--offsets", a->offsets_out, "compensation in the dialect's own form");
  ana->add_flag("--force", a->force, "write offsets beyond the plausibility limit");
  ana->add_option("--tolerance", a->tolerance,
                  "LENGTH_UM,ANGLE_MDEG: the tolerances the verdict decides against (ISO 14253-1 with U; default "
                  "MACHINE.json's \"tolerance\"; either may be empty)");
  ana->add_flag("--write-insignificant", a->write_insignificant,
                "write offsets although every location error lies within its own U");
  ana->add_option("--contributors", a->contributors_file,
                  "CONTRIB.json: the Type B contributors (default: the machine's `contributors`; docs/uncertainty.md)");
  ana->add_option("--mc-runs", a->mc_runs, "Monte Carlo runs of the Type B uncertainty (default 2000)");
  ana->add_option("--mc-seed", a->mc_seed, "seed of that Monte Carlo (default 1)");
  ana->add_option("--compensated-with", a->compensated_with,
                  "REPORT.json: the results are of a program `compensate` rewrote for this report's errors (repeat as "
                  "given to compensate); the analysis then identifies what the compensation left");
  cmds.push_back({ana, [a, &common] {
                    return cmdAnalyze(common, a->plan_file, a->results, a->dialect, a->method, a->json_out, a->text_out,
                                      a->offsets_out, a->force, a->html_out, a->contributors_file, a->mc_runs,
                                      a->mc_seed, a->compensated_with, a->write_insignificant, a->tolerance);
                  }});

  auto* dia = app.add_subcommand("diagnose", "find what the model misses, name the cause, extend the model, measure the gain");
  dia->add_option("--plan", a->plan_file, "PLAN.json")->required();
  dia->add_option("--results", a->results, "RESULTS... (repeats of the plan, in time order)")->required();
  dia->add_option("--dialect", a->dialect, results_dialects)->required();
  dia->add_option("--json", a->json_out, "DIAGNOSIS.json (- for stdout)")->required();
  dia->add_option("--html", a->html_out, "DIAGNOSIS.html: the report to look at, self-contained");
  dia->add_option("--text", a->text_out, "the readable summary, also printed on stdout");
  dia->add_option("--alpha", a->alpha, "family-wise false-alarm rate of the judge (default 0.01, docs/diagnosis.md)");
  dia->add_option("--contributors", a->contributors_file,
                  "CONTRIB.json: the declared contributors the tests read (default: the machine's `contributors`)");
  cmds.push_back({dia, [a, &common] {
                    return cmdDiagnose(common, a->plan_file, a->results, a->dialect, a->alpha, a->json_out,
                                       a->text_out, a->html_out, a->contributors_file);
                  }});
  return cmds;
}

}  // namespace rotacal
