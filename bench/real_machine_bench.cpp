// rotacal_real_machine_bench: analyze and diagnose on real machines, not the clean world. Each
// machine is drawn by the independent generator (bench/independent_machine.hpp: 000 Eq. (1),
// Eq. (22)-(23), set-up, form, pretravel, repeatability and roughness from the contributors
// file, location errors around 000 Table 4), measured with the cycle's bundled plan, written
// through a dialect's results writer and read back, analyzed and diagnosed through the Cycle
// interface exactly as the command line does (`analyze --contributors CONTRIB --offsets`,
// `diagnose --contributors CONTRIB`). The same machine is measured again with a chip under one
// random touch (20 um and 1 mm) and analyzed. Printed, not asserted: the figures of docs/real_machines.md.
//
// Run: build/bench/rotacal_real_machine_bench [--machines N] [--mc-runs R] [--seed S]
//        [--contributors FILE] [--machine FILE] [--dialect D] [--sd-um X] [--sd-mdeg X] [--no-chips] [--verbose]
//        [--cycle touch154|one_sphere|spheres3|spaceframe|tooltip|rtest|probe_qual] [--dump DIR] [--off LIST]
// --off switches contributors of the generator off (setup, form, linear_axes, pretravel,
// repeatability, roughness; tooltip: linear_axes, alignment, laser (the per-reading terms), pivot
// (the head's dR); rtest: linear_axes, sphere (its offset), sensors (gain and direction), drift,
// noise (the sensors' own), form (the sphere's, per reading));
// comma-separated), to see which one a failure is owed to.
// --runs N (tooltip only; default: the bundled plan's own `repeats`, 3): the plan made with
// repeats = N and measured N times on the same drawn machine (the same head and linear axes; a
// new laser zero and per-reading scatter each run), the N runs in one results file as its program
// has the laser write them; the chip is in one reading of one run (the run drawn with the reading).
// --dump writes the first machine's PLAN.json, RESULTS, TRUTH.json, REPORT.json and DIAGNOSIS.json,
// so that the command line can be run on the same data (`rotacal analyze --plan DIR/PLAN.json ...`).
// Defaults: 200 machines, 2000 Monte Carlo runs per analysis (the CLI's default), seeds 1..N,
// the cycle's bundled example machine and options and the contributors that machine declares
// (examples/contributors/table5.json for the A/C cycles), linuxcnc; about 2 s per machine (three analyses and one
// diagnosis). `--machines 20` is a quick check; `--mc-runs 500` cuts the analyses' time further.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "bench/independent_machine.hpp"
#include "bench/independent_rtest.hpp"
#include "controllers/dialect.hpp"
#include "core/contributors.hpp"
#include "core/machine.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probe_qual/plan.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/tooltip/plan.hpp"

#ifndef ROTACAL_SOURCE_DIR
#define ROTACAL_SOURCE_DIR "."
#endif

using namespace rotacal;
namespace ind = rotacal::independent;

namespace {

struct Args {
  int machines = 200;
  int mc_runs = 2000;
  std::uint64_t seed = 1;
  // Empty: the cycle's bundled example machine with its example options (`plan --cycle C` with no
  // --machine), and the contributors that machine declares (else table5.json).
  std::string contributors;
  std::string machine;
  std::string dialect = "linuxcnc";
  double sd_um = 5.0, sd_mdeg = 0.5;
  std::string cycle = "touch154";
  bool chips = true;
  bool verbose = false;
  std::string dump;  // a folder for the first machine's RESULTS, REPORT.json and DIAGNOSIS.json
  std::string off;   // contributors switched off, comma-separated (what each failure is owed to)
  int runs = 0;      // tooltip: runs of the plan on the same machine (0: the plan's own repeats)
};

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "rotacal_real_machine_bench: %s\nusage: rotacal_real_machine_bench [--machines N] [--mc-runs R] [--seed S] "
               "[--contributors FILE] [--machine FILE] [--dialect D] [--sd-um X] [--sd-mdeg X] [--no-chips] [--verbose] [--runs N]\n"
               "       [--cycle touch154|one_sphere|spheres3|spaceframe|tooltip|rtest|probe_qual] [--dump DIR] [--off setup,form,linear_axes,pretravel,repeatability,roughness,alignment,laser,pivot,sphere,sensors,drift,noise]\n",
               why);
  std::exit(2);
}

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(("missing value of " + k).c_str());
      return argv[++i];
    };
    if (k == "--machines") a.machines = std::stoi(value());
    else if (k == "--mc-runs") a.mc_runs = std::stoi(value());
    else if (k == "--seed") a.seed = std::stoull(value());
    else if (k == "--contributors") a.contributors = value();
    else if (k == "--machine") a.machine = value();
    else if (k == "--dialect") a.dialect = value();
    else if (k == "--sd-um") a.sd_um = std::stod(value());
    else if (k == "--sd-mdeg") a.sd_mdeg = std::stod(value());
    else if (k == "--no-chips") a.chips = false;
    else if (k == "--verbose") a.verbose = true;
    else if (k == "--cycle") a.cycle = value();
    else if (k == "--dump") a.dump = value();
    else if (k == "--off") a.off = value();
    else if (k == "--runs") a.runs = std::stoi(value());
    else usage(("unknown option " + k).c_str());
  }
  if (a.machines < 1) usage("--machines must be >= 1");
  if (a.runs < 0) usage("--runs must be >= 1");
  if (a.runs > 0 && a.cycle != "tooltip") usage("--runs is for --cycle tooltip");
  if (a.mc_runs < 100) usage("--mc-runs must be >= 100 (analyze's own lower limit)");
  return a;
}

DialectIO dialectIO(const Dialect& d) {
  return {std::string(d.name()),
          [&d](const std::string& text, const std::string& file, const ProbePlan& plan) {
            return d.parseResults(text, file, plan);
          },
          [&d](const ProbePlan& plan, const MeasurementRun& run) { return d.writeResults(plan, run); }};
}

// The results file's name: the dialect's, or the tool-tip laser's neutral CSV (its readings come
// from the laser system, whatever the dialect; the R-test's from its logger, likewise).
// Repeats (run > 0) are RESULTS2, RESULTS3, ... as an operator would save them.
std::string resultsName(const ProbePlan& plan, const Dialect& d, int run = 0) {
  const std::string stem = run > 0 ? fmt::format("RESULTS{}", run + 1) : std::string("RESULTS");
  return plan.cycle == "tooltip" || plan.cycle == "rtest" ? stem + ".csv" : stem + std::string(d.resultsExtension());
}

// One drawn machine: an A/C table (the probing cycles), a spindle head (tooltip) or a B/C table
// with an R-test (rtest).
struct Drawn {
  ind::Machine m;
  ind::Head head;
  ind::RtestMachine rt;
};

