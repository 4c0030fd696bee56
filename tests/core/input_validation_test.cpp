// Bad input is refused with the file and the line of the offending value (issue 14): every field
// of a machine, plan, truth and contributors file that is of the wrong type, not finite, of the
// wrong sign or out of range; every count a user can set is capped before anything is built.
// Expected lines are found by searching the test's own text for the substituted value, never
// by asking the parser that is under test.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <fmt/format.h>

#include "controllers/clock.hpp"
#include "core/contributors.hpp"
#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "core/limits.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "cycles/cycle.hpp"
#include "cycles/spheres3/analyze.hpp"
#include "history/store.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

// One field per line, and "controller_sign" twice: a report at the first occurrence of a key
// would name the wrong line for the C axis.
const char* kMachine = R"({
 "format": "rotacal-machine/1",
 "name": "ac_test",
 "description": "validation fixture",
 "kinematics": "table_ac",
 "units": "mm",
 "strokes": {
  "X": [-625.0, 625.0],
  "Y": [-330.0, 330.0],
  "Z": [-140.0, 400.0]
 },
 "rotary_axes": {
  "A": {
   "stroke_deg": [-110.0, 20.0],
   "controller_sign": 1,
   "dialect_sign": {"linuxcnc": -1}
  },
  "C": {
   "continuous": true,
   "controller_sign": 1
  }
 },
 "table_diameter_mm": 500.0,
 "probe": {
  "ball_diameter_mm": 6.0,
  "stylus_length_mm": 50.0,
  "body_clearance_mm": 5.0,
  "tool_number": 0,
  "repeatability_um": 0.7
 },
 "feeds": {
  "rapid_mm_min": 20000.0,
  "positioning_mm_min": 2000.0,
  "probing_mm_min": 100.0,
  "rotary_deg_min": 3600.0
 },
 "clearance_mm": 10.0,
 "approach_mm": 5.0,
 "overtravel_mm": 2.0,
 "artefact": {
  "type": "square_column",
  "top_centre_w_mm": [0.0, -200.0, 170.0],
  "size_mm": [100.0, 100.0, 150.0]
 }
})";

/// Position of the n-th (0-based) occurrence of `what` in `text`.
size_t nth(const std::string& text, const std::string& what, int n) {
  size_t pos = text.find(what);
  for (int i = 0; i < n && pos != std::string::npos; ++i) pos = text.find(what, pos + 1);
  return pos;
}

int lineAt(const std::string& text, size_t pos) {
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(pos), '\n'));
}

struct Mutation {
  std::string from;  // text replaced ...
  int occurrence;    // ... at this occurrence (0-based)
  std::string to;
  std::string says;  // a part of the expected message
};

/// Applies the mutation; returns the text and the line of the replaced value.
std::pair<std::string, int> mutate(const std::string& base, const Mutation& m) {
  std::string t = base;
  const size_t pos = nth(t, m.from, m.occurrence);
  EXPECT_NE(pos, std::string::npos) << m.from;
  t.replace(pos, m.from.size(), m.to);
  return {t, lineAt(t, pos)};
}

// The plan loader with the format's rules alone (a cycle's own rules: tests/cycles/).
ProbePlan loadPlanDoc(const JsonDoc& doc) { return planFromJson(doc); }

template <class Load>
void expectRefusedAt(const std::string& text, int line, const std::string& says, const std::string& file, Load load) {
  try {
    load(parseJsonText(text, file));
    ADD_FAILURE() << "accepted: " << says;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an InputError (no FILE:LINE): " << e.what();
  }
}

/// Every mutation of `base` is refused at the line of the value it replaced, naming what it says.
template <class Load>
void expectEachRefusedAt(const std::string& base, const std::vector<Mutation>& cases, const std::string& file, Load load) {
  for (const auto& c : cases) {
    SCOPED_TRACE(c.to);
    const auto [text, line] = mutate(base, c);
    expectRefusedAt(text, line, c.says, file, load);
  }
}

MachineModel machineOf(const JsonDoc& doc) { return machineFromJson(doc, doc.value); }

