// The program verifier (issue 14, `rotacal check`): every program rotacal writes passes it - all
// cycles x all dialects that write them, and every compensated program - and each kind of fault
// it exists for is caught, one test each, by injecting it into a real program. Each fault test
// asserts the violation the verifier names (line and kind) and, where the fault is built from a
// clean program, that the clean one has none: removing the verifier fails them.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "controllers/end_point_check.hpp"
#include "controllers/dialect.hpp"
#include "controllers/motion_reader.hpp"
#include "core/machine.hpp"
#include "cycles/check_rules.hpp"
#include "cycles/cycle.hpp"
#include "postproc/compensate_program.hpp"
#include "postproc/program_check.hpp"
#include "test_util.hpp"
#include "dialect_lists.hpp"

namespace rotacal {
namespace {

// The setup `rotacal check --plan` builds (cli/cmd_check.cpp): the plan's cycle gives the
// number and whether the machine's artefact is on the table.
ProgramCheckResult verify(const std::string& text, const std::string& dialect, const MachineModel& machine,
                          const ProbePlan* plan, const LocationErrors* errors = nullptr) {
  ProgramCheckSetup s = programCheckSetup(machine, dialect, ctl::numbersPrograms(dialect), plan, true);
  if (errors) s.errors = *errors;
  return checkProgram(ctl::readMotions(dialect, text), s);
}

nc::Program programOf(const ProbePlan& plan, const std::string& dialect) {
  return cycleOfPlan(plan).program(plan, dialect);
}

std::string describe(const ProgramCheckResult& r) {
  std::string s;
  for (const auto& v : r.violations) s += fmt::format("  line {}: {}\n", v.line, v.problem);
  return s;
}

// The first violation containing `what`, or nullptr.
const ProgramViolation* find(const ProgramCheckResult& r, const std::string& what) {
  for (const auto& v : r.violations)
    if (v.problem.find(what) != std::string::npos) return &v;
  return nullptr;
}

// The checker's only violation is `what`, at line `line` (1-based); `context` names the case.
void expectOnly(const ProgramCheckResult& r, const std::string& what, int line, const std::string& context = "") {
  const ProgramViolation* v = find(r, what);
  ASSERT_NE(v, nullptr) << context << "\n" << describe(r);
  EXPECT_EQ(v->line, line) << context;
  EXPECT_EQ(r.violations.size(), 1u) << context << "\n" << describe(r);
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start < text.size()) {
    const size_t nl = text.find('\n', start);
    out.push_back(text.substr(start, nl == std::string::npos ? std::string::npos : nl - start));
    if (nl == std::string::npos) break;
    start = nl + 1;
  }
  return out;
}

std::string joined(const std::vector<std::string>& ls) {
  std::string s;
  for (const auto& l : ls) s += l + "\n";
  return s;
}

// Index of the first line that starts with `prefix` at or after `from`.
size_t lineStarting(const std::vector<std::string>& ls, const std::string& prefix, size_t from = 0) {
  for (size_t i = from; i < ls.size(); ++i)
    if (ls[i].rfind(prefix, 0) == 0) return i;
  ADD_FAILURE() << "no line starting with " << prefix;
  return ls.size();
}

// 000 Table 4's location errors (um / mdeg) on any table kinematics: what compensate applies.
LocationErrors table4Like(Kinematics k) {
  const double v[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};
  LocationErrors e;
  e.kinematics = k;
  for (int i = 0; i < 8; ++i) e.setReportValue(i, v[i]);
  return e;
}

NcSyntax syntaxOf(const std::string& d) {
  return NcSyntax{d, 4, 5, 4, d == "siemens" ? NcSyntax::Comment::Semicolon : NcSyntax::Comment::Parentheses};
}

const std::vector<std::string> kProgramDialects = test::programDialects();

struct Written {
  std::string cycle, dialect, text;
  ProbePlan plan;
};

// Every program rotacal writes for every cycle's example, in every dialect that writes it.
std::vector<Written> everyProgram() {
  std::vector<Written> out;
  for (const auto& name : cycleNames()) {
    const Cycle& c = cycleByName(name);
    const CycleExample ex = c.example();
    const ProbePlan plan = makePlan(name, loadMachine(test::sourcePath(ex.machine)), ex.options);
    for (const auto& d : kProgramDialects) {
      std::string text;
      try {
        text = dialectByName(d).writeProgram(c.program(plan, d));
      } catch (const std::invalid_argument&) {
        continue;  // the dialect refuses this cycle (docs/dialects.md)
      }
      out.push_back({name, d, text, plan});
    }
  }
  return out;
}

// The space-frame planner once descended onto a lower sphere through the one above it at
// A = -90 deg (found by this verifier); it now leaves such touches out, and its programs pass here
// like every other cycle's.
TEST(ProgramCheck, PassesEveryProgramOfEveryCycleAndDialect) {
  int programs = 0, probes = 0;
  for (const auto& w : everyProgram()) {
    const ProgramCheckResult r = verify(w.text, w.dialect, w.plan.machine, &w.plan);
    EXPECT_TRUE(r.violations.empty()) << w.cycle << " " << w.dialect << ":\n" << describe(r);
    EXPECT_GT(r.motion_blocks, 0) << w.cycle << " " << w.dialect;
    // Every touch of the plan is a probing move the simulation saw reach its surface.
    size_t probes_in_program = 0;
    for (const auto& op : programOf(w.plan, w.dialect).ops) probes_in_program += op.kind == nc::Op::Kind::Probe;
    EXPECT_EQ(static_cast<size_t>(r.probing_moves), probes_in_program) << w.cycle << " " << w.dialect;
    // Without the plan (rotacal check PROGRAM --machine M): the machine's artefact alone.
    const ProgramCheckResult bare = verify(w.text, w.dialect, w.plan.machine, nullptr);
    EXPECT_TRUE(bare.violations.empty()) << w.cycle << " " << w.dialect << " without the plan:\n" << describe(bare);
    ++programs;
    probes += r.probing_moves;
  }
  // touch154, spheres3, spaceframe and one_sphere in 6 dialects, probe_qual in 5 (heidenhain's
  // cycle 0 refuses its 45-degree approaches), tooltip in 4 (okuma and heidenhain refuse G93),
  // rtest in linuxcnc only.
  EXPECT_EQ(programs, 4 * 6 + 5 + 4 + 1);
  RecordProperty("programs", programs);
  RecordProperty("probing_moves", probes);
}

TEST(ProgramCheck, TheTouchProgramsKeepTheirPlannedGaps) {
  const ProbePlan plan = test::touch154Plan();
  const std::string text = dialectByName("fanuc").writeProgram(programOf(plan, "fanuc"));
  const ProgramCheckResult r = verify(text, "fanuc", plan.machine, &plan);
  ASSERT_TRUE(r.violations.empty()) << describe(r);
  EXPECT_EQ(r.obstacles, 2);  // the column and the table
  // The probe starts approach_mm = 5 mm from each face: the smallest gap between touches.
  EXPECT_NEAR(r.min_clearance_mm, plan.machine.approach_mm, 1e-3);
  EXPECT_NEAR(r.required_gap_mm, 4.5, 1e-12);
}

TEST(ProgramCheck, PassesEveryCompensatedProgram) {
  int compensated = 0;
  for (const auto& w : everyProgram()) {
    if (w.dialect == "heidenhain" || w.plan.machine.kinematics == Kinematics::HeadAB) continue;  // not rewritten
    ProgramCompensationOptions o;
    o.header = {"location errors of report.json:"};
    const ProgramCompensation c = compensateProgram(w.text, "p", w.plan.machine, table4Like(w.plan.machine.kinematics),
                                                    syntaxOf(w.dialect), o);
    const ProgramCheckResult r = verify(c.text, w.dialect, w.plan.machine, &w.plan);
    EXPECT_TRUE(r.violations.empty()) << w.cycle << " " << w.dialect << " compensated:\n" << describe(r);
    // On the machine with the errors it is compensated for, the rewrite keeps the planned gaps
    // (what compensate checks before writing).
    const LocationErrors e = table4Like(w.plan.machine.kinematics);
    const ProgramCheckResult on_machine = verify(c.text, w.dialect, w.plan.machine, &w.plan, &e);
    EXPECT_TRUE(on_machine.violations.empty()) << w.cycle << " " << w.dialect << " on its machine:\n" << describe(on_machine);
    if (w.cycle == "touch154") {
      EXPECT_NEAR(on_machine.min_clearance_mm, w.plan.machine.approach_mm, 1e-3) << w.dialect;
      EXPECT_GT(std::abs(r.min_clearance_mm - w.plan.machine.approach_mm), 5e-3) << w.dialect << ": nominally shifted";
    }
    if (ctl::endPointCheck(w.dialect) && test::shapeOf(w.plan, w.dialect).probes > 0) {
      EXPECT_GT(c.rewritten_checks, 0) << w.cycle << " " << w.dialect;
    }
    ++compensated;
  }
  EXPECT_EQ(compensated, 5 * 5 + 1);  // touch154, spheres3, spaceframe, one_sphere, probe_qual x 5 word-address dialects; rtest
  RecordProperty("compensated_programs", compensated);
}

// ---- Injected faults, one each ----

struct Fanuc154 {
  ProbePlan plan = test::touch154Plan();
  std::string text = dialectByName("fanuc").writeProgram(programOf(plan, "fanuc"));
  std::vector<std::string> ls = split(text);
};

TEST(ProgramCheckFault, RapidThroughTheArtefact) {
  Fanuc154 f;
  ASSERT_TRUE(verify(f.text, "fanuc", f.plan.machine, &f.plan).violations.empty());
  // After the first touch's retract (at X58 Y-235 Z150, beside the +X face), a rapid straight
  // across the column to the -X side and back.
  const size_t retract = lineStarting(f.ls, "G01 X58.0000 Y-235.0000 Z150.0000 F2000.0", lineStarting(f.ls, "G31"));
  auto ls = f.ls;
  ls.insert(ls.begin() + static_cast<long>(retract) + 1, {"G00 X-58.0000 Y-235.0000 Z150.0000", "G00 X58.0000 Y-235.0000 Z150.0000"});
  const ProgramCheckResult r = verify(joined(ls), "fanuc", f.plan.machine, &f.plan);
  const ProgramViolation* v = find(r, "of the artefact");
  ASSERT_NE(v, nullptr) << describe(r);
  EXPECT_EQ(v->line, static_cast<int>(retract) + 2);
  EXPECT_NE(v->problem.find("must be a guarded probing move"), std::string::npos) << v->problem;
}

// A/C table at A = -90: the column lies on its side, its top toward machine -Y; at C = 180 deg
// it hangs above the rotary centre, its body at machine Z 150..250, Y -170..-20, X -50..50. The
// probe stands at X0 Y-95 Z130: the ball 17 mm below the column, its 50 mm stylus reaching up into
// the column's place. Turning C from 120 to 240 deg there sweeps the column through the stylus,
// while both end poses are clear (the column then stands 173 mm to either side): only the sweep
// shows it.
constexpr char kStylusProgram[] = R"(%
O7154(ROTACAL TEST)
G21
G17 G40 G49 G80 G90 G94
G00 Z319.4311
G00 A-90.0000 C120.0000
G00 X0.0000 Y-95.0000 Z319.4311
G00 X0.0000 Y-95.0000 Z130.0000
{}
M30
%
)";