// What one analyze gave, as the command line would see it.
/// The screen's stated reach (REPORT.json outliers.reach.points[].detectable_um, um) at the value
/// of run `run1` (1-based), point `point` whose name ends in `suffix` (empty: any); +inf where the
/// report says the screen cannot see it (null), nothing when the report gives no reach there.
std::optional<double> statedReach(const Json& doc, int run1, int point, const std::string& suffix) {
  if (!doc.contains("outliers") || !doc["outliers"].contains("reach") || doc["outliers"]["reach"].is_null()) return {};
  for (const auto& e : doc["outliers"]["reach"]["points"]) {
    if (e.value("run", 0) != run1 || e.value("point", -1) != point) continue;
    const std::string name = e.value("name", std::string());
    if (!suffix.empty() && (name.size() < suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0))
      continue;
    if (e["detectable_um"].is_null()) return std::numeric_limits<double>::infinity();
    return e["detectable_um"].get<double>();
  }
  return {};
}

struct Analyzed {
  bool ok = false;            // analyze returned (no refusal of the data as a whole)
  std::string error;          // its message otherwise
  bool written = false;       // `--offsets` would write the file (no refusal, the writer accepts it)
  std::string refused;        // why not
  std::vector<int> excluded;  // point ids the outlier screen left out (rtest: 3 x pose id + axis)
  std::vector<int> excluded_run;  // the run (1-based) of each, 1 where the report names none
  bool finding = false;       // REPORT.json names a finding (rtest: the re-read check's sensor_step)
  bool too_many = false;
  bool held_back = false;     // REPORT.json's corrections_held_back: the data beyond the declaration
  int beyond = 0;
  double threshold_t = 0;
  Json doc;
};

Analyzed analyze(const Cycle& cycle, const ProbePlan& plan, const Dialect& d, const DialectIO& io,
                 const ContributorSet& contrib, const std::vector<std::string>& results, const Args& args, std::uint64_t mc_seed) {
  AnalyzeRequest r;
  r.plan = &plan;
  for (size_t i = 0; i < results.size(); ++i) r.results.push_back({resultsName(plan, d, static_cast<int>(i)), results[i]});
  r.dialect = &io;
  r.contributors = &contrib;
  r.mc_runs = args.mc_runs;
  r.mc_seed = mc_seed;
  Analyzed a;
  CycleDocuments docs;
  try {
    docs = cycle.analyze(r);
  } catch (const std::exception& e) {
    a.error = e.what();
    return a;
  }
  a.ok = true;
  a.doc = docs.doc;
  a.held_back = a.doc.contains("corrections_held_back");
  a.finding = a.doc.contains("findings") && a.doc["findings"].is_array() && !a.doc["findings"].empty();
  if (a.doc.contains("outliers")) {
    const Json& o = a.doc["outliers"];
    for (const auto& e : o.value("excluded", Json::array())) {
      // The R-test screens values: a pose's reading of one sensor (x, y, z).
      if (e.contains("axis") && e["axis"].is_string())
        a.excluded.push_back(3 * e.value("pose", 0) + static_cast<int>(std::string("xyz").find(e["axis"].get<std::string>())));
      else
        a.excluded.push_back(e.value("point", 0));
      a.excluded_run.push_back(e.contains("run") && e["run"].is_number_integer() ? e["run"].get<int>() : 1);
    }
    a.too_many = o.value("too_many", false);
    a.beyond = o.value("beyond", 0);
    a.threshold_t = o.value("threshold_t", 0.0);
  }
  // `analyze --offsets` (cli/cmd_cycle.cpp): no corrections, a refusal, or the dialect's writer
  // refusing a correction beyond its plausibility limit each mean no file without --force.
  if (!docs.offsets) {
    a.refused = docs.offsets_refused.empty() ? "no offsets" : docs.offsets_refused;
  } else if (!docs.offsets_refused.empty()) {
    a.refused = docs.offsets_refused;
  } else {
    OffsetRequest req;
    req.plan = &plan;
    req.identified = docs.offsets->identified;
    req.u = docs.offsets->u;
    req.report_file = "REPORT.json";
    req.path = "offsets.ngc";
    try {
      (void)d.writeOffsets(req);
      a.written = true;
    } catch (const std::exception& e) {
      a.refused = e.what();
    }
  }
  return a;
}

// The report's value and U of a parameter, in report units; nullopt when the report has none.
struct ValueU {
  double value = 0, U = 0, u_c = 0;
};
// A parameter's value, U and u_c in the report: U and u_c beside the value, else in the budget's
// block under the parameter's own name or its ISO 230-7 name (one_sphere's budget is in those).
std::optional<ValueU> reported(const Json& doc, const std::string& name) {
  const Json* entry = nullptr;
  if (doc.contains("location_errors") && doc["location_errors"].contains(name)) entry = &doc["location_errors"][name];
  const Json* budget = nullptr;
  if (doc.contains("uncertainty") && doc["uncertainty"].contains("parameters")) {
    const Json& ps = doc["uncertainty"]["parameters"];
    if (ps.contains(name)) budget = &ps[name];
    else if (entry && entry->contains("iso") && ps.contains((*entry)["iso"].get<std::string>()))
      budget = &ps[(*entry)["iso"].get<std::string>()];
    else {
      // 000's parameters that 000 Table 1 names relative to the A axis are, in the per-axis
      // ISO 230-7 model, the C axis's own (docs/conventions.md).
      static const std::map<std::string, std::string> per_axis = {{"dx_AY", "X0C"}, {"dy_CA", "Y0C"}, {"b_CA", "B0C"}};
      const auto it = per_axis.find(name);
      if (it != per_axis.end() && ps.contains(it->second)) budget = &ps[it->second];
    }
  }
  if (!entry && budget) entry = budget;  // a parameter only the budget lists (one_sphere's squareness)
  if (!entry) return std::nullopt;
  auto number = [&](const char* key) -> std::optional<double> {
    if (entry->contains(key) && (*entry)[key].is_number()) return (*entry)[key].get<double>();
    if (budget && budget->contains(key) && (*budget)[key].is_number()) return (*budget)[key].get<double>();
    return std::nullopt;
  };
  const auto value = number("value"), U = number("U"), uc = number("u_c");
  if (!value || !U) return std::nullopt;
  return ValueU{*value, *U, uc.value_or(0.0)};
}

// The diagnosis' baseline adequacy test, where the cycle's document puts it.
const Json* baselineAdequacy(const Json& doc) {
  for (const Json* d : {&doc, doc.contains("judge") ? &doc["judge"] : nullptr})
    if (d && d->contains("baseline") && (*d)["baseline"].contains("adequacy")) return &(*d)["baseline"]["adequacy"];
  return nullptr;
}

