#pragma once
// A measuring cycle: everything a verb of the command line needs from it, behind one interface.
// The CLI looks a cycle up by name (`plan --cycle`) or by a plan's `cycle` field and never tests
// a cycle name itself; cycles/registry.cpp is the only list of cycles. A cycle never includes
// controllers/: the CLI hands it the dialect's results reader and writer (DialectIO) and writes
// the offsets a cycle returns with the dialect's own writer.
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/contributors.hpp"
#include "core/errors.hpp"
#include "core/error_model.hpp"
#include "core/json_io.hpp"
#include "core/judge.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"
#include "gcode/program.hpp"

namespace rotacal {

/// The dialect the user named, as a cycle may use it: what the controller writes back for a
/// plan and how to read it. Touch cycles read and write through it; cycles whose results come
/// from another device (an R-test logger, a laser) read their own format and ignore it.
struct DialectIO {
  std::string name;
  std::function<MeasurementRun(const std::string& text, const std::string& file, const ProbePlan& plan)> read_results;
  std::function<std::string(const ProbePlan& plan, const MeasurementRun& run)> write_results;
};

/// A file named on the command line, read by the CLI (cycles stay pure functions of text).
struct InputFile {
  std::string path;
  std::string text;
};

/// The files' paths, in order (the reports name the results files they were drawn from).
inline std::vector<std::string> pathsOf(const std::vector<InputFile>& files) {
  std::vector<std::string> p;
  for (const auto& f : files) p.push_back(f.path);
  return p;
}

struct SimulateRequest {
  const ProbePlan* plan = nullptr;
  InputFile truth;                   // TRUTH.json
  std::optional<double> noise_um;    // --noise-um: overrides the truth file's noise
  std::optional<double> start_s;     // --start-s: clock at the cycle start, for repeats
  std::uint64_t seed = 1;
  const DialectIO* dialect = nullptr;
  /// --contributors: a whole machine drawn from these declared contributors (machine_seed) on
  /// top of the truth file (core/contributor_draw.hpp drawMachine); null: the truth file alone.
  const ContributorSet* contributors = nullptr;
  std::uint64_t machine_seed = 1;
};

/// `simulate()` run on what a truth file declares: a refusal of the simulation becomes an
/// InputError naming the truth file (line 0: the file as a whole), the rule of every cycle's
/// `simulate`; an InputError already naming a file passes through.
template <class F>
auto onTruthFile(const InputFile& truth, F&& simulate) -> decltype(simulate()) {
  try {
    return simulate();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(truth.path, 0, e.what());
  }
}

struct Simulated {
  std::string results_text;  // what the controller (or device) writes
  std::string message;       // one line for the terminal, without the output path
  /// The truth simulated, with what was drawn from the contributors (`drawn`); null when the
  /// cycle's simulator draws no machine (the CLI then refuses --contributors).
  Json truth;
  /// What the simulated machine carries that analyze reports, by the report's own keys and
  /// names, in its units: {"location_errors": {"dx_AY": 14.6, ...}, "mean_pretravel": 0.5}. A test
  /// compares a report with it; a key the report does not state is not compared.
  Json injected = Json::object();
};

struct AnalyzeRequest {
  const ProbePlan* plan = nullptr;
  std::vector<InputFile> results;  // repeats of the plan, in time order
  const DialectIO* dialect = nullptr;
  std::string method;              // "" = the cycle's default; one of Cycle::methods()
  /// The Type B contributors (--contributors, else the machine's); null: none declared,
  /// and the report says u_B was not evaluated.
  const ContributorSet* contributors = nullptr;
  int mc_runs = 2000;              // Monte Carlo runs of u_B
  std::uint64_t mc_seed = 1;
};

struct DiagnoseRequest {
  const ProbePlan* plan = nullptr;
  std::vector<InputFile> results;
  const DialectIO* dialect = nullptr;
  double alpha = JudgeOptions{}.alpha;  // family-wise false-alarm rate (docs/diagnosis.md), validated by the CLI
  /// The declared contributors the tests read (--contributors, else the machine's), as analyze's;
  /// null: the probe's repeatability alone is declared, and the diagnosis says so.
  const ContributorSet* contributors = nullptr;
  std::function<void(int done, int all)> progress;  // may be empty
};

/// A cycle's refusal of one command-line option's value: the CLI reports it as a usage error
/// (exit 2) naming the option, as it does for the options it checks itself.
struct OptionError : std::invalid_argument {
  OptionError(std::string option_name, const std::string& what) : std::invalid_argument(what), option(std::move(option_name)) {}
  std::string option;
};

/// `rotacal uncertainty`: the Monte Carlo of a cycle's calibration chain (000 Sec. 5) for its
/// plan and the declared contributors.
struct UncertaintyRequest {
  const ProbePlan* plan = nullptr;
  std::string plan_file;                 // named in the document
  const ContributorSet* contributors = nullptr;
  int runs = 1000;
  std::uint64_t seed = 1;
  bool combined_only = false;
  bool exact = false;
  int threads = 0;                       // 0: all cores
  std::string methods;                   // comma-separated estimator names; "" = all that apply
  std::optional<LocationErrors> truth;   // the simulated machine's location errors (default: none)
  std::function<void(int done, int all)> progress;
};

/// `rotacal design`: a plan for a probe budget, compared with the cycle's full plan.
struct DesignRequest {
  const MachineModel* machine = nullptr;
  const ContributorSet* contributors = nullptr;
  int points = 77;
  std::string criterion = "A";
  std::vector<double> a_deg, c_deg;      // candidate rotary angles; empty = the cycle's defaults
  int exchange_passes = 2;
  std::vector<double> sweep;             // further budgets to design and compare
  int runs = 1000;                       // Monte Carlo runs of the comparison
  std::uint64_t seed = 1;
  std::string plan_file;                 // where the CLI writes the plan (named in the documents)
  std::function<void(int done, int all)> progress;
};

struct DesignedPlan {
  ProbePlan plan;
  Json doc;          // DESIGN.json
  std::string text;  // the summary and the comparison table
};

/// Corrections an analysis hands to the dialect's offsets writer (000 Sec. 4.5).
struct LocationCorrection {
  LocationErrors identified;            // mm / rad, papers' convention
  ErrorVector u = ErrorVector::Zero();  // standard uncertainties, mm / rad
  /// A head machine's own parameters by ISO 230-7 name (head_table, head_cb), identified.kinematics
  /// naming the machine, identified.values unused. Empty for a table machine.
  std::vector<ParameterEstimate> parameters;
};

/// What analyze or diagnose produce: the JSON document (REPORT.json / DIAGNOSIS.json, from which
/// the HTML report is drawn), the readable summary, warnings for stderr, and for analyze the
/// corrections a dialect may write as offsets.
struct CycleDocuments {
  Json doc;
  std::string text;
  std::vector<std::string> warnings;
  std::optional<LocationCorrection> offsets;
  /// Why the data must not reach an offsets file (e.g. the outlier screen found the data beyond a
  /// few chips): analyze --offsets refuses with it, --force writes them anyway.
  std::string offsets_refused;
};
/// The documents of a command that writes a JSON document and its text, nothing else.
inline CycleDocuments documents(Json doc, std::string text) {
  CycleDocuments d;
  d.doc = std::move(doc);
  d.text = std::move(text);
  return d;
}

/// The smallest run of a cycle: a bundled machine it suits (a path under the source tree) and
/// options that keep it short. The test battery over every cycle and the README start from it.
struct CycleExample {
  std::string machine;
  CycleOptions options;
  /// A TRUTH.json the example machine can be simulated with (source-relative): errors of the
  /// size the cycle's source measured, for the battery's recovery test and the docs' examples.
  std::string truth;
};

/// What a cycle is, as data: each cycle hands it to Cycle's constructor, and every verb reads it
/// through the accessors below (no override to write for what is only a value).
struct CycleIdentity {
  std::string_view name;     // what `plan --cycle` takes and the plan's `cycle` field carries
  std::string_view summary;  // one line for --help: the source and what the cycle identifies
  CycleExample example;
  /// The number of the cycle's programs in the control's memory (O-word): one per cycle, 1-9999
  /// (docs/dialects.md), so that two cycles' programs never overwrite each other.
  int program_number = 0;
  /// The plan. Throws std::invalid_argument naming the option or the limit.
  ProbePlan (*make_plan)(const MachineModel& machine, const CycleOptions& options) = nullptr;
  /// The program's operations; Cycle::program() adds what every cycle's program carries.
  nc::Program (*build_program)(const ProbePlan& plan, const std::string& dialect) = nullptr;
  /// What a PLAN.json of this cycle must satisfy beyond the format (checked with FILE:LINE).
  PlanRules plan_rules{};
  /// Empty when analyze returns corrections for `--offsets`; otherwise why the cycle writes none.
  std::string_view no_offsets_reason{};
  /// What one plan point is in a program, for the terminal.
  std::string_view point_noun = "probing moves";
};

class Cycle {
 public:
  explicit Cycle(CycleIdentity identity) : identity_(std::move(identity)) {}
  virtual ~Cycle() = default;