TEST(ProgramCheckFault, StylusSweptThroughTheArtefactOnARotaryMove) {
  const MachineModel m = test::acMachine();
  // The end poses are clear: the probe reaches the same place at C = -60 (above) and at C = +60.
  const std::string at_end = fmt::format(kStylusProgram, "G00 Z319.4311\nG00 C240.0000\nG00 X0.0000 Y-95.0000 Z130.0000");
  const ProgramCheckResult clear = verify(at_end, "fanuc", m, nullptr);
  EXPECT_TRUE(clear.violations.empty()) << describe(clear);
  // Turning there: caught on the rotary line.
  const std::string swept = fmt::format(kStylusProgram, "G00 C240.0000");
  const ProgramCheckResult r = verify(swept, "fanuc", m, nullptr);
  const ProgramViolation* v = find(r, "of the artefact");
  ASSERT_NE(v, nullptr) << describe(r);
  EXPECT_EQ(v->line, 9);
  EXPECT_EQ(r.violations.size(), 1u) << describe(r);
  // The stylus, not the ball: 30 mm of it inside the column (and the ball's radius).
  EXPECT_NE(v->problem.find("within -33.000 mm"), std::string::npos) << v->problem;
}

TEST(ProgramCheckFault, MissingTriggerCheck) {
  Fanuc154 f;
  // The first G31's three end-point statements and its test, removed.
  const size_t g31 = lineStarting(f.ls, "G31");
  auto ls = f.ls;
  ASSERT_EQ(ls[g31 + 4].rfind("IF[", 0), 0u) << ls[g31 + 4];
  ls.erase(ls.begin() + static_cast<long>(g31) + 1, ls.begin() + static_cast<long>(g31) + 6);
  const ProgramCheckResult r = verify(joined(ls), "fanuc", f.plan.machine, &f.plan);
  expectOnly(r, "without its no-trigger check", static_cast<int>(g31) + 1);
}