// What the coverage is counted on: the location errors, then the linear axes' squareness where
// the report estimates it (one_sphere fits it), each with the drawn truth in report units.
struct Counted {
  std::string name, unit;
  std::function<double(const Drawn&)> truth;
  /// Where the report has it, when not where reported() looks (tooltip's angular errors by angle).
  std::function<std::optional<ValueU>(const Json&)> lookup;
};
// The drawn truth of one of 000's location errors by name, report units.
double truthOf(const ind::Machine& m, const std::string& name) {
  const auto& params = locationParameters(Kinematics::TableAC);
  for (size_t k = 0; k < params.size(); ++k)
    if (params[k].name == name) return m.location.reportValue(static_cast<int>(k));
  throw std::logic_error("no location error " + name);
}
std::vector<Counted> countedParameters(const std::string& cycle, const ProbePlan& plan) {
  std::vector<Counted> c;
  if (cycle == "tooltip") {
    // The pivot-length error and the stepping axis's angular error at each commanded angle
    // (REPORT.json angular_error[]; null where the screen left that angle's reading out).
    c.push_back({"dR", "um", [](const Drawn& d) { return 1e3 * d.head.dR_mm; }, nullptr});
    const char axis = plan.options.at("axis").at(0);
    std::vector<double> angles;
    for (const auto& p : plan.points) {
      const double a = axis == 'A' ? p.pose.A : p.pose.B;
      if (std::find(angles.begin(), angles.end(), a) == angles.end()) angles.push_back(a);
    }
    for (const double a : angles)
      c.push_back({fmt::format("e_{}{:g}", axis, a), "mdeg", [a](const Drawn& d) { return d.head.angularErrorMdeg(a); },
                   [a](const Json& doc) -> std::optional<ValueU> {
                     for (const auto& e : doc.value("angular_error", Json::array()))
                       if (std::abs(e.value("angle_deg", 1e9) - a) < 1e-9 && e.contains("value") && e["value"].is_number() &&
                           e.contains("U") && e["U"].is_number())
                         return ValueU{e["value"].get<double>(), e["U"].get<double>(), e.value("u_c", 0.0)};
                     return std::nullopt;
                   }});
    return c;
  }
  if (cycle == "rtest") {
    // The eight location errors the constant fit separates (REPORT.json location_errors), truth
    // the drawn table's; then the per-tilt errors of the first cycle (cycles[0].errors, what the
    // R-test measures at each tilt), truth the drawn table's in the reset's convention
    // (ind::perTiltTruth: dz and c at tilt 0 are 0 by convention, U 0, not counted).
    const auto& params = locationParameters(Kinematics::TableBC);
    for (size_t k = 0; k < params.size(); ++k)
      c.push_back({std::string(params[k].name), std::string(reportUnit(params[k].kind)),
                   [k](const Drawn& d) { return d.rt.location.reportValue(static_cast<int>(k)); }, nullptr});
    LocationErrors none;
    none.kinematics = Kinematics::TableBC;
    const ind::PerTiltTruth shape = ind::perTiltTruth(plan, ind::cleanRtestMachine(none));
    for (size_t i = 0; i < shape.tilt_deg.size(); ++i)
      for (int p = 0; p < kRtestParams; ++p) {
        if (shape.tilt_deg[i] == 0.0 && (p == 2 || p == 5)) continue;
        const std::string name = rtestParameterName(Kinematics::TableBC, p);
        const double tilt = shape.tilt_deg[i];
        c.push_back({fmt::format("{}@{:g}", name, tilt), p < 3 ? "um" : "mdeg",
                     [&plan, i, p](const Drawn& d) { return ind::perTiltTruth(plan, d.rt).value[i][static_cast<size_t>(p)]; },
                     [name, tilt](const Json& doc) -> std::optional<ValueU> {
                       if (!doc.contains("cycles") || doc["cycles"].empty()) return std::nullopt;
                       const Json& cy = doc["cycles"][0];
                       if (!cy.contains("errors") || !cy["errors"].contains(name)) return std::nullopt;
                       const Json& e = cy["errors"][name];
                       const Json tilts = doc.value("tilt_deg", Json::array());
                       for (size_t j = 0; j < tilts.size(); ++j)
                         if (std::abs(tilts[j].get<double>() - tilt) < 1e-9 && e.contains("U") && e["U"][j].is_number() &&
                             e["values"][j].is_number())
                           return ValueU{e["values"][j].get<double>(), e["U"][j].get<double>(),
                                         e.contains("u_c") ? e["u_c"][j].get<double>() : 0.0};
                       return std::nullopt;
                     }});
      }
    return c;
  }
  if (cycle == "probe_qual") {
    // The probe's own figures against what the generator drew: its pretravel along each approach
    // (squared direction cosines over +X -X +Y -Y +Z -Z), the horizontal ones less their first
    // harmonic (a centre offset: the fit puts it in the sphere's centre and reports the rest), the
    // top's as drawn, their mean; and the per-touch scatter (repeatability and roughness, both
    // along the approach in the report's weighted rows) against the repeatability's 95 % interval.
    const ProbeQualLayout l = probeQualLayoutOf(plan);
    const std::vector<Eigen::Vector3d> approaches = l.approaches();
    const int A = l.azimuths;
    const auto truths = [approaches, A](const Drawn& d) {
      std::vector<double> p(approaches.size(), 0.0);
      for (size_t a = 0; a < approaches.size(); ++a)
        for (int k = 0; k < 3; ++k)
          p[a] += approaches[a][k] * approaches[a][k] * d.m.pretravel_mm[static_cast<size_t>(2 * k + (approaches[a][k] < 0 ? 1 : 0))];
      Eigen::MatrixXd CS(A, 2);
      Eigen::VectorXd h(A);
      for (int a = 0; a < A; ++a) {
        const double th = std::atan2(approaches[static_cast<size_t>(a)].y(), approaches[static_cast<size_t>(a)].x());
        CS(a, 0) = std::cos(th), CS(a, 1) = std::sin(th);
        h[a] = p[static_cast<size_t>(a)];
      }
      const Eigen::VectorXd rest = h - CS * CS.colPivHouseholderQr().solve(h);
      for (int a = 0; a < A; ++a) p[static_cast<size_t>(a)] = 1e3 * rest[a];
      p.back() *= 1e3;
      return p;
    };
    c.push_back({"mean_pretravel", "um", [truths, A](const Drawn& d) {
                   const std::vector<double> p = truths(d);
                   return std::accumulate(p.begin(), p.begin() + A, 0.0) / A;
                 },
                 [](const Json& doc) -> std::optional<ValueU> {
                   if (!doc.contains("mean_pretravel") || !doc["mean_pretravel"].contains("U")) return std::nullopt;
                   const Json& e = doc["mean_pretravel"];
                   return ValueU{e["value"].get<double>(), e["U"].get<double>(), e.value("u_c", 0.0)};
                 }});
    const std::vector<std::string> names = l.approachNames();
    for (size_t a = 0; a < approaches.size(); ++a)
      c.push_back({"pretravel " + names[a], "um", [truths, a](const Drawn& d) { return truths(d)[a]; },
                   [a](const Json& doc) -> std::optional<ValueU> {
                     const Json dirs = doc.value("pretravel_by_direction", Json::array());
                     if (a >= dirs.size() || !dirs[a].contains("U")) return std::nullopt;
                     return ValueU{dirs[a]["pretravel"].get<double>(), dirs[a]["U"].get<double>(), dirs[a].value("u_c", 0.0)};
                   }});
    // "within U": the drawn scatter inside the 95 % interval (value = its middle, U = its half-width).
    // The report's repeatability is along the approach: the probe's scatter is drawn there, the
    // roughness as a height along the contact normal, which a horizontal approach above the
    // equator reads as h / |n . u|; pooled over one repeat's touches (each has the same repeats).
    double mean_w2 = 0.0;
    for (const auto& t : l.touches()) mean_w2 += 1.0 / std::pow(t.n.dot(approaches[static_cast<size_t>(t.approach)]), 2);
    mean_w2 /= static_cast<double>(l.touches().size());
    c.push_back({"repeatability (95 % interval)", "um",
                 [mean_w2](const Drawn& d) {
                   return 1e3 * std::sqrt(d.m.repeatability_mm * d.m.repeatability_mm + mean_w2 * d.m.roughness_mm * d.m.roughness_mm);
                 },
                 [](const Json& doc) -> std::optional<ValueU> {
                   if (!doc.contains("repeatability") || !doc["repeatability"].contains("interval_95")) return std::nullopt;
                   const double lo = doc["repeatability"]["interval_95"][0].get<double>(),
                                hi = doc["repeatability"]["interval_95"][1].get<double>();
                   return ValueU{(lo + hi) / 2, (hi - lo) / 2, 0.0};
                 }});
    return c;
  }
  if (cycle == "spheres3") {
    // spheres3 reports the C axis's location (001 Table 1); on this A/C machine at A = 0 it is
    // 000's chain to first order (cycles/spheres3/analyze.hpp, docs/e2e-linuxcnc.md's comp_table):
    // Oxc = dx_AY, Oyc = dy_AY + dy_CA, Sxc = a_AY, Syc = b_AY + b_CA.
    c.push_back({"Oxc", "um", [](const Drawn& d) { return truthOf(d.m, "dx_AY"); }, nullptr});
    c.push_back({"Oyc", "um", [](const Drawn& d) { return truthOf(d.m, "dy_AY") + truthOf(d.m, "dy_CA"); }, nullptr});
    c.push_back({"Sxc", "mdeg", [](const Drawn& d) { return truthOf(d.m, "a_AY"); }, nullptr});
    c.push_back({"Syc", "mdeg", [](const Drawn& d) { return truthOf(d.m, "b_AY") + truthOf(d.m, "b_CA"); }, nullptr});
    return c;
  }
  const auto& params = locationParameters(Kinematics::TableAC);
  for (size_t k = 0; k < params.size(); ++k)
    c.push_back({std::string(params[k].name), std::string(reportUnit(params[k].kind)),
                 [k](const Drawn& d) { return d.m.location.reportValue(static_cast<int>(k)); }, nullptr});
  // A squareness S (mm/mm) is reported as the small angle it is, in mdeg.
  const double mdeg = 180.0 / 3.14159265358979323846 * 1e3;
  c.push_back({"S_xy", "mdeg", [mdeg](const Drawn& d) { return d.m.axes.S_xy * mdeg; }, nullptr});
  c.push_back({"S_xz", "mdeg", [mdeg](const Drawn& d) { return d.m.axes.S_xz * mdeg; }, nullptr});
  c.push_back({"S_yz", "mdeg", [mdeg](const Drawn& d) { return d.m.axes.S_yz * mdeg; }, nullptr});
  return c;
}