  std::string_view name() const { return identity_.name; }
  /// Other plan `cycle` values this cycle analyzes (plans written by other tools or commands).
  virtual std::vector<std::string> aliases() const { return {}; }
  std::string_view summary() const { return identity_.summary; }
  CycleExample example() const { return identity_.example; }

  /// The plan of the cycle. Throws std::invalid_argument naming the option or the limit.
  ProbePlan plan(const MachineModel& machine, const CycleOptions& options) const {
    return identity_.make_plan(machine, options);
  }
  const PlanRules& planRules() const { return identity_.plan_rules; }

  /// The dialect-neutral program of a plan, carrying the cycle's program number; `dialect`
  /// selects only the controller's conventions the plan needs (rotary sign). Throws
  /// std::invalid_argument when it cannot be expressed.
  nc::Program program(const ProbePlan& plan, const std::string& dialect) const;
  int programNumber() const { return identity_.program_number; }
  /// The machine time of the plan's program, s: its last point's clock, unless the program runs
  /// the plan more than once.
  virtual double machineSeconds(const ProbePlan& plan) const { return plan.points.empty() ? 0.0 : plan.points.back().t_s; }
  std::string_view pointNoun() const { return identity_.point_noun; }

  /// What the controller records on a machine with known errors (exact simulation). The default
  /// is the touch probe's: exact contact with the plan's artefact (cycles/probing.hpp), read back
  /// through the dialect; a cycle whose readings come from another device overrides it.
  virtual Simulated simulate(const SimulateRequest& request) const;