TEST(ProgramCheckFault, StaleCheckEndPointInACompensatedProgram) {
  for (const char* d : {"fanuc", "haas", "okuma", "siemens"}) {
    const ProbePlan plan = test::touch154Plan();
    const std::string text = dialectByName(d).writeProgram(programOf(plan, d));
    ProgramCompensationOptions o;
    const std::string comp =
        compensateProgram(text, "p", plan.machine, table4Like(Kinematics::TableAC), syntaxOf(d), o).text;
    ASSERT_TRUE(verify(comp, d, plan.machine, &plan).violations.empty()) << d;
    // The defect compensate once had: the moves rewritten, the checks left with the old end point.
    const ctl::EndPointCheck form = *ctl::endPointCheck(d);
    auto old_ls = split(text);
    auto ls = split(comp);
    size_t first_old = 0, first_new = 0;
    for (; first_old < old_ls.size(); ++first_old)
      if (ctl::parseEndPointCheckStatement(form, old_ls[first_old])) break;
    for (; first_new < ls.size(); ++first_new)
      if (ctl::parseEndPointCheckStatement(form, ls[first_new])) break;
    ASSERT_LT(first_new, ls.size()) << d;
    ASSERT_NE(ls[first_new], old_ls[first_old]) << d << ": compensation moves the first end point";
    ls[first_new] = old_ls[first_old];
    const ProgramCheckResult r = verify(joined(ls), d, plan.machine, &plan);
    expectOnly(r, "a stale check", static_cast<int>(first_new) + 1, d);
  }
}

