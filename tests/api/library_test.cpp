// The public library as a post uses it (<rotacal/rotacal.hpp> only): a LinuxCNC program
// compensated for a report of `analyze` must be the very text `rotacal compensate` writes, and
// say what it says; the verifier must say what `rotacal check` says; bad input is one Error.
#include <rotacal/rotacal.hpp>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_run.hpp"

namespace rotacal::test {
namespace {

std::vector<std::string> linesOf(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

class Library : public ScratchTest {
 protected:
  const std::string program = sourcePath("examples/programs/linuxcnc/touch154.ngc");
  const std::string machine = sourcePath("examples/machines/ac_trunnion.json");

  // A report of the bundled simulated results (examples/programs: 000 Table 4's errors, 0.7 um noise).
  std::string report() {
    const std::string path = p("REPORT.json");
    const auto a = sh("analyze --plan " + sourcePath("examples/programs/plan.json") + " --results " +
                      sourcePath("examples/programs/linuxcnc/results.txt") + " --dialect linuxcnc --json " + path);
    EXPECT_EQ(a.code, 0) << a.out;
    return path;
  }
};

TEST_F(Library, CompensatesAsTheCommandLineDoes) {
  const std::string rep = report();
  const std::string out = p("touch154_c.ngc");
  const auto cli = sh("compensate --program " + program + " --report " + rep + " --dialect linuxcnc -o " + out);
  ASSERT_EQ(cli.code, 0) << cli.out;

  CompensateRequest request;
  request.program = {program, slurp(program)};
  request.reports = {{rep, slurp(rep)}};
  request.dialect = "linuxcnc";
  request.output_name = out;
  const CompensateResult r = compensate(request);
  EXPECT_EQ(r.text, slurp(out));
  EXPECT_EQ(r.messages, linesOf(cli.out));
  EXPECT_GT(r.compensated_blocks, 100);
  EXPECT_EQ(r.motion_blocks, r.compensated_blocks + r.uncompensated_blocks);
  EXPECT_GT(r.max_shift_um, 10.0);  // Table 4's errors move the tool point by tens of um
  EXPECT_TRUE(r.position_uncertainty_k2_um.has_value());

  // The machine given separately (MACHINE.json) is the one the report carries: the same program.
  request.machine = NamedText{machine, slurp(machine)};
  EXPECT_EQ(compensate(request).text, r.text);
}

TEST_F(Library, ChecksAsTheCommandLineDoes) {
  const auto cli = sh("check " + program + " --dialect linuxcnc --machine " + machine);
  ASSERT_EQ(cli.code, 0) << cli.out;
  CheckRequest request;
  request.program = {program, slurp(program)};
  request.machine = {machine, slurp(machine)};
  request.dialect = "linuxcnc";
  request.rotacal_program = true;
  const CheckResult r = check(request);
  ASSERT_TRUE(r.ok()) << r.violations.front().problem;
  EXPECT_EQ(r.summary, linesOf(cli.out).front());
  EXPECT_EQ(r.probing_moves, 154);

  // A move out of the strokes is a violation at its line, not an exception.
  request.program.text = "G21\nG17 G40 G49 G54 G80 G90 G94\nG0 Z390.0\nG1 X5000.0 F1000.0\nM2\n";
  request.rotacal_program = false;
  const CheckResult bad = check(request);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.violations.front().line, 4);
  EXPECT_TRUE(bad.summary.empty());
}

TEST_F(Library, BadInputIsOneErrorOfOneLine) {
  CompensateRequest request;
  request.program = {program, slurp(program)};
  request.reports = {{"bad.json", "{\n  \"format\": \"rotacal-report/1\",\n  \"location_errors\": {,\n}\n"}};
  request.dialect = "linuxcnc";
  try {
    compensate(request);
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.rfind("bad.json:3: invalid JSON", 0), 0u) << what;
    EXPECT_EQ(e.input(), "bad.json");
    EXPECT_EQ(e.line(), 3);
  }
  // An Error is a std::runtime_error; a dialect without programs to compensate is one too.
  request.dialect = "heidenhain";
  EXPECT_THROW(compensate(request), std::runtime_error);
  EXPECT_THROW(Compensator({{"bad.json", "{"}}, "linuxcnc"), Error);
}

TEST(LibraryVersion, IsTheHeadersVersion) { EXPECT_EQ(version(), ROTACAL_VERSION_STRING); }

}  // namespace
}  // namespace rotacal::test
