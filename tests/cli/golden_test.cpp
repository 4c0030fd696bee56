// Golden example programs (examples/programs/, scripts/golden.sh) and the CLI's behaviour on a
// malformed results file, for every dialect.
//  - Regenerating the examples with the current build gives the committed files byte for byte,
//    so any change to a program, results or offsets writer is a reviewed diff of those files.
//  - The committed sample results of every dialect, parsed and identified, give the same
//    location errors as the committed csv sample (the same simulated run) within the printed
//    digits' effect, and the injected truth within the noise's.
//  - `rotacal analyze` on a malformed results file exits 1, names file and line, and writes
//    none of --json, --text, --offsets.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "controllers/dialect.hpp"
#include "cycles/touch154/identification.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;
using test::slurp;

/// A whole command line (golden.sh, diff), stdout and stderr together.
using ShellRun = test::CliRun;
ShellRun sh(const std::string& cmd) { return test::runCommand(cmd + " 2>&1"); }


const std::vector<std::string> kDialects = dialectNames();

std::string resultsName(const std::string& d) { return d == "csv" ? "results.csv" : "results.txt"; }


/// Relative paths of the regular files under `dir`.
std::set<std::string> filesUnder(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out.insert(fs::relative(e.path(), dir).generic_string());
  return out;
}

TEST(Golden, RegeneratedExamplesEqualTheCommittedOnesByteForByte) {
  const fs::path committed = test::sourcePath("examples/programs");
  const fs::path out = test::freshDir("golden") / "programs";
  const ShellRun r = sh("bash " + test::sourcePath("scripts/golden.sh") + " " + ROTACAL_CLI + " " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto generated = filesUnder(out);
  auto expected = filesUnder(committed);
  expected.erase("README.md");  // written by hand
  expected.erase(".gitattributes");
  EXPECT_EQ(generated, expected);
  // Every dialect: program (csv has none), results and offsets.
  for (const auto& d : kDialects) {
    EXPECT_EQ(generated.count(d + "/" + resultsName(d)), 1u) << d;
    int in_dir = 0;
    for (const auto& f : generated) in_dir += f.rfind(d + "/", 0) == 0;
    EXPECT_EQ(in_dir, d == "csv" ? 2 : 3) << d;
  }
  for (const auto& f : generated) {
    if (!expected.count(f)) continue;
    const std::string a = slurp(out / f), b = slurp(committed / f);
    EXPECT_TRUE(a == b) << f << " differs from the committed golden file: rerun scripts/golden.sh and review the diff";
  }
}

TEST(Golden, EverySampleIdentifiesAsTheCsvSampleAndTheTruth) {
  const ProbePlan plan = loadPlan(test::sourcePath("examples/programs/plan.json"));
  auto identifyFile = [&](const std::string& d) {
    const std::string f = test::sourcePath("examples/programs/" + d + "/" + resultsName(d));
    const MeasurementRun run = dialectByName(d).parseResults(slurp(f), f, plan);
    return identify(plan, {run}, IdentificationOptions{});
  };
  const IdentificationResult csv = identifyFile("csv");
  ASSERT_EQ(csv.summary.termination, Termination::Converged) << csv.summary.message;
  const LocationErrors truth = test::table4Mean();
  const auto& params = locationParameters(Kinematics::TableAC);
  for (const auto& d : kDialects) {
    const IdentificationResult r = identifyFile(d);
    ASSERT_EQ(r.summary.termination, Termination::Converged) << d << ": " << r.summary.message;
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const bool length = params[static_cast<size_t>(i)].kind == ParamKind::Length;
      const double u = length ? mmToUm(r.u[i]) : radToMdeg(r.u[i]);
      // Same simulated triggers, printed with 4 decimals (linuxcnc 6): 000 Table 4's errors move
      // by at most ~0.04 um / mdeg through that rounding (digits_bound_test computes the exact
      // bound); 0.1 um / mdeg is a loose ceiling for a sample file.
      EXPECT_NEAR(r.estimate.reportValue(i), csv.estimate.reportValue(i), 0.1) << d << " " << params[i].name;
      // 0.7 um noise: within 5 standard uncertainties of the injected truth.
      EXPECT_NEAR(r.estimate.reportValue(i), truth.reportValue(i), 5 * u) << d << " " << params[i].name;
    }
  }
}