void writeFile(const std::string& dir, const std::string& name, const std::string& text) {
  std::filesystem::create_directories(dir);
  std::ofstream(std::filesystem::path(dir) / name, std::ios::binary) << text;
}

// The drawn truth as TRUTH.json (rotacal-truth/1) plus what the generator drew beside it.
Json truthJson(const ind::Machine& m) {
  Json le = Json::object();
  const auto& params = locationParameters(Kinematics::TableAC);
  for (size_t k = 0; k < params.size(); ++k)
    le[std::string(params[k].name)] = {{"value", m.location.reportValue(static_cast<int>(k))},
                                       {"unit", std::string(reportUnit(params[k].kind))}};
  return {{"format", "rotacal-truth/1"},
          {"_comment", "drawn by bench/independent_machine (rotacal_real_machine_bench --dump)"},
          {"location_errors", le},
          {"independent_generator",
           {{"setup_translation_um", {1e3 * m.setup_translation_mm.x(), 1e3 * m.setup_translation_mm.y(), 1e3 * m.setup_translation_mm.z()}},
            {"setup_rotation_urad", {1e6 * m.setup_rotation_rad.x(), 1e6 * m.setup_rotation_rad.y(), 1e6 * m.setup_rotation_rad.z()}},
            {"squareness_um_per_m", {{"S_xy", 1e6 * m.axes.S_xy}, {"S_xz", 1e6 * m.axes.S_xz}, {"S_yz", 1e6 * m.axes.S_yz}}},
            {"scale_um_per_m", {1e6 * m.axes.scale[0], 1e6 * m.axes.scale[1], 1e6 * m.axes.scale[2]}},
            {"node_spacing_mm", {m.axes.spacing_mm[0], m.axes.spacing_mm[1], m.axes.spacing_mm[2]}}}}};
}

