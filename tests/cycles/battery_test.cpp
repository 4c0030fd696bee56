// One battery over every cycle of the registry (the dialect battery of tests/controllers is the
// model): plan -> program in every dialect -> simulate -> analyze -> diagnose -> HTML report,
// and a malformed results file rejected naming the file. A new cycle is tested by being listed.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "core/machine.hpp"
#include "cycles/cycle.hpp"
#include "report/html_report.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

DialectIO ioOf(const Dialect& d) {
  return {std::string(d.name()),
          [&d](const std::string& text, const std::string& file, const ProbePlan& plan) {
            return d.parseResults(text, file, plan);
          },
          [&d](const ProbePlan& plan, const MeasurementRun& run) { return d.writeResults(plan, run); }};
}

class CycleBattery : public ::testing::TestWithParam<std::string> {
 protected:
  const Cycle& cycle() const { return cycleByName(GetParam()); }
  ProbePlan plan() const {
    const CycleExample ex = cycle().example();
    return cycle().plan(loadMachine(test::sourcePath(ex.machine)), ex.options);
  }
  /// A request of the cycle on plan `p`, its results in the csv dialect.
  template <class Request>
  Request on(const ProbePlan& p) const {
    Request r;
    r.plan = &p;
    r.dialect = &csv;
    return r;
  }
  /// The simulation of a machine whose truth file declares nothing (the defaults).
  SimulateRequest simulation(const ProbePlan& p) const {
    auto s = on<SimulateRequest>(p);
    s.truth = {"truth.json", R"({"format": "rotacal-truth/1"})"};
    return s;
  }
  const DialectIO csv = ioOf(dialectByName("csv"));
};

TEST_P(CycleBattery, PlanCarriesTheCycleAndFitsTheMachine) {
  const ProbePlan p = plan();
  EXPECT_EQ(p.cycle, cycle().name());
  EXPECT_EQ(&cycleOfPlan(p), &cycle());
  ASSERT_FALSE(p.points.empty());
  // The plan survives its own file format.
  const ProbePlan back = planFromJson(parseJsonText(planToJson(p).dump(1), "plan.json"), cycle().planRules());
  EXPECT_EQ(back.cycle, p.cycle);
  EXPECT_EQ(back.points.size(), p.points.size());
}

TEST_P(CycleBattery, ProgramInEveryDialectPassesItsCheckerOrIsRefusedWithAReason) {
  const ProbePlan p = plan();
  int written = 0;
  for (const auto& name : dialectNames()) {
    if (name == "csv") continue;
    const Dialect& d = dialectByName(name);
    std::string text;
    nc::Shape shape;
    try {
      const nc::Program program = cycle().program(p, name);
      shape = nc::shapeOf(program);
      EXPECT_EQ(program.number, cycle().programNumber()) << name;
      text = d.writeProgram(program);
    } catch (const std::invalid_argument& e) {
      EXPECT_GT(std::string(e.what()).size(), 20u) << name << ": a refusal must say why";
      continue;
    }
    const auto problems = d.check(text, p, shape);
    EXPECT_TRUE(problems.empty()) << name << ": " << (problems.empty() ? "" : problems.front());
    ++written;
  }
  EXPECT_GE(written, 1) << "a cycle runs on at least one controller";
}

TEST_P(CycleBattery, SimulateAnalyzeDiagnoseAndReport) {
  const ProbePlan p = plan();
  SimulateRequest s = simulation(p);
  s.noise_um = 0.3;
  s.seed = 7;
  const Simulated sim = cycle().simulate(s);
  ASSERT_FALSE(sim.results_text.empty());

  auto a = on<AnalyzeRequest>(p);
  a.results = {{"r1.txt", sim.results_text}};
  const CycleDocuments rep = cycle().analyze(a);
  EXPECT_FALSE(rep.text.empty());
  EXPECT_EQ(rep.doc.value("cycle", std::string()), p.cycle);
  EXPECT_EQ(rep.offsets.has_value(), cycle().noOffsetsReason().empty());
  const std::string html = report::reportHtml(rep.doc);
  EXPECT_NE(html.find("<html"), std::string::npos);

  auto dr = on<DiagnoseRequest>(p);
  dr.results = {{"r1.txt", sim.results_text}};
  const CycleDocuments dg = cycle().diagnose(dr);
  EXPECT_FALSE(dg.text.empty());
  EXPECT_NE(report::reportHtml(dg.doc).find("<html"), std::string::npos);
}

TEST_P(CycleBattery, MalformedResultsAreRejectedNamingTheFile) {
  const ProbePlan p = plan();
  const std::string good = cycle().simulate(simulation(p)).results_text;
  // Half the lines: points (or readings) are missing.
  size_t cut = good.size() / 2;
  cut = good.rfind('\n', cut) + 1;
  for (const std::string& bad : {good.substr(0, cut), good.substr(0, cut) + "1,2,three\n"}) {
    auto a = on<AnalyzeRequest>(p);
    a.results = {{"bad_results.txt", bad}};
    try {
      cycle().analyze(a);
      ADD_FAILURE() << "accepted a malformed results file";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "bad_results.txt") << e.what();
    } catch (const std::invalid_argument& e) {
      ADD_FAILURE() << "rejected without naming the file: " << e.what();
    }
  }
}

TEST_P(CycleBattery, AnUnknownOptionIsRefusedWithTheCyclesKeys) {
  // One rule for every cycle (cycles/options.hpp): the refusal names the key and the cycle, and
  // lists keys the cycle reads; each listed key gets past the rule (its value may still be refused).
  const CycleExample ex = cycle().example();
  const MachineModel m = loadMachine(test::sourcePath(ex.machine));
  CycleOptions o = ex.options;
  o["no_such_option"] = "1";
  std::string why;
  try {
    (void)cycle().plan(m, o);
  } catch (const std::invalid_argument& e) {
    why = e.what();
  }
  const std::string head = "unknown option 'no_such_option' for cycle " + std::string(cycle().name()) + " (known: ";
  ASSERT_EQ(why.rfind(head, 0), 0u) << why;
  ASSERT_EQ(why.back(), ')');
  const std::string listed = why.substr(head.size(), why.size() - head.size() - 1);
  size_t keys = 0;
  for (size_t at = 0; at <= listed.size(); ++keys) {
    const size_t comma = std::min(listed.find(", ", at), listed.size());
    CycleOptions one = ex.options;
    one[listed.substr(at, comma - at)] = "7";
    try {
      (void)cycle().plan(m, one);
    } catch (const std::exception& e) {  // a file option (frame_file) fails to open "7": not the rule
      EXPECT_EQ(std::string(e.what()).find("unknown option"), std::string::npos) << e.what();
    }
    at = comma + 2;
  }
  EXPECT_GE(keys, 4u) << listed;
}


INSTANTIATE_TEST_SUITE_P(EveryCycle, CycleBattery, ::testing::ValuesIn(cycleNames()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });


TEST(CycleBattery, EveryCycleHasItsOwnProgramNumber) {
  // Two cycles' programs must never overwrite each other in the control's memory.
  std::map<int, std::string> seen;
  for (const Cycle* c : cycles()) {
    const int n = c->programNumber();
    EXPECT_GE(n, 1) << c->name();
    EXPECT_LE(n, 9999) << c->name();
    const auto [it, fresh] = seen.emplace(n, std::string(c->name()));
    EXPECT_TRUE(fresh) << c->name() << " shares program number " << n << " with " << it->second;
  }
}

}  // namespace
}  // namespace rotacal