TEST(MachineValidation, TheFixtureIsValid) {
  const MachineModel m = machineOf(parseJsonText(kMachine, "m.json"));
  EXPECT_EQ(m.probe.repeatability_um, 0.7);
  EXPECT_EQ(m.rotaryAxis('C').controller_sign, 1);
}

TEST(MachineValidation, EveryBadFieldIsRefusedAtItsLine) {
  const std::vector<Mutation> cases = {
      {"\"repeatability_um\": 0.7", 0, "\"repeatability_um\": 0", "repeatability_um"},
      {"\"repeatability_um\": 0.7", 0, "\"repeatability_um\": -0.7", "repeatability_um"},
      {"\"repeatability_um\": 0.7", 0, "\"repeatability_um\": 1e308", "repeatability_um"},
      {"\"rapid_mm_min\": 20000.0", 0, "\"rapid_mm_min\": 0", "rapid_mm_min"},
      {"\"rapid_mm_min\": 20000.0", 0, "\"rapid_mm_min\": -20000", "rapid_mm_min"},
      {"\"positioning_mm_min\": 2000.0", 0, "\"positioning_mm_min\": 0", "positioning_mm_min"},
      {"\"probing_mm_min\": 100.0", 0, "\"probing_mm_min\": -1", "probing_mm_min"},
      {"\"rotary_deg_min\": 3600.0", 0, "\"rotary_deg_min\": 0", "rotary_deg_min"},
      {"\"controller_sign\": 1", 0, "\"controller_sign\": 1.5", "controller_sign"},
      {"\"controller_sign\": 1", 1, "\"controller_sign\": 0", "controller_sign"},
      {"\"controller_sign\": 1", 1, "\"controller_sign\": 1e308", "controller_sign"},
      {"{\"linuxcnc\": -1}", 0, "{\"linuxcnc\": \"minus\"}", "linuxcnc"},
      {"\"tool_number\": 0", 0, "\"tool_number\": 1e308", "tool_number"},
      {"\"tool_number\": 0", 0, "\"tool_number\": 2.5", "tool_number"},
      {"\"tool_number\": 0", 0, "\"tool_number\": -1", "tool_number"},
      {"[-625.0, 625.0]", 0, "[625.0, -625.0]", "min >= max"},
      {"[-110.0, 20.0]", 0, "[20.0, -110.0]", "min >= max"},
      {"[-140.0, 400.0]", 0, "[-140.0, \"400\"]", "[min, max]"},
      {"\"ball_diameter_mm\": 6.0", 0, "\"ball_diameter_mm\": 0", "ball_diameter_mm"},
      {"\"ball_diameter_mm\": 6.0", 0, "\"ball_diameter_mm\": -6", "ball_diameter_mm"},
      {"\"stylus_length_mm\": 50.0", 0, "\"stylus_length_mm\": 1e308", "stylus_length_mm"},
      {"\"body_clearance_mm\": 5.0", 0, "\"body_clearance_mm\": -5", "body_clearance_mm"},
      {"\"clearance_mm\": 10.0", 0, "\"clearance_mm\": -10", "clearance_mm"},
      {"\"clearance_mm\": 10.0", 0, "\"clearance_mm\": 0", "clearance_mm"},
      {"\"approach_mm\": 5.0", 0, "\"approach_mm\": 0", "approach_mm"},
      {"\"overtravel_mm\": 2.0", 0, "\"overtravel_mm\": -2", "overtravel_mm"},
      {"\"table_diameter_mm\": 500.0", 0, "\"table_diameter_mm\": 0", "table_diameter_mm"},
      {"[100.0, 100.0, 150.0]", 0, "[100.0, -100.0, 150.0]", "size_mm"},
      {"[0.0, -200.0, 170.0]", 0, "[0.0, -200.0, 1e308]", "top_centre_w_mm"},
      // Wrong types, which nlohmann would report as type_error.302 without a line.
      {"\"name\": \"ac_test\"", 0, "\"name\": 12", "name"},
      {"\"description\": \"validation fixture\"", 0, "\"description\": 5", "description"},
      {"\"units\": \"mm\"", 0, "\"units\": 3", "units"},
      {"\"continuous\": true", 0, "\"continuous\": \"yes\"", "continuous"},
      {"\"probing_mm_min\": 100.0", 0, "\"probing_mm_min\": \"fast\"", "probing_mm_min"},
      {"\"strokes\": {", 0, "\"strokes\": [], \"x\": {", "strokes"},
  };
  expectEachRefusedAt(kMachine, cases, "m.json", machineOf);
}