// A drawn R-test machine as TRUTH.json (rotacal-truth/1: the location errors) plus what the
// generator drew beside it.
Json rtestTruthJson(const ind::RtestMachine& m) {
  Json le = Json::object();
  const auto& params = locationParameters(Kinematics::TableBC);
  for (size_t k = 0; k < params.size(); ++k)
    le[std::string(params[k].name)] = {{"value", m.location.reportValue(static_cast<int>(k))},
                                       {"unit", std::string(reportUnit(params[k].kind))}};
  const Eigen::Vector3d s = 1e3 * m.sphere_offset_mm, v = 3.6e6 * m.drift_mm_per_s;
  return {{"format", "rotacal-truth/1"},
          {"_comment", "drawn by bench/independent_rtest (rotacal_real_machine_bench --dump)"},
          {"location_errors", le},
          {"independent_generator",
           {{"sphere_offset_um", {s.x(), s.y(), s.z()}},
            {"drift_um_per_h", {v.x(), v.y(), v.z()}},
            {"sensor_gain_ppm", {1e6 * m.gain[0], 1e6 * m.gain[1], 1e6 * m.gain[2]}},
            {"sensor_direction_urad_xy_xz_yx_yz_zx_zy",
             {1e6 * m.direction[0], 1e6 * m.direction[1], 1e6 * m.direction[2], 1e6 * m.direction[3], 1e6 * m.direction[4],
              1e6 * m.direction[5]}},
            {"per_reading_um", {1e3 * m.sensor_noise_mm, 1e3 * m.sphere_form_mm}},
            {"node_spacing_mm", {m.axes.spacing_mm[0], m.axes.spacing_mm[1], m.axes.spacing_mm[2]}}}}};
}

// A drawn head as TRUTH.json's tooltip object (docs/tooltip.md) plus what the generator drew beside it.
Json headTruthJson(const ind::Head& h) {
  return {{"format", "rotacal-truth/1"},
          {"_comment", "drawn by bench/independent_machine (rotacal_real_machine_bench --dump)"},
          {"tooltip",
           {{"dR_um", 1e3 * h.dR_mm},
            {"angular_error", {{"offset_mdeg", h.angular_mdeg[0]}, {"slope_mdeg_per_90deg", h.angular_mdeg[1]},
                               {"sin_mdeg", h.angular_mdeg[2]}, {"sin2_mdeg", h.angular_mdeg[3]}}}}},
          {"independent_generator",
           {{"beam_tilt_urad", {1e6 * h.beam_tilt_rad[0], 1e6 * h.beam_tilt_rad[1], 1e6 * h.beam_tilt_rad[2], 1e6 * h.beam_tilt_rad[3]}},
            {"node_spacing_mm", {h.axes.spacing_mm[0], h.axes.spacing_mm[1], h.axes.spacing_mm[2]}},
            {"per_reading_um", {1e3 * h.laser_resolution_mm, 1e3 * h.sphere_form_mm, 1e3 * h.lateral_coupling_mm}}}}};
}

double pct(int k, int n) { return n > 0 ? 100.0 * k / n : 0.0; }