  /// Estimation methods `analyze --method` accepts; the first is the default. Empty: none to choose.
  virtual std::vector<std::string> methods() const { return {}; }
  virtual CycleDocuments analyze(const AnalyzeRequest& request) const = 0;
  /// Empty when analyze returns corrections for `--offsets`; otherwise why the cycle writes none.
  std::string_view noOffsetsReason() const { return identity_.no_offsets_reason; }
  virtual CycleDocuments diagnose(const DiagnoseRequest& request) const = 0;

  /// Whether `uncertainty` and `design` are offered; the defaults refuse, naming the cycle.
  virtual bool hasUncertainty() const { return false; }
  virtual CycleDocuments uncertainty(const UncertaintyRequest& request) const;
  virtual bool hasDesign() const { return false; }
  virtual DesignedPlan design(const DesignRequest& request) const;

 private:
  CycleIdentity identity_;
};

/// Every cycle, in the registry's order.
const std::vector<const Cycle*>& cycles();
std::vector<std::string> cycleNames();
/// By `plan --cycle` name. Throws std::invalid_argument listing the names.
const Cycle& cycleByName(std::string_view name);
/// The cycle that analyzes a plan (its name or one of its aliases). Throws std::invalid_argument.
const Cycle& cycleOfPlan(const ProbePlan& plan);

/// The plan of the named cycle. Throws std::invalid_argument on an unknown cycle or option, or a
/// plan that does not fit the machine (stroke, reach), naming what is wrong.
ProbePlan makePlan(const std::string& cycle, const MachineModel& machine, const CycleOptions& options);

/// PLAN.json read with the rules of the cycle it names (an unknown cycle: the format alone).
ProbePlan loadCyclePlan(const std::string& path);
/// The same from a document already read (the fuzz harness of the plan loader).
ProbePlan cyclePlanFromJson(const JsonDoc& doc);

}  // namespace rotacal