TEST(JsonValidation, ANumberBeyondADoubleNamesItsLine) {
  // nlohmann reports out_of_range.406 without a position.
  const auto [text, line] = mutate(kMachine, {"\"stylus_length_mm\": 50.0", 0, "\"stylus_length_mm\": 1e400", ""});
  try {
    parseJsonText(text, "m.json");
    FAIL() << "1e400 accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
  }
}

std::string touch154PlanText() { return planToJson(test::touch154Plan()).dump(1); }

TEST(PlanValidation, ABadValueDeepInThePlanIsReportedAtItsOwnLine) {
  // Point 100's normal: the first "normal_w" of the file is some 3000 lines earlier.
  const std::string base = touch154PlanText();
  const size_t at = nth(base, "\"normal_w\"", 99);
  ASSERT_NE(at, std::string::npos);
  std::string text = base;
  const size_t open = text.find('[', at), close = text.find(']', at);
  text.replace(open, close - open + 1, "[0, 0.6, 0.6]");
  ASSERT_GT(lineAt(text, at), lineAt(text, base.find("\"normal_w\"")) + 1000);
  expectRefusedAt(text, lineAt(text, at), "point 100: normal_w must be a unit vector", "plan.json", loadPlanDoc);
}

TEST(PlanValidation, TheEmbeddedMachineIsCheckedInThePlanFile) {
  const std::string base = touch154PlanText();
  const auto [text, line] = mutate(base, {"\"repeatability_um\": 0.7", 0, "\"repeatability_um\": 0", ""});
  expectRefusedAt(text, line, "repeatability_um", "plan.json", loadPlanDoc);
}

TEST(PlanValidation, HeightsBelowTheArtefactAreRefused) {
  const std::string base = touch154PlanText();
  const ProbePlan plan = test::touch154Plan();
  {
    const std::string from = fmt::format("\"index_z_mm\": {}", Json(plan.index_z_mm).dump());
    const auto [text, line] = mutate(base, {from, 0, "\"index_z_mm\": -100.0", ""});
    expectRefusedAt(text, line, "index_z_mm = -100 mm is below the artefact", "plan.json", loadPlanDoc);
  }
  {
    // Pose V (A = -90, C = 90): the column's side x = +50 mm faces up, so the ball centre must
    // stay above 50 + 3 mm; its safe height lowered to 40 mm.
    ASSERT_DOUBLE_EQ(plan.poses[4].safe_z_mm, 50.0 + 3.0 + 10.0);
    const std::string from = fmt::format("\"safe_z_mm\": {}", Json(plan.poses[4].safe_z_mm).dump());
    const auto [text, line] = mutate(base, {from, 0, "\"safe_z_mm\": 40.0", ""});
    ASSERT_EQ(line, lineAt(base, nth(base, "\"safe_z_mm\"", 4)));
    expectRefusedAt(text, line, "pose V: safe_z_mm = 40 mm is below what the probe moves over: the ball centre must stay "
                    "at z >= 53.000 mm", "plan.json", loadPlanDoc);
  }
}