TEST(CliMalformed, AnalyzeExitsOneNamesFileAndLineAndWritesNothing) {
  const fs::path dir = test::freshDir("cli_malformed");
  for (const auto& d : kDialects) {
    const std::string good = slurp(test::sourcePath("examples/programs/" + d + "/" + resultsName(d)));
    // Three kinds per dialect: a line cut off (file ends inside point 100's line), a NUL byte in
    // point 5's line (0x01 for the DPRNT dialects, where NUL is a punch feed code), and the
    // values of points 10 and 11 exchanged.
    std::vector<std::string> ls;
    {
      std::string cur;
      for (char c : good) {
        if (c == '\n') {
          ls.push_back(cur);
          cur.clear();
        } else {
          cur += c;
        }
      }
    }
    const size_t first = d == "fanuc" || d == "haas" ? 2 : 1;
    const size_t stride = d == "heidenhain" ? 2 : 1;
    auto at = [&](int k) { return first + static_cast<size_t>(k - 1) * stride; };
    auto joined = [](const std::vector<std::string>& v, size_t n) {
      std::string s;
      for (size_t i = 0; i < n; ++i) s += v[i] + "\n";
      return s;
    };
    struct Bad {
      std::string text;
      int line;
    };
    std::vector<Bad> bads;
    bads.push_back({joined(ls, at(100)) + ls[at(100)].substr(0, 9), static_cast<int>(at(100)) + 1});
    auto v = ls;
    v[at(5)].insert(2, 1, d == "fanuc" || d == "haas" ? '\x01' : '\0');
    bads.push_back({joined(v, v.size()), static_cast<int>(at(5)) + 1});
    v = ls;
    std::swap(v[at(10)], v[at(11)]);  // the lines, ids included: then fix the ids back
    const char id_end = d == "csv" ? ',' : d == "linuxcnc" ? ' ' : 'X';
    const auto id10 = ls[at(10)].substr(0, ls[at(10)].find(id_end));
    const auto id11 = ls[at(11)].substr(0, ls[at(11)].find(id_end));
    v[at(10)] = id10 + v[at(10)].substr(id11.size());
    v[at(11)] = id11 + v[at(11)].substr(id10.size());
    bads.push_back({joined(v, v.size()), static_cast<int>(at(10)) + 1});
    for (size_t k = 0; k < bads.size(); ++k) {
      SCOPED_TRACE(d + " kind " + std::to_string(k));
      const fs::path res = dir / (d + "_bad" + std::to_string(k) + ".txt");
      std::ofstream(res, std::ios::binary) << bads[k].text;
      const fs::path json = dir / "r.json", text = dir / "r.txt", off = dir / "off.out";
      const ShellRun r = sh(std::string(ROTACAL_CLI) + " analyze --plan " + test::sourcePath("examples/programs/plan.json") +
                       " --results " + res.string() + " --dialect " + d + " --json " + json.string() + " --text " +
                       text.string() + " --offsets " + off.string());
      EXPECT_EQ(r.code, 1) << r.out;
      const std::string expected = "rotacal: error: " + res.string() + ":" + std::to_string(bads[k].line) + ": ";
      EXPECT_EQ(r.out.rfind(expected, 0), 0u) << r.out;
      EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
      EXPECT_FALSE(fs::exists(json));
      EXPECT_FALSE(fs::exists(text));
      EXPECT_FALSE(fs::exists(off));
    }
  }
}

TEST(CliInch, EveryDialectRoundTripsOnAnInchCopyOfTheMachine) {
  // The bundled A/C machine declared inch: every program is written in inch (G20 / G70;
  // Heidenhain stays MM, see docs/dialects.md), every results file in the dialect's inch form,
  // and analysis through each dialect gives the csv path's errors.
  const fs::path dir = test::freshDir("cli_inch");
  std::string machine = slurp(test::sourcePath("examples/machines/ac_trunnion.json"));
  const size_t at = machine.find("\"units\": \"mm\"");
  ASSERT_NE(at, std::string::npos);
  machine.replace(at, 13, "\"units\": \"inch\"");
  const std::string contributors = "\"../contributors/table5.json\"";  // relative to the original
  const size_t c = machine.find(contributors);
  ASSERT_NE(c, std::string::npos);
  machine.replace(c, contributors.size(), "\"" + test::sourcePath("examples/contributors/table5.json") + "\"");
  std::ofstream(dir / "ac_inch.json") << machine;
  const std::string plan = (dir / "plan.json").string();
  const std::string cli = ROTACAL_CLI;
  ASSERT_EQ(sh(cli + " plan --cycle touch154 --machine " + (dir / "ac_inch.json").string() + " -o " + plan).code, 0);
  const std::string truth = test::sourcePath("examples/truth/table4_mean.json");
  std::map<std::string, std::vector<double>> values;
  const char* names[8] = {"dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA"};
  for (const auto& d : kDialects) {
    SCOPED_TRACE(d);
    if (d != "csv") {
      const std::string prog = (dir / ("touch154_" + d)).string();
      const ShellRun g = sh(cli + " generate --plan " + plan + " --dialect " + d + " -o " + prog);
      ASSERT_EQ(g.code, 0) << g.out;  // generate runs the dialect's strict checker
      const std::string text = slurp(prog);
      const std::string unit_word = d == "siemens" ? "\nG70\n" : d == "heidenhain" ? " MM\n" : "\nG20\n";
      EXPECT_NE(text.find(unit_word), std::string::npos) << unit_word;
    }
    const std::string res = (dir / ("results_" + d)).string();
    ASSERT_EQ(sh(cli + " simulate --plan " + plan + " --truth " + truth + " --start-s 750000000 --dialect " + d + " -o " +
                 res).code,
              0);
    if (d != "csv" && d != "heidenhain") {
      EXPECT_NE(slurp(res).find(d == "linuxcnc" ? "unit=inch" : "UNIT INCH"), std::string::npos);
    }
    const std::string report = (dir / ("report_" + d + ".json")).string();
    const ShellRun a = sh(cli + " analyze --plan " + plan + " --results " + res + " --dialect " + d + " --json " + report);
    ASSERT_EQ(a.code, 0) << a.out;
    const auto j = nlohmann::json::parse(slurp(report));
    for (const char* n : names) values[d].push_back(j["location_errors"][n]["value"].get<double>());
  }
  for (const auto& d : kDialects)
    for (int i = 0; i < 8; ++i) {
      // 5 inch decimals round each coordinate by up to 0.127 um; digits_bound_test computes the
      // bound per parameter on this plan: at most 0.32 um / 0.09 mdeg (LinuxCNC's 6 decimals:
      // 0.1 of that; Heidenhain prints 4 mm decimals: 0.13 um / 0.035 mdeg).
      const double tol = d == "linuxcnc" ? 0.04 : d == "heidenhain" ? 0.13 : (i < 4 ? 0.32 : 0.09);
      EXPECT_NEAR(values[d][static_cast<size_t>(i)], values["csv"][static_cast<size_t>(i)], tol) << d << " " << names[i];
    }
}

}  // namespace
}  // namespace rotacal