TEST(ProgramCheckFault, StaleHeidenhainCheck) {
  const ProbePlan plan = test::touch154Plan();
  const std::string text = dialectByName("heidenhain").writeProgram(programOf(plan, "heidenhain"));
  ASSERT_TRUE(verify(text, "heidenhain", plan.machine, &plan).violations.empty());
  // The first FN 12 test moved 40 um: it no longer guards the travel the header asks for.
  const std::string stale = std::regex_replace(text, std::regex(R"(IF \+Q10 LT \+51\.0100)"), "IF +Q10 LT +51.0500",
                                               std::regex_constants::format_first_only);
  ASSERT_NE(stale, text);
  const ProgramCheckResult r = verify(stale, "heidenhain", plan.machine, &plan);
  ASSERT_NE(find(r, "a stale check"), nullptr) << describe(r);
}

TEST(ProgramCheckFault, PoseOutOfStroke) {
  Fanuc154 f;
  // The first index, written 0.5 mdeg past A's stroke [-110, 20] (what compensate once wrote).
  const size_t index = lineStarting(f.ls, "G00 A0.0000 C0.0000");
  auto ls = f.ls;
  ls[index] = "G00 A-110.0005 C0.0000";
  const ProgramCheckResult r = verify(joined(ls), "fanuc", f.plan.machine, &f.plan);
  const ProgramViolation* v = find(r, "A = -110.0005 deg (papers' convention) is outside the A stroke [-110, 20]");
  ASSERT_NE(v, nullptr) << describe(r);
  EXPECT_EQ(v->line, static_cast<int>(index) + 1);
  // And a linear word: Z past its stroke [-140, 400].
  ls = f.ls;
  const size_t climb = lineStarting(f.ls, "G00 Z319.4311");
  ls[climb] = "G00 Z400.5000";
  const ProgramCheckResult z = verify(joined(ls), "fanuc", f.plan.machine, &f.plan);
  const ProgramViolation* vz = find(z, "Z = 400.5000 mm is outside the Z stroke");
  ASSERT_NE(vz, nullptr) << describe(z);
  EXPECT_EQ(vz->line, static_cast<int>(climb) + 1);
}