TEST(PlanValidation, StructuralProblemsAreRefused) {
  Json j = planToJson(test::touch154Plan());
  {
    Json k = j;
    k["poses"].push_back({{"name", "extra"}, {"pose", {{"A", 0.0}, {"C", 45.0}}}, {"safe_z_mm", 400.0}});
    EXPECT_THROW(planFromJson(parseJsonText(k.dump(1), "p.json")), InputError);
  }
  {
    Json k = j;
    k["poses"][1]["name"] = "I";
    try {
      planFromJson(parseJsonText(k.dump(1), "p.json"));
      FAIL();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("appears twice"), std::string::npos) << e.what();
    }
  }
  for (const char* field : {"id", "t_s", "target"}) {
    Json k = j;
    k["points"][5][field] = 1e308;
    EXPECT_THROW(planFromJson(parseJsonText(k.dump(1), "p.json")), InputError) << field;
  }
  {
    Json k = j;
    k["points"][5]["t_s"] = -1.0;
    EXPECT_THROW(planFromJson(parseJsonText(k.dump(1), "p.json")), InputError);
  }
}

TEST(PlanValidation, AHandEditedSpheres3PoseWithoutTouchesIsRefusedByTheLoader) {
  const ProbePlan plan = makePlan("spheres3", test::acMachine(), {});
  Json j = planToJson(plan);
  Json kept = Json::array();
  for (const auto& p : j["points"])
    if (!(p["pose_name"] == plan.poses.back().name && p["sphere"]["id"] == 2)) kept.push_back(p);
  for (size_t i = 0; i < kept.size(); ++i) kept[i]["id"] = i + 1;
  j["points"] = kept;
  try {
    planFromJson(parseJsonText(j.dump(1), "s.json"), cycleByName("spheres3").planRules());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has 0 touches of sphere 2"), std::string::npos) << e.what();
  }
}

TEST(Spheres3, APoseWithoutTouchesIsAnErrorNotACrash) {
  // The identification's own guard, for plans built in code.
  ProbePlan plan = makePlan("spheres3", test::acMachine(), {});
  const MeasurementRun run = simulate(plan, test::truthWith(test::table4Mean()), {});
  const std::string last = plan.poses.back().name;
  std::vector<ProbePoint> kept;
  for (const auto& p : plan.points)
    if (p.pose_name != last) kept.push_back(p);
  plan.points = kept;
  try {
    identifySpheres3(plan, {run}, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("has 0 touches of sphere 1"), std::string::npos) << e.what();
  }
}

// ---- Caps --------------------------------------------------------------------------------

struct CapCase {
  std::string cycle;
  MachineModel machine;
  CycleOptions options;
  std::string names;  // the option the message must name
};

std::string listOf(int n, double first, double step) {
  std::string s;
  for (int i = 0; i < n; ++i) s += (i ? "," : "") + fmt::format("{:g}", first + i * step);
  return s;
}

TEST(Caps, EveryCountAUserSetsIsCappedWithTheOptionNamed) {
  const MachineModel ac = test::acMachine();
  const MachineModel bc = loadMachine(test::sourcePath("examples/machines/bc_trunnion.json"));
  const MachineModel head = loadMachine(test::sourcePath("examples/machines/head_ab.json"));
  const std::vector<CapCase> cases = {
      {"touch154", ac, {{"top_offsets_mm", listOf(3000, -45, 0.03)}}, "top_offsets_mm"},
      {"touch154", ac, {{"top_offsets_mm", listOf(40, -45, 2)}}, "top_offsets_mm"},  // 7 x 40^2 touches
      {"touch154", ac, {{"side_offsets_mm", listOf(400, -45, 0.2)}}, "side_offsets_mm"},
      {"spheres3", ac, {{"c_step_deg", "1e-6"}}, "c_step_deg"},
      {"spheres3", ac, {{"c_step_deg", "8.4e-08"}}, "c_step_deg"},
      {"spheres3", ac, {{"c_step_deg", "0.5"}}, "c_step_deg"},  // 720 poses
      {"rtest", bc, {{"c_list", listOf(100, 0, 3)}}, "c_list"},    // 5 x 100 poses
      {"rtest", bc, {{"b_list", listOf(400, -60, 0.3)}}, "b_list"},
      {"rtest", bc, {{"thermal", "1"}, {"duration_h", "1000"}, {"interval_min", "1"}}, "duration_h"},
      {"rtest", bc, {{"thermal", "1"}, {"interval_min", "1e-300"}}, "interval_min"},
      {"spaceframe", ac, {{"theta_list", listOf(20, 0, 18)}, {"phi_list", listOf(20, -90, 4.5)}}, "theta_list"},
      {"spaceframe", ac, {{"theta_list", listOf(300, 0, 1)}}, "theta_list"},  // 300 poses x 35 touches
      {"tooltip", head, {{"step_deg", "0.001"}, {"end_deg", "90"}}, "step_deg"},
      {"tooltip", head, {{"step_deg", "1e-300"}, {"end_deg", "90"}}, "step_deg"},
      {"tooltip", head, {{"sweeps", "100000"}}, "sweeps"},
      {"tooltip", head, {{"sweeps", "1000"}}, "sweeps"},  // 1000 sweeps x 4 x 18 steps
      {"tooltip", head, {{"other_deg", listOf(400, -80, 0.4)}}, "other_deg"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.cycle + " " + c.options.begin()->first + "=" + c.options.begin()->second.substr(0, 40));
    try {
      makePlan(c.cycle, c.machine, c.options);
      ADD_FAILURE() << "built";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(c.names), std::string::npos) << m;
      EXPECT_TRUE(m.find("at most") != std::string::npos || m.find("0..") != std::string::npos ||
                  m.find("from 0 to ") != std::string::npos)
          << m;
    }
  }
}