struct Quantiles {
  std::vector<double> v;
  void add(double x) { v.push_back(x); }
  std::string text(int digits) const {
    if (v.empty()) return "-";
    std::vector<double> s = v;
    std::sort(s.begin(), s.end());
    auto q = [&](double p) { return s[static_cast<size_t>(p * static_cast<double>(s.size() - 1) + 0.5)]; };
    return fmt::format("median {:.{}f} (min {:.{}f}, 90 % {:.{}f}, max {:.{}f}; {} machines)", q(0.5), digits, s.front(),
                       digits, q(0.9), digits, s.back(), digits, s.size());
  }
};

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  const auto t0 = std::chrono::steady_clock::now();
  // The cycle's bundled example: its machine and options (spaceframe's: ac_trunnion.json with
  // phi_list=-90,-45,0), unless --machine names another (then no options, as before).
  const CycleExample example = cycleByName(args.cycle).example();
  const std::string machine_file =
      args.machine.empty() ? std::string(ROTACAL_SOURCE_DIR) + "/" + example.machine : args.machine;
  const MachineModel machine = loadMachine(machine_file);
  const ContributorSet contrib =
      !args.contributors.empty() ? loadContributors(args.contributors)
      : machine.contributors     ? *machine.contributors
                                 : loadContributors(std::string(ROTACAL_SOURCE_DIR) + "/examples/contributors/table5.json");
  CycleOptions plan_options = args.machine.empty() ? example.options : CycleOptions{};
  if (args.runs > 0) plan_options["repeats"] = std::to_string(args.runs);
  const ProbePlan plan = makePlan(args.cycle, machine, plan_options);
  // tooltip's program repeats the plan (its `repeats`); every other cycle's is one run here.
  const int runs = plan.options.count("repeats") && plan.cycle == "tooltip" ? std::stoi(plan.options.at("repeats")) : 1;
  const Cycle& cycle = cycleOfPlan(plan);
  const Dialect& dialect = dialectByName(args.dialect);
  const DialectIO io = dialectIO(dialect);

  ind::DrawOptions draw;
  ind::HeadDrawOptions head_draw;
  ind::RtestDrawOptions rtest_draw;
  draw.sd_um = args.sd_um;
  draw.sd_mdeg = args.sd_mdeg;
  for (size_t b = 0, e; b <= args.off.size() && !args.off.empty(); b = e + 1) {
    e = std::min(args.off.find(',', b), args.off.size());
    const std::string w = args.off.substr(b, e - b);
    bool* flag = w == "setup" ? &draw.setup
                 : w == "form" ? &draw.form
                 : w == "sphere" ? &rtest_draw.sphere
                 : w == "sensors" ? &rtest_draw.sensors
                 : w == "drift" ? &rtest_draw.drift
                 : w == "noise" ? &rtest_draw.noise
                 : w == "linear_axes" ? &draw.linear_axes
                 : w == "pretravel" ? &draw.pretravel
                 : w == "repeatability" ? &draw.repeatability
                 : w == "roughness" ? &draw.roughness
                 : w == "alignment" ? &head_draw.alignment
                 : w == "laser" ? &head_draw.per_reading
                 : w == "pivot" ? &head_draw.pivot
                 : nullptr;
    if (w == "linear_axes") head_draw.linear_axes = rtest_draw.linear_axes = false;
    if (w == "form") rtest_draw.form = false;
    if (!flag) usage(("--off: unknown contributor " + w).c_str());
    *flag = false;
  }

  const bool tooltip = plan.cycle == "tooltip";
  const bool rtest = plan.cycle == "rtest";
  rtest_draw.sd_um = args.sd_um;
  rtest_draw.sd_mdeg = args.sd_mdeg;
  // The results text of a drawn machine, with a chip of `mm` under point `id` (0: none) in run
  // `chip_run`: the probing cycles' triggers through the dialect's results writer, tooltip's laser
  // readings of every run through its neutral CSV writer, one file (what `simulate` writes). A
  // tooltip run is the same head read again: its own per-reading draws (a new zero and scatter),
  // run 0 the head's own so that a plan of one run is the single-run bench.
  const auto resultsText = [&](const Drawn& d, int id, bool chip_z, int chip_axis, double mm, int chip_run) -> std::string {
    // The R-test: one sensor's value at one pose of the first cycle off by the chip's size (the
    // reset and re-read rows are the re-read check's, not the screen's: docs/rtest.md).
    if (rtest)
      return rtestResultsCsv(plan, ind::measureRtest(plan, d.rt, id ? std::optional<ind::RtestChip>(ind::RtestChip{0, id, chip_axis, mm})
                                                                    : std::nullopt));
    if (tooltip) {
      std::vector<TooltipRun> read;
      for (int r = 0; r < runs; ++r) {
        auto head = d.head;
        head.reading_seed = d.head.reading_seed + 1000003ULL * static_cast<std::uint64_t>(r);
        const bool chipped = id && r == chip_run;
        read.push_back(ind::measureHead(plan, head, chipped ? std::optional<ind::ReadingChip>(ind::ReadingChip{id, chip_z, mm})
                                                            : std::nullopt));
      }
      return tooltipResultsText(plan, read);
    }
    return dialect.writeResults(plan, ind::measure(plan, d.m, id ? std::optional<ind::Chip>(ind::Chip{id, mm}) : std::nullopt));
  };
  const auto resultsOf = [&](const Drawn& d, int id, bool chip_z, int chip_axis, double mm, int chip_run) {
    return std::vector<std::string>{resultsText(d, id, chip_z, chip_axis, mm, chip_run)};
  };
  std::vector<int> chip_points;
  for (const auto& p : plan.points)
    if (!tooltip || std::abs(plan.options.at("axis") == "A" ? p.pose.A : p.pose.B) > 1e-9) chip_points.push_back(p.id);

  int analyze_finding = 0;
  int n = 0, analyzed = 0, not_held_back = 0, written = 0, screen_removed = 0, screen_gave_up = 0, diagnosed = 0, inadequate = 0,
      named = 0, no_effect = 0;
  std::map<std::string, int> causes, refusals;
  struct ChipTally {
    int n = 0, caught = 0, written = 0, written_from_chip = 0, gave_up = 0;
    int isolated = 0;       // the chip's touch and nothing else left out
    int returned = 0;       // analyze returned (a REPORT.json)
    int returned_with = 0;  // ... with the chip's touch in the fit
    int handed_on = 0;      // ... and nothing held back: the chip reaches what the cycle hands on
    int refused = 0;        // analyze refused the data
    // Coverage of U on the analyses with the chip left out (what a report of such data claims).
    std::vector<int> in_U, counted;
    // By the screen's stated reach at the chip's value (the chip-free REPORT.json's
    // outliers.reach): at most the chip's size (caught 8 times in 10 or more, it claims), beyond
    // it, and unseen at any size.
    int within = 0, caught_within = 0, beyond = 0, caught_beyond = 0, unseen = 0, caught_unseen = 0;
  };
  ChipTally chip20, chip1mm;
  const std::vector<Counted> cover = countedParameters(args.cycle, plan);
  std::vector<int> in_U(cover.size(), 0), in_uc(cover.size(), 0), counted(cover.size(), 0);
  std::vector<double> err2(cover.size(), 0.0), U2(cover.size(), 0.0);
  Quantiles beyond, removed_count, chi2_dof, excess_rms, residual_rms, threshold;
  std::map<std::string, int> top_factor;

  for (int i = 0; i < args.machines; ++i) {
    const std::uint64_t seed = args.seed + static_cast<std::uint64_t>(i);
    Drawn drawn;
    if (tooltip) drawn.head = ind::drawHead(contrib, machine, head_draw, seed);
    else if (rtest) drawn.rt = ind::drawRtestMachine(contrib, plan, rtest_draw, seed);
    else drawn.m = ind::drawMachine(contrib, machine, draw, seed);
    const ind::Machine& m = drawn.m;
    ++n;
    const std::vector<std::string> clean = resultsOf(drawn, 0, false, 0, 0.0, 0);
    const Analyzed a = analyze(cycle, plan, dialect, io, contrib, clean, args, seed);
    const bool dump = i == 0 && !args.dump.empty();
    if (dump) {
      writeFile(args.dump, "PLAN.json", planToJson(plan).dump(1) + "\n");
      for (size_t r = 0; r < clean.size(); ++r) writeFile(args.dump, resultsName(plan, dialect, static_cast<int>(r)), clean[r]);
      writeFile(args.dump, "TRUTH.json",
                (tooltip ? headTruthJson(drawn.head) : rtest ? rtestTruthJson(drawn.rt) : truthJson(m)).dump(1) + "\n");
      writeFile(args.dump, "REPORT.json", a.doc.dump(1) + "\n");
    }
    if (!a.ok) {
      ++refusals["analyze refused: " + a.error.substr(0, 80)];
    } else {
      ++analyzed;
      not_held_back += !a.held_back;
      analyze_finding += a.finding;
      if (a.written) ++written;
      else ++refusals[a.refused.substr(0, std::min<size_t>(a.refused.find(':') == std::string::npos ? 60 : a.refused.find(':'), 60))];
      if (!a.excluded.empty()) {
        ++screen_removed;
        removed_count.add(static_cast<double>(a.excluded.size()));
      }
      if (a.too_many) {
        ++screen_gave_up;
        beyond.add(a.beyond);
      }
      if (a.doc.contains("outliers")) threshold.add(a.threshold_t);
      for (size_t k = 0; k < cover.size(); ++k) {
        const auto v = cover[k].lookup ? cover[k].lookup(a.doc) : reported(a.doc, cover[k].name);
        if (!v) continue;
        const double e = std::abs(v->value - cover[k].truth(drawn));
        ++counted[k];
        in_U[k] += e <= v->U;
        in_uc[k] += e <= v->u_c;
        err2[k] += e * e;
        U2[k] += v->U * v->U;
      }
    }

    DiagnoseRequest dr;
    dr.plan = &plan;
    for (size_t r = 0; r < clean.size(); ++r) dr.results.push_back({resultsName(plan, dialect, static_cast<int>(r)), clean[r]});
    dr.dialect = &io;
    dr.contributors = &contrib;  // as `diagnose` reads the machine's (or --contributors)
    std::string verdict = "refused";
    try {
      const CycleDocuments dg = cycle.diagnose(dr);
      if (dump) writeFile(args.dump, "DIAGNOSIS.json", dg.doc.dump(1) + "\n");
      ++diagnosed;
      verdict = dg.doc.value("verdict", std::string("?"));
      if (verdict == "model_inadequate") ++inadequate;
      if (verdict == "no_significant_effect") ++no_effect;
      const Json findings = dg.doc.value("findings", Json::array());
      if (!findings.empty()) ++named;
      for (const auto& f : findings) ++causes[f.value("cause", std::string("?"))];
      if (const Json* adequacy = baselineAdequacy(dg.doc)) {
        const Json& ad = *adequacy;
        const double dof = ad.value("dof", 0.0);
        if (dof > 0) chi2_dof.add(ad.value("chi2", 0.0) / dof);
        excess_rms.add(ad.value("excess_rms", 0.0));
        residual_rms.add(ad.value("rms_residual", 0.0));
        double best = -1;
        std::string who;
        for (const auto& f : ad.value("factors", Json::array()))
          if (f.value("share", 0.0) > best) best = f.value("share", 0.0), who = f.value("factor", std::string("?"));
        if (!who.empty()) ++top_factor[who];
      }
    } catch (const std::exception& e) {
      ++refusals["diagnose refused: " + std::string(e.what()).substr(0, 80)];
    }

    std::string chip_line;
    if (args.chips) {
      // The chip's touch: one of the plan's, drawn from the machine's own seed.
      std::mt19937_64 pick(seed ^ 0x9e3779b97f4a7c15ULL);
      // On tooltip: a reading off by the chip's size along one beam (transverse or Z, drawn
      // next), at a pose other than its sweep's zero (there the laser is zeroed: a chip would
      // move every later reading of the sweep, not one).
      const std::vector<int>& candidates = chip_points;
      const int id = candidates[std::uniform_int_distribution<size_t>(0, candidates.size() - 1)(pick)];
      const bool chip_z = std::uniform_int_distribution<int>(0, 1)(pick) == 1;
      // The R-test's chip: one of the three sensors (drawn after the others' draws, which stay).
      const int chip_axis = std::uniform_int_distribution<int>(0, 2)(pick);
      const int key = rtest ? 3 * id + chip_axis : id;  // what the screen's excluded list names
      // With repeats, the run the chip is in (drawn after the others, which stay).
      const int chip_run = runs > 1 ? std::uniform_int_distribution<int>(0, runs - 1)(pick) : 0;
      // How the report names the chip's value beside its point: tooltip's beam, the R-test's sensor.
      const std::string reachSuffix = tooltip ? fmt::format(" d{}", chip_z ? 'z' : (plan.options.at("axis") == "A" ? 'y' : 'x'))
                                      : rtest ? fmt::format(" d{}", "xyz"[chip_axis])
                                              : std::string();
      for (auto [height_mm, tally] : {std::pair{0.020, &chip20}, std::pair{1.0, &chip1mm}}) {
        const std::vector<std::string> chipped = resultsOf(drawn, id, chip_z, chip_axis, height_mm, chip_run);
        const Analyzed c = analyze(cycle, plan, dialect, io, contrib, chipped, args, seed);
        ++tally->n;
        bool caught = false;
        for (size_t x = 0; x < c.excluded.size(); ++x)
          caught = caught || (c.excluded[x] == key && (runs == 1 || c.excluded_run[x] == chip_run + 1));
        tally->caught += caught;
        if (const std::optional<double> r = statedReach(a.doc, chip_run + 1, id, reachSuffix)) {
          const bool unseen = !std::isfinite(*r), within = !unseen && *r <= height_mm * 1e3;
          tally->unseen += unseen, tally->caught_unseen += unseen && caught;
          tally->within += within, tally->caught_within += within && caught;
          tally->beyond += !unseen && !within, tally->caught_beyond += !unseen && !within && caught;
        }
        tally->written += c.written;
        tally->written_from_chip += c.written && !caught;
        tally->gave_up += c.too_many;
        tally->isolated += caught && c.excluded.size() == 1;
        tally->returned += c.ok;
        tally->returned_with += c.ok && !caught;
        tally->handed_on += c.ok && !caught && !c.held_back;
        tally->refused += !c.ok;
        if (c.ok && caught) {
          tally->in_U.resize(cover.size(), 0);
          tally->counted.resize(cover.size(), 0);
          for (size_t k = 0; k < cover.size(); ++k)
            if (const auto v = cover[k].lookup ? cover[k].lookup(c.doc) : reported(c.doc, cover[k].name)) {
              ++tally->counted[k];
              tally->in_U[k] += std::abs(v->value - cover[k].truth(drawn)) <= v->U;
            }
        }
        if (!c.written)
          ++refusals[fmt::format("{:g} um chip: ", height_mm * 1e3) +
                     (c.ok ? c.refused.substr(0, std::min<size_t>(c.refused.find(':'), 60)) : "analyze refused: " + c.error.substr(0, 80))];
        chip_line += fmt::format(" chip {:g} um at {}{}{}: {}{}{}", height_mm * 1e3, id,
                                 runs > 1 ? fmt::format(" run {}", chip_run + 1) : std::string(),
                                 tooltip ? (chip_z ? " (dz)" : " (dt)") : rtest ? fmt::format(" (d{})", "xyz"[chip_axis]) : "", caught ? "caught" : "missed",
                                 caught && c.excluded.size() > 1 ? fmt::format(" ({} left out)", c.excluded.size()) : "",
                                 c.written ? (caught ? ", written" : ", WRITTEN")
                                 : c.ok    ? (caught ? ", analyzed" : c.held_back ? ", ANALYZED (held back)" : ", ANALYZED")
                                           : ", refused");
      }
    }
    if (args.verbose || (i + 1) % 20 == 0)
      std::fprintf(stderr, "machine %d/%d (seed %llu): offsets %s%s, screen %s, diagnose %s;%s  [%.0f s]\n", i + 1,
                   args.machines, static_cast<unsigned long long>(seed),
                   a.ok ? (a.written ? "written" : "refused") : "analyze refused", a.finding ? " (REPORT.json names a finding)" : "",
                   a.too_many ? fmt::format("gave up ({} beyond {:.2f})", a.beyond, a.threshold_t).c_str()
                              : fmt::format("{} removed", a.excluded.size()).c_str(),
                   verdict.c_str(), chip_line.c_str(),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::string options;
  for (const auto& [k, v] : plan_options) options += " --set " + k + "=" + v;
  std::printf("rotacal_real_machine_bench: %s (%zu touches) on %s%s, contributors %s, dialect %s\n", args.cycle.c_str(),
              plan.points.size(), machine_file.c_str(), options.c_str(),
              contrib.file.empty() ? "(the machine's, inline)" : contrib.file.c_str(), args.dialect.c_str());
  if (!args.off.empty()) std::printf("switched off in the generator: %s\n", args.off.c_str());
  if (runs > 1)
    std::printf("%d runs of the plan per machine (the same head and axes, a new laser zero and scatter each), analyzed and "
                "diagnosed as repeats (one results file); a chip is in one reading of one run\n",
                runs);
  const std::string around =
      tooltip ? fmt::format("a head with dR around {:g} um (sd {:g} um) and angular-error coefficients around {:g}, {:g}, {:g}, "
                            "{:g} mdeg (sd {:g} mdeg)",
                            head_draw.dR_um, head_draw.sd_dR_um, head_draw.angular_mdeg[0], head_draw.angular_mdeg[1],
                            head_draw.angular_mdeg[2], head_draw.angular_mdeg[3], head_draw.sd_mdeg)
      : rtest ? fmt::format("B/C location errors around examples/truth/bc_location.json (sd {:g} um, {:g} mdeg)", args.sd_um,
                            args.sd_mdeg)
              : fmt::format("location errors around 000 Table 4 (sd {:g} um, {:g} mdeg)", args.sd_um, args.sd_mdeg);
  std::printf("%d machines (seeds %llu..%llu), %s, analyze's Monte Carlo %d runs; %.0f s (%.1f s per machine)\n\n", n,
              static_cast<unsigned long long>(args.seed), static_cast<unsigned long long>(args.seed + n - 1), around.c_str(),
              args.mc_runs, seconds, seconds / n);
  if (analyzed < n || diagnosed < n)
    std::printf("analyze returned on %d of %d machines, diagnose on %d (the others refused the data: listed below)\n\n",
                analyzed, n, diagnosed);
  std::printf("| figure | machines | %% | issue's target |\n|---|---|---|---|\n");
  auto row = [&](const char* what, int k, int of, const char* target) {
    std::printf("| %s | %d / %d | %.1f %% | %s |\n", what, k, of, pct(k, of), target);
  };
  row("offsets written (`analyze --offsets`, no --force)", written, n, ">= 99 %");
  // A cycle that writes no offsets (spheres3, spaceframe, tooltip, rtest): what it would hand on
  // is its report's values, held back when the data exceed the declaration.
  row("analyze returned, nothing held back (no `corrections_held_back`)", not_held_back, n, "");
  row("analyze: REPORT.json names a finding (rtest: the re-read check's sensor_step)", analyze_finding, n, "");
  row("`diagnose`: model_inadequate", inadequate, n, "<= 5 %");
  row("`diagnose`: a cause named", named, n, "<= 2 %");
  row("`diagnose`: no_significant_effect", no_effect, n, "");
  row("outlier screen removed >= 1 touch (chip-free)", screen_removed, n, "<= 1 % (its alpha)");
  row("outlier screen gave up (too many beyond; offsets refused)", screen_gave_up, n, "");
  if (args.chips) {
    row("20 um chip caught (its touch excluded)", chip20.caught, chip20.n, ">= 95 %");
    row("20 um chip: offsets written", chip20.written, chip20.n, "");
    row("20 um chip: offsets written with the chip in the fit", chip20.written_from_chip, chip20.n, "0");
    row("1 mm chip caught", chip1mm.caught, chip1mm.n, "100 %");
    row("1 mm chip: offsets written", chip1mm.written, chip1mm.n, "");
    row("1 mm chip: offsets written with the chip in the fit", chip1mm.written_from_chip, chip1mm.n, "0");
    // Where a cycle writes no offsets (spheres3), what reaches an output is the report itself.
    row("20 um chip: the chip's touch alone left out", chip20.isolated, chip20.n, "");
    row("20 um chip: analyzed (a report) with the chip in the fit", chip20.returned_with, chip20.n, "0");
    row("20 um chip: analyzed with the chip in the fit, nothing held back", chip20.handed_on, chip20.n, "0");
    row("20 um chip: analyze refused the data", chip20.refused, chip20.n, "");
    row("1 mm chip: the chip's touch alone left out", chip1mm.isolated, chip1mm.n, "");
    row("1 mm chip: analyzed (a report) with the chip in the fit", chip1mm.returned_with, chip1mm.n, "0");
    row("1 mm chip: analyzed with the chip in the fit, nothing held back", chip1mm.handed_on, chip1mm.n, "0");
    row("1 mm chip: analyze refused the data", chip1mm.refused, chip1mm.n, "");
    for (auto [what, tally] : {std::pair{"20 um", &chip20}, std::pair{"1 mm", &chip1mm}}) {
      row(fmt::format("{} chip: caught, where the clean report's reach there is <= its size", what).c_str(), tally->caught_within,
          tally->within, ">= 80 % (the reach's claim)");
      row(fmt::format("{} chip: caught, where the reach is beyond its size", what).c_str(), tally->caught_beyond, tally->beyond, "");
      row(fmt::format("{} chip: caught, where the report says the screen cannot see it", what).c_str(), tally->caught_unseen,
          tally->unseen, "");
    }
  }
  std::printf("\nCoverage of analyze's U (chip-free machines; truth = the drawn location errors):\n\n");
  std::printf("| parameter | within U | within u_c | rms error | rms U | unit |\n|---|---|---|---|---|---|\n");
  for (size_t k = 0; k < cover.size(); ++k)
    if (counted[k] > 0)
      std::printf("| %s | %.1f %% | %.1f %% | %.3f | %.3f | %s |\n", cover[k].name.c_str(), pct(in_U[k], counted[k]),
                  pct(in_uc[k], counted[k]), std::sqrt(err2[k] / counted[k]), std::sqrt(U2[k] / counted[k]),
                  cover[k].unit.c_str());
  if (args.chips)
    for (auto [what, tally] : {std::pair{"20 um", &chip20}, std::pair{"1 mm", &chip1mm}})
      for (size_t k = 0; k < tally->counted.size(); ++k)
        if (tally->counted[k] > 0)
          std::printf("- %s chip left out, analyzed: %s within U on %d of %d (%.1f %%)\n", what, cover[k].name.c_str(),
                      tally->in_U[k], tally->counted[k], pct(tally->in_U[k], tally->counted[k]));
  std::printf("\nWhat fires (chip-free machines):\n");
  std::printf("- outlier screen threshold |t|: %s\n",
              threshold.v.empty() ? "no outlier screen in this cycle's analyze" : threshold.text(2).c_str());
  std::printf("- touches beyond it when the screen gave up: %s\n", beyond.text(0).c_str());
  std::printf("- touches removed when it did not: %s\n", removed_count.text(0).c_str());
  std::printf("- diagnose baseline chi2 / dof: %s\n", chi2_dof.text(2).c_str());
  std::printf("- diagnose baseline rms residual (um): %s\n", residual_rms.text(2).c_str());
  std::printf("- diagnose baseline excess rms over the declared noise (um): %s\n", excess_rms.text(2).c_str());
  for (const auto& [f, k] : top_factor) std::printf("- adequacy factor carrying the largest share: %s on %d machines\n", f.c_str(), k);
  for (const auto& [c, k] : causes) std::printf("- cause named: %s on %d machines\n", c.c_str(), k);
  for (const auto& [r, k] : refusals) std::printf("- not written / refused: \"%s\" on %d machines\n", r.c_str(), k);
  return 0;
}