TEST(ProgramCheckFault, InverseTimeBlockWithoutF) {
  const Cycle& tooltip = cycleByName("tooltip");
  const CycleExample ex = tooltip.example();
  const ProbePlan plan = makePlan("tooltip", loadMachine(test::sourcePath(ex.machine)), ex.options);
  for (const char* d : {"linuxcnc", "fanuc"}) {
    const std::string text = dialectByName(d).writeProgram(tooltip.program(plan, d));
    ASSERT_TRUE(verify(text, d, plan.machine, &plan).violations.empty()) << d;
    // The second move under G93 loses its F (004's sample writes F once; controls want it on every block).
    auto ls = split(text);
    const size_t g93 = lineStarting(ls, std::string(d) == "linuxcnc" ? "G91 G01 G93" : "G91 G01 G93");
    size_t moves = 0, at = g93 + 1;
    for (; at < ls.size(); ++at)
      if (ls[at].find('F') != std::string::npos && (ls[at][0] == 'Y' || ls[at][0] == 'X' || ls[at][0] == 'Z' || ls[at][0] == 'A' || ls[at][0] == 'B'))
        if (++moves == 2) break;
    ASSERT_LT(at, ls.size()) << d << ": no second G93 move";
    ls[at] = std::regex_replace(ls[at], std::regex(R"(F[0-9.]+)"), "");
    const ProgramCheckResult r = verify(joined(ls), d, plan.machine, &plan);
    expectOnly(r, "inverse-time (G93) move without F", static_cast<int>(at) + 1, d);
  }
}

TEST(ProgramCheckFault, WrongOrDuplicateProgramNumber) {
  const MachineModel m = test::acMachine();
  const ProbePlan plan = makePlan("spheres3", m, {});
  const std::string text = dialectByName("fanuc").writeProgram(programOf(plan, "fanuc"));
  ASSERT_TRUE(verify(text, "fanuc", m, &plan).violations.empty());
  // spheres3 numbered like touch154: the two would overwrite each other in the control.
  const std::string dup = std::regex_replace(text, std::regex("\nO7001"), "\nO7154", std::regex_constants::format_first_only);
  ASSERT_NE(dup, text);
  const ProgramCheckResult r = verify(dup, "fanuc", m, &plan);
  const ProgramViolation* v = find(r, "program number 7154 is not this cycle's (7001)");
  ASSERT_NE(v, nullptr) << describe(r);
  EXPECT_EQ(v->line, 2);
  // Without the plan: a number none of rotacal's cycles has, and a second number.
  const std::string foreign = std::regex_replace(text, std::regex("\nO7001"), "\nO1234", std::regex_constants::format_first_only);
  ASSERT_NE(find(verify(foreign, "fanuc", m, nullptr), "none of rotacal's cycle numbers"), nullptr);
  const std::string two = std::regex_replace(text, std::regex("\nG21\n"), "\nO7002\nG21\n", std::regex_constants::format_first_only);
  ASSERT_NE(find(verify(two, "fanuc", m, &plan), "a second program number"), nullptr);
}

TEST(ProgramCheckFault, FeedMoveBeforeAnyFeed) {
  const MachineModel m = test::acMachine();
  const std::string p = "%\nO7154(T)\nG21\nG90 G94\nG00 Z319.4311\nG00 A0.0000 C0.0000\nG00 X0.0000 Y0.0000 Z319.4311\n"
                        "G01 X10.0000 Y0.0000 Z319.4311\nM30\n%\n";
  const ProgramCheckResult r = verify(p, "fanuc", m, nullptr);
  const ProgramViolation* v = find(r, "feed move before any feed is set");
  ASSERT_NE(v, nullptr) << describe(r);
  EXPECT_EQ(v->line, 8);
  const std::string with_f = std::regex_replace(p, std::regex("Z319.4311\nM30"), "Z319.4311 F500.\nM30");
  EXPECT_TRUE(verify(with_f, "fanuc", m, nullptr).violations.empty()) << describe(verify(with_f, "fanuc", m, nullptr));
}