TEST(Caps, APlanThatWouldOutlastTheClockIsRefused) {
  // Not a count, but what makes a written plan fail to load: its times.
  const MachineModel bc = loadMachine(test::sourcePath("examples/machines/bc_trunnion.json"));
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"dwell_s", "1e12"}, {"interval_min", "1e300"}, {"duration_h", "1e300"}}) {
    EXPECT_THROW(makePlan("rtest", bc, {{key, value}}), std::invalid_argument) << key;
  }
  const MachineModel head = loadMachine(test::sourcePath("examples/machines/head_ab.json"));
  EXPECT_THROW(makePlan("tooltip", head, {{"move_s", "1e12"}}), std::invalid_argument);
}

TEST(Caps, APlanAtTheCapsIsBuiltWrittenAndLoaded) {
  // spheres3 at 1 deg: kMaxPlanPoses poses of 15 touches each.
  const ProbePlan plan = makePlan("spheres3", test::acMachine(), {{"c_step_deg", "1"}});
  EXPECT_EQ(plan.poses.size(), static_cast<size_t>(kMaxPlanPoses));
  EXPECT_EQ(plan.points.size(), 15u * kMaxPlanPoses);
  const ProbePlan back = planFromJson(parseJsonText(planToJson(plan).dump(1), "p.json"));
  EXPECT_EQ(back.points.size(), plan.points.size());
  // A fractional start keeps every pose name distinct.
  const ProbePlan half = makePlan("spheres3", test::acMachine(), {{"c_step_deg", "1"}, {"c_start_deg", "0.5"}});
  EXPECT_NO_THROW(planFromJson(parseJsonText(planToJson(half).dump(1), "p.json")));
}

// ---- Truth and contributors --------------------------------------------------------------

TEST(TruthValidation, ImplausibleOrIllTypedErrorsAreRefusedAtTheirLine) {
  const std::string base = R"({
 "format": "rotacal-truth/1",
 "location_errors": {
  "dx_AY": {"value": 14.6, "unit": "um"},
  "a_AY": {"value": -0.5, "unit": "mdeg"}
 },
 "drift": {
  "dz_AY": {"rate": 6.0, "unit": "um/h"}
 },
 "setup_error": {"translation_mm": [0.5, 0.5, 0.0], "rotation_mrad": [0.0, 0.0, 2.0]},
 "probe_noise_um": 0.7,
 "start_time_s": 0
})";
  auto load = [](const JsonDoc& d) { return truthFromJson(d, Kinematics::TableAC); };
  EXPECT_NO_THROW(load(parseJsonText(base, "t.json")));
  const std::vector<Mutation> cases = {
      {"14.6", 0, "1e308", "value"},
      {"-0.5", 0, "-1e300", "value"},
      {"\"unit\": \"um\"", 0, "\"unit\": 7", "unit"},
      {"6.0", 0, "1e300", "rate"},
      {"[0.5, 0.5, 0.0]", 0, "[0.5, 1e308, 0.0]", "translation_mm"},
      {"\"probe_noise_um\": 0.7", 0, "\"probe_noise_um\": -0.7", "probe_noise_um"},
      {"\"start_time_s\": 0", 0, "\"start_time_s\": 1e300", "start_time_s"},
  };
  expectEachRefusedAt(base, cases, "t.json", load);
}

// fuzz_truth (AddressSanitizer, stack-use-after-scope): the limits of rotation_mrad kept their
// unit as a view of a temporary string, so the refusal printed whatever the stack held there.
// The message must end in the unit itself (under scripts/sanitize.sh the old code aborts here).
TEST(TruthValidation, AnOutOfRangeRotationNamesItsUnit) {
  const std::string text = R"({"format": "rotacal-truth/1",
 "setup_error": {"rotation_mrad": [0.0, 0.0, 1e300]}})";
  try {
    (void)truthFromJson(parseJsonText(text, "t.json"), Kinematics::TableAC);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.line(), 2) << what;
    EXPECT_NE(what.find("rotation_mrad"), std::string::npos) << what;
    EXPECT_NE(what.find(" mrad (got 1e+300)"), std::string::npos) << what;
  }
}

// fuzz_report: a report whose location errors carry a head_ab parameter name made history's
// unit check ask head_ab for its location errors, which throws std::invalid_argument (no file,
// no line). Such a report is read like any other.
TEST(ReportValidation, HistoryReadsAReportOfAnyKinematics) {
  const std::string text = R"({"format": "rotacal-report/1", "cycle": "tooltip", "residual_rms_um": 0.5,
 "location_errors": {"dR": {"value": 3.0, "u": 0.2, "unit": "um"}}})";
  EXPECT_NO_THROW((void)history::calibrationFromReport(parseJsonText(text, "r.json"), "m1", 1.7e9));
  const std::string inch = R"({"format": "rotacal-report/1", "cycle": "touch154", "residual_rms_um": 0.5,
 "location_errors": {"dx_AY": {"value": 3.0, "u": 0.2, "unit": "inch"}}})";
  try {
    (void)history::calibrationFromReport(parseJsonText(inch, "r.json"), "m1", 1.7e9);
    FAIL() << "accepted a length in inch";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2) << e.what();
    EXPECT_NE(std::string(e.what()).find("must be um"), std::string::npos) << e.what();
  }
}

TEST(ContributorValidation, AnImplausibleUncertaintyIsRefusedAtItsLine) {
  const std::string base = readTextFile(test::sourcePath("examples/contributors/table5.json"));
  ASSERT_NO_THROW(contributorsFromJson(parseJsonText(base, "c.json")));
  const size_t at = nth(base, "\"probe_repeatability\"", 0);
  ASSERT_NE(at, std::string::npos);
  const size_t u = base.find("\"u\":", at);
  const size_t end = base.find_first_of(",}", u);
  std::string text = base;
  text.replace(u, end - u, "\"u\": 1e308");
  expectRefusedAt(text, lineAt(text, u), "'u'", "c.json", contributorsFromJson);
}

// ---- The controllers' clock ---------------------------------------------------------------

TEST(Clock, StampsBeyondTheControllersYearsAreRefusedNotOverflowed) {
  for (double s : {1e300, -1e300, 1e19, 4.1e11}) EXPECT_THROW(ctl::clockStamp(s), std::invalid_argument) << s;
  // Within range the stamp still inverts clockSeconds.
  for (double s : {0.0, 1.0e9, 2.5e11, -3.0e9}) {
    const auto c = ctl::clockStamp(s);
    EXPECT_EQ(ctl::clockSeconds(c.yyyymmdd, c.hhmmss).value_or(-1), s);
  }
}

}  // namespace
}  // namespace rotacal