// The retract a Fanuc or Haas part program ends with, G91 G28 Z0 (or G53 Z0.), takes Z alone to
// its reference at the top of the Z stroke: followed, not refused. Shown by where Z stands after
// it: a feed move down from there by the distance MACHINE.json puts between the stroke's top and
// the table's top, plus 1 mm, crosses the table; 1 mm less does not. G53 Z-10. stands 10 mm lower.
// LinuxCNC's G28 goes to a stored position and stays refused, as does a G28 of other axes.
TEST(ProgramCheck, APartProgramsRetractToTheZReferenceIsFollowed) {
  const MachineModel m = loadMachine(test::sourcePath("examples/machines/ac_trunnion.json"));
  ASSERT_TRUE(m.artefact.has_value());
  // The table's top as MACHINE.json declares it (table_top_z_mm, else the column's foot).
  const double top = m.table_top_z_mm ? *m.table_top_z_mm : m.artefact->top_centre_w.z() - m.artefact->size_mm.z();
  const auto run = [&](const std::string& dialect, const std::string& retract, double down_mm) {
    const std::string text = fmt::format(
        "%\nO1000\nG90 G21 G17\nG0 A0. C0.\nG0 X0. Y0. Z100.\n{}\nG90 G0 X0. Y0.\nG91 G1 Z{:.4f} F500.\nG90\nM30\n%\n",
        retract, -down_mm);
    // As `check --part-program` sets it up: no plan, no rotacal program number.
    ProgramCheckSetup s = programCheckSetup(m, dialect, ctl::numbersPrograms(dialect), nullptr, false);
    s.part_program = true;
    return checkProgram(ctl::readMotions(dialect, text), s);
  };
  for (const std::string dialect : {"fanuc", "haas"}) {
    for (const auto& [retract, below] : {std::pair<std::string, double>{"G91 G28 Z0", 0.0}, {"G28 G91 Z0.", 0.0},
                                         {"G91 G30 Z0", 0.0}, {"G53 G0 Z0.", 0.0}, {"G53 Z-10.", 10.0}}) {
      const double gap = m.z.max - below - top;
      const ProgramCheckResult clear = run(dialect, retract, gap - 1.0);
      EXPECT_TRUE(clear.violations.empty()) << dialect << " " << retract << "\n" << describe(clear);
      const ProgramCheckResult hit = run(dialect, retract, gap + 1.0);
      const ProgramViolation* v = find(hit, "table");
      ASSERT_NE(v, nullptr) << dialect << " " << retract << "\n" << describe(hit);
      EXPECT_EQ(v->line, 8) << describe(hit);
    }
    const ProgramCheckResult xz = run(dialect, "G91 G28 X0 Z0", 10.0);
    ASSERT_NE(find(xz, "G28 moves in machine coordinates"), nullptr) << describe(xz);
    EXPECT_EQ(find(xz, "G28 moves in machine coordinates")->line, 6);
    EXPECT_FALSE(run(dialect, "G91 G28 Z5.", 10.0).violations.empty());  // an intermediate point: not followed
    EXPECT_FALSE(run(dialect, "G53 Z10.", 10.0).violations.empty());      // above the reference
    // The retract and the end in one block: the program ends there, as with M30 on its own.
    const std::vector<nc::Motion> ending = ctl::readMotions(dialect, "%\nO1000\nG90 G21\nG0 Z100.\nG91 G28 Z0 M30\n%\n");
    ASSERT_FALSE(ending.empty());
    EXPECT_EQ(ending.back().kind, nc::Motion::Kind::End) << dialect;
    EXPECT_EQ(ending.back().line, 5) << dialect;
    ASSERT_GE(ending.size(), 2u);
    EXPECT_TRUE(ending[ending.size() - 2].z_from_reference.has_value()) << dialect;
  }
  const std::string ngc = "G21 G90\nG0 Z100.\nG91 G28 Z0\nG90\nM2\n";
  ProgramCheckSetup s = programCheckSetup(m, "linuxcnc", false, nullptr, false);
  s.part_program = true;
  const ProgramCheckResult lcnc = checkProgram(ctl::readMotions("linuxcnc", ngc), s);
  ASSERT_EQ(lcnc.violations.size(), 1u) << describe(lcnc);
  EXPECT_EQ(lcnc.violations.front().problem, "G28 moves in machine coordinates: the verifier follows program coordinates only");
}

}  // namespace
}  // namespace rotacal
