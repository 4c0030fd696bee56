// The calibration history: the drift and step tests against series whose answer is known in
// closed form, their false-alarm rate against the stated alpha (Monte Carlo), the SQLite store
// (round trip, concurrent writers, damaged files), and the whole chain through the command
// line: a Table-4-like machine that drifts in dz_AY and is knocked in dx_AY, simulated,
// analyzed, added, shown.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include <sqlite3.h>

#include "core/errors.hpp"
#include "core/json_io.hpp"
#include "history/store.hpp"
#include "history/trend.hpp"
#include "history/trend_report.hpp"
#include "cli/cli_run.hpp"
#include "test_util.hpp"

namespace rotacal::history {
namespace {

namespace fs = std::filesystem;

using ShellRun = test::CliRun;
/// A whole command line, stdout and stderr together.
ShellRun sh(const std::string& cmd) { return test::runCommand(cmd + " 2>&1"); }
const std::string kCli = ROTACAL_CLI;

fs::path freshDir() { return test::freshDir("history_" + test::testName()); }

std::vector<TrendPoint> series(const std::vector<double>& t, const std::vector<double>& v, double u) {
  std::vector<TrendPoint> p;
  for (size_t i = 0; i < t.size(); ++i) p.push_back({t[i], v[i], u});
  return p;
}

TEST(Trend, ChiSquareQuantileMatchesKnownValues) {
  // chi^2(1): P(X > 3.841459) = 0.05, P(X > 10.827566) = 0.001 (tables).
  EXPECT_NEAR(chiSquareQuantileUpper(0.05, 1), 3.841459, 1e-5);
  EXPECT_NEAR(chiSquareQuantileUpper(0.001, 1), 10.827566, 1e-5);
}

TEST(Trend, ClosedFormSeries) {
  const TrendOptions o;
  const std::vector<double> t = {0, 1, 2, 3, 10, 11};
  // Constant: stable, chi^2 = 0.
  auto c = analyzeTrend(series(t, {5, 5, 5, 5, 5, 5}, 0.3), o);
  EXPECT_EQ(c.verdict, "stable");
  EXPECT_NEAR(c.chi2_constant, 0.0, 1e-18);
  // A line of 0.5 per day, exactly: drift, slope 0.5, never a step (a line beats any step).
  auto d = analyzeTrend(series(t, {1, 1.5, 2, 2.5, 6, 6.5}, 0.3), o);
  EXPECT_EQ(d.verdict, "drift");
  EXPECT_NEAR(d.drift_per_day, 0.5, 1e-12);
  EXPECT_NEAR(d.drift_u, 0.3 / std::sqrt(235.0 - 27.0 * 27.0 / 6.0), 1e-12);  // u / sqrt(Sxx)
  // A step of 15 after the 4th: step after index 3, size 15, no drift.
  auto s = analyzeTrend(series(t, {14.6, 14.6, 14.6, 14.6, 29.6, 29.6}, 0.3), o);
  EXPECT_EQ(s.verdict, "step");
  ASSERT_TRUE(s.step_after.has_value());
  EXPECT_EQ(*s.step_after, 3);
  EXPECT_NEAR(s.step_size, 15.0, 1e-9);
  // Too few.
  EXPECT_EQ(analyzeTrend(series({0, 1}, {1, 2}, 0.1), o).verdict, "too few calibrations");
}

TEST(Trend, FalseAlarmRateIsAlpha) {
  // Constant truth, Gaussian noise of the stated u: the drift test must fire in alpha of the
  // series, and the step test (Bonferroni over the splits) at most alpha. 20000 series, alpha
  // 0.01: binomial standard deviation 0.0007, so [0.007, 0.013] is over 4 sigma wide.
  TrendOptions o;
  o.alpha = 0.01;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  const std::vector<double> t = {0, 1, 2, 3, 10, 11, 12, 20};
  int drift = 0, step = 0;
  const int trials = 20000;
  for (int k = 0; k < trials; ++k) {
    std::vector<TrendPoint> p;
    for (double ti : t) p.push_back({ti, 3.0 + 0.5 * n(rng), 0.5});
    const Trend tr = analyzeTrend(p, o);
    drift += tr.drift && !tr.step;
    step += tr.step;
  }
  EXPECT_GT(drift / double(trials), 0.007);
  EXPECT_LT(drift / double(trials), 0.013);
  EXPECT_LT(step / double(trials), 0.013);
}

Calibration sample(const std::string& machine, double t_s, double dx) {
  Calibration c;
  c.machine_id = machine;
  c.time_s = t_s;
  c.time_utc = isoTime(t_s);
  c.cycle = "touch154";
  c.method = "lsq_per_point";
  c.machine_name = "m";
  c.source = "REPORT.json";
  c.residual_rms_um = 0.7;
  c.points_used = 154;
  c.plan_json = "{}";
  c.parameters = {{"dx_AY", "X0A", "um", dx, 0.3}, {"a_AY", "A0A", "mdeg", -0.5, 0.01}};
  return c;
}

// With fewer than 3 calibrations the shown value is the latest, not a mean, and no drift was
// tested: the text says so instead of printing "0.000 (0.000)" as if it had been measured.
TEST(Trend, FewerThanThreeCalibrationsShowTheLatestAndNoDrift) {
  const std::vector<Calibration> two = {sample("m", 0.0, 10.0), sample("m", 86400.0, 12.0)};
  const Json h2 = historyJson("m", two, TrendOptions{});
  EXPECT_EQ(h2["trends"]["dx_AY"]["value_is"], "latest");
  EXPECT_FALSE(h2["trends"]["dx_AY"]["drift_evaluated"].get<bool>());
  EXPECT_DOUBLE_EQ(h2["trends"]["dx_AY"]["mean"].get<double>(), 12.0);
  const std::string t2 = historyText(h2);
  EXPECT_NE(t2.find("12.000 latest                -"), std::string::npos) << t2;
  EXPECT_EQ(t2.find("(0.000)"), std::string::npos) << t2;
  std::vector<Calibration> three = two;
  three.push_back(sample("m", 2 * 86400.0, 14.0));
  const Json h3 = historyJson("m", three, TrendOptions{});
  EXPECT_EQ(h3["trends"]["dx_AY"]["value_is"], "mean");
  // The weighted mean of 10, 12, 14 with equal u, and their slope of 2 um/day.
  EXPECT_NEAR(h3["trends"]["dx_AY"]["mean"].get<double>(), 12.0, 1e-9);
  EXPECT_NEAR(h3["trends"]["dx_AY"]["drift_per_day"].get<double>(), 2.0, 1e-9);
  EXPECT_NE(historyText(h3).find("12.000 mean      2.000 ("), std::string::npos) << historyText(h3);
}

TEST(Store, RoundTripInTimeOrder) {
  const fs::path d = freshDir();
  const std::string db_path = (d / "sub" / "h.sqlite").string();  // the directory is created
  {
    Database db(db_path);
    db.add(sample("m1", parseIsoTime("2026-03-02"), 2.0));
    db.add(sample("m1", parseIsoTime("2026-03-01T12:00:00Z"), 1.0));
    db.add(sample("m2", parseIsoTime("2026-03-01"), 9.0));
  }
  const Database db(db_path, false);
  const auto l = db.list("m1");
  ASSERT_EQ(l.size(), 2u);
  EXPECT_EQ(l[0].time_utc, "2026-03-01T12:00:00Z");
  EXPECT_DOUBLE_EQ(l[0].parameters[0].value, 1.0);
  EXPECT_DOUBLE_EQ(l[1].parameters[0].value, 2.0);
  EXPECT_EQ(l[1].parameters[1].iso, "A0A");
  EXPECT_EQ(db.machines(), (std::vector<std::string>{"m1", "m2"}));
  EXPECT_THROW(parseIsoTime("1.3.2026"), std::invalid_argument);
}

TEST(Store, GarbageFileIsRefusedClearly) {
  const fs::path d = freshDir();
  const std::string path = (d / "h.sqlite").string();
  std::ofstream(path) << std::string(8192, 'x');
  try {
    Database db(path);
    FAIL() << "opened a file of garbage";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a rotacal history database, or damaged"), std::string::npos) << e.what();
  }
}

TEST(Store, DamagedPagesAreFoundOnOpen) {
  const fs::path d = freshDir();
  const std::string path = (d / "h.sqlite").string();
  {
    Database db(path);
    for (int i = 0; i < 200; ++i) db.add(sample("m1", 1.7e9 + i * 86400.0, i));
  }
  // Checkpointed on close: the data sit in the main file. Overwrite its pages after the first.
  const auto size = fs::file_size(path);
  ASSERT_GT(size, 16384u);
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(4096);
    const std::string junk(static_cast<size_t>(size) - 4096, '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  try {
    Database db(path, false);
    (void)db.list("m1");
    FAIL() << "read a damaged database without complaint";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  // Through the command line: exit 1, one line naming the file.
  const ShellRun r = sh(kCli + " history show --machine-id m1 --db " + path);
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("rotacal: error: " + path), std::string::npos) << r.out;
}

TEST(Store, ConcurrentAddsFromSeveralProcesses) {
  const fs::path d = freshDir();
  const std::string path = (d / "h.sqlite").string();
  const std::string report = (d / "REPORT.json").string();
  std::ofstream(report) << R"({"format": "rotacal-report/1", "cycle": "touch154", "machine": "m",
    "method": "lsq_per_point", "residual_rms_um": 0.7, "points_used": 154,
    "location_errors": {"dx_AY": {"value": 14.6, "unit": "um", "u": 0.3, "iso": "X0A"},
                        "a_AY": {"value": -0.5, "unit": "mdeg", "u": 0.01, "iso": "A0A"}}})";
  // 6 processes x 8 adds each, started together, no database file yet (they race to create it).
  const int procs = 6, adds = 8;
  std::string script = "set -e; pids=; for p in $(seq 1 " + std::to_string(procs) + "); do ( for k in $(seq 1 " +
                       std::to_string(adds) + "); do " + kCli + " -q history add " + report +
                       " --machine-id mc --time 2026-01-0${k}T0${p}:00:00Z --db " + path +
                       " || exit 1; done ) & pids=\"$pids $!\"; done; for q in $pids; do wait $q; done";
  const ShellRun r = sh("bash -c '" + script + "'");
  ASSERT_EQ(r.code, 0) << r.out;
  const Database db(path, false);  // quick_check passes on open
  const auto l = db.list("mc");
  ASSERT_EQ(l.size(), static_cast<size_t>(procs * adds));
  std::set<long long> ids;
  for (const auto& c : l) {
    ids.insert(c.id);
    EXPECT_EQ(c.parameters.size(), 2u);
  }
  EXPECT_EQ(ids.size(), l.size());
}

std::string truthJson(double dx_um, double dz_um) {
  return fmt::format(R"({{"format": "rotacal-truth/1", "location_errors": {{
      "dx_AY": {{"value": {}, "unit": "um"}}, "dy_AY": {{"value": 23.2, "unit": "um"}},
      "dz_AY": {{"value": {}, "unit": "um"}}, "dy_CA": {{"value": 3.9, "unit": "um"}},
      "a_AY": {{"value": -0.5, "unit": "mdeg"}}, "b_AY": {{"value": -0.1, "unit": "mdeg"}},
      "c_AY": {{"value": -0.5, "unit": "mdeg"}}, "b_CA": {{"value": 0.2, "unit": "mdeg"}}}},
    "setup_error": {{"translation_mm": [0.5, 0.5, 0.0], "rotation_mrad": [0.0, 0.0, 2.0]}},
    "form_error": {{"top": {{"tilt_v_mrad": 2.0}}}},
    "probe_noise_um": 0.7}})",
                     dx_um, dz_um);
}

TEST(HistoryCli, Table4SeriesDriftThenAStep) {
  // 000 Table 4's machine, calibrated on days 0-3 (the four repeats) while dz_AY grows 2 um/day
  // (thermal growth of the column, 000 Sec. 4.4 suspects it), then on days 10 and 11 after a
  // crash moved the C axis: dx_AY +15 um. Expected: dz_AY drift (2 um/day), dx_AY a step of
  // 15 um after calibration #4, every other parameter stable.
  const fs::path d = freshDir();
  const std::string db = (d / "h.sqlite").string(), plan = (d / "plan.json").string();
  ASSERT_EQ(sh(kCli + " plan --cycle touch154 --machine " + test::sourcePath("examples/machines/ac_trunnion.json") + " -o " + plan).code, 0);
  const std::vector<int> days = {0, 1, 2, 3, 10, 11};
  for (size_t i = 0; i < days.size(); ++i) {
    const double dx = 14.6 + (days[i] >= 10 ? 15.0 : 0.0), dz = 27.7 + 2.0 * days[i];
    const std::string tr = (d / fmt::format("truth{}.json", i)).string(), res = (d / fmt::format("r{}.csv", i)).string(),
                      rep = (d / fmt::format("REPORT{}.json", i)).string();
    std::ofstream(tr) << truthJson(dx, dz);
    ASSERT_EQ(sh(kCli + " simulate --plan " + plan + " --truth " + tr + " --seed " + std::to_string(i + 11) +
                 " --dialect csv -o " + res).code, 0);
    ASSERT_EQ(sh(kCli + " -q analyze --plan " + plan + " --results " + res + " --dialect csv --json " + rep).code, 0);
    const ShellRun add = sh(kCli + " history add " + rep + " --machine-id dmg1 --db " + db +
                       fmt::format(" --time 2026-05-{:02d}T08:00:00Z", 1 + days[i]));
    ASSERT_EQ(add.code, 0) << add.out;
  }
  const std::string trend = (d / "TREND.json").string(), html = (d / "history.html").string();
  const ShellRun show = sh(kCli + " history show --machine-id dmg1 --db " + db + " --json " + trend + " --html " + html);
  ASSERT_EQ(show.code, 0) << show.out;
  std::ifstream in(trend);
  const Json h = Json::parse(in);
  ASSERT_EQ(h["calibrations"].size(), 6u);
  const Json& t = h["trends"];
  EXPECT_EQ(t["dz_AY"]["verdict"], "drift") << t["dz_AY"].dump();
  // 2 um/day injected; u of one dz_AY is ~0.1 um, of the slope ~0.01 um/day: 0.1 um/day is ample.
  EXPECT_NEAR(t["dz_AY"]["drift_per_day"].get<double>(), 2.0, 0.1);
  EXPECT_EQ(t["dx_AY"]["verdict"], "step") << t["dx_AY"].dump();
  EXPECT_EQ(t["dx_AY"]["step_after_seq"], 4);
  // Within 3 standard uncertainties of the step (about 0.5 um here: the slope is fitted too).
  EXPECT_NEAR(t["dx_AY"]["step_size"].get<double>(), 15.0, 3 * t["dx_AY"]["step_u"].get<double>());
  EXPECT_NEAR(t["dx_AY"]["drift_per_day"].get<double>(), 0.0, 3 * t["dx_AY"]["drift_u_per_day"].get<double>());
  for (const char* name : {"dy_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA"})
    EXPECT_EQ(t[name]["verdict"], "stable") << name << " " << t[name].dump();
  EXPECT_EQ(h["figures"].size(), 8u);
  EXPECT_TRUE(fs::exists(html));
  // `--json -` puts the document on stdout and nothing else.
  const ShellRun piped = sh(kCli + " history show --machine-id dmg1 --db " + db + " --json -");
  ASSERT_EQ(piped.code, 0);
  EXPECT_EQ(Json::parse(piped.out)["trends"], t);
}

TEST(HistoryCli, AHeadMachinesGrowingSpindleIsADrift) {
  // A head/head machine (examples/machines/ab_head.json) calibrated with one_sphere on
  // days 0-4 while its spindle grows 3 um/day (dL) and the sphere is set up anew each day. Its
  // report carries the head's ISO 230-7 parameters as kinematic_parameters: history trends the
  // fitted ones (dL: a drift of 3 um/day; the axes' errors stable) and leaves the sphere's set-up
  // and the held parameters out.
  const fs::path d = freshDir();
  const std::string db = (d / "h.sqlite").string(), plan = (d / "plan.json").string();
  ASSERT_EQ(sh(kCli + " plan --cycle one_sphere --machine " + test::sourcePath("examples/machines/ab_head.json") + " -o " + plan).code, 0);
  for (int day = 0; day <= 4; ++day) {
    const std::string tr = (d / fmt::format("truth{}.json", day)).string(), res = (d / fmt::format("r{}.txt", day)).string(),
                      rep = (d / fmt::format("REPORT{}.json", day)).string();
    std::ofstream(tr) << fmt::format(
        R"({{"format": "rotacal-truth/1", "location_errors": {{"B0A": {{"value": 15, "unit": "mdeg"}},
           "C0A": {{"value": -9, "unit": "mdeg"}}, "Z0B": {{"value": -11, "unit": "um"}}, "dL": {{"value": {}, "unit": "um"}},
           "dX_S": {{"value": {}, "unit": "um"}}, "dY_S": {{"value": {}, "unit": "um"}}}}, "probe_noise_um": 0.7}})",
        14.0 + 3.0 * day, 40.0 * day - 50.0, 25.0 - 30.0 * day);
    ASSERT_EQ(sh(kCli + " simulate --plan " + plan + " --truth " + tr + " --seed " + std::to_string(day + 21) +
                 " --dialect linuxcnc -o " + res).code, 0);
    ASSERT_EQ(sh(kCli + " -q analyze --plan " + plan + " --results " + res + " --dialect linuxcnc --json " + rep).code, 0);
    const ShellRun add = sh(kCli + " history add " + rep + " --machine-id head1 --db " + db +
                            fmt::format(" --time 2026-06-{:02d}T08:00:00Z", 1 + day));
    ASSERT_EQ(add.code, 0) << add.out;
  }
  const std::string trend = (d / "TREND.json").string();
  const ShellRun show = sh(kCli + " history show --machine-id head1 --db " + db + " --json " + trend);
  ASSERT_EQ(show.code, 0) << show.out;
  std::ifstream in(trend);
  const Json t = Json::parse(in)["trends"];
  EXPECT_EQ(t["dL"]["verdict"], "drift") << t["dL"].dump();
  EXPECT_NEAR(t["dL"]["drift_per_day"].get<double>(), 3.0, 3 * t["dL"]["drift_u_per_day"].get<double>());
  for (const char* name : {"B0A", "C0A", "A0A", "Z0B", "C0B", "B0B", "dY_T"})
    EXPECT_EQ(t[name]["verdict"], "stable") << name << " " << t[name].dump();
  for (const char* name : {"dX_S", "dY_S", "dZ_S", "Y0A", "X0B", "dX_T"}) EXPECT_FALSE(t.contains(name)) << name;
}

// ---- Issue 14: damaged rows, strict dates, the handle of a file that fails to open ----------

/// Runs SQL on a history file behind the store's back (what a damaged or hand-edited file holds).
void tamper(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  EXPECT_EQ(rc, SQLITE_OK) << (err ? err : "");
  sqlite3_free(err);
  sqlite3_close(db);
}

TEST(Store, DamagedRowsAreRefusedNamingTheFile) {
  // Each tampering used to show as 0.000 or -nan with the verdict "stable".
  const std::vector<std::string> damage = {
      "UPDATE parameter SET u = -1 WHERE name = 'dx_AY'",
      "UPDATE parameter SET value = 'abc' WHERE name = 'a_AY'",
      "UPDATE parameter SET iso = x'00ff' WHERE name = 'a_AY'",
      "UPDATE calibration SET residual_rms_um = 'n/a'",
      "UPDATE calibration SET time_s = 1e300",
  };
  for (const auto& sql : damage) {
    SCOPED_TRACE(sql);
    const fs::path d = freshDir();
    const std::string path = (d / "h.sqlite").string();
    {
      Database db(path);
      for (int i = 0; i < 3; ++i) db.add(sample("m1", 1.7e9 + i * 86400.0, i));
    }
    tamper(path, sql);
    try {
      const Database db(path, false);
      (void)db.list("m1");
      ADD_FAILURE() << "read without complaint";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_NE(std::string(e.what()).find("damaged history"), std::string::npos) << e.what();
    }
    const ShellRun r = sh(kCli + " history show --machine-id m1 --db " + path);
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_EQ(r.out.rfind("rotacal: error: " + path + ":", 0), 0u) << r.out;
  }
}

int openDescriptors() {
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator("/proc/self/fd")) ++n;
  return n;
}

TEST(Store, AFileThatFailsToOpenIsClosed) {
  // The handle used to stay open when the constructor threw (LeakSanitizer): its descriptor
  // shows in /proc/self/fd.
  const fs::path d = freshDir();
  const std::string path = (d / "h.sqlite").string();
  std::ofstream(path) << std::string(8192, 'x');
  const int before = openDescriptors();
  for (int i = 0; i < 20; ++i) EXPECT_THROW(Database(path, false), InputError);
  EXPECT_EQ(openDescriptors(), before);
}

TEST(Store, DatesThatDoNotExistAreRefused) {
  for (const char* bad : {"2024-02-31", "2023-02-29", "2024-04-31", "2024-13-01", "2024-00-10", "2024-01-00",
                          "2024-01-01T24:00:00Z", "2024-01-01T12:60:00Z", "2024-01-01T12:00:60Z", " 2024-01-01",
                          "2024-1-01 ", "+024-01-01", "1969-12-31", "2024-01-01T12:00:00"})
    EXPECT_THROW(parseIsoTime(bad), std::invalid_argument) << bad;
  // A leap day exists: one day before 1 March (the calendar's count, not timegm's).
  EXPECT_DOUBLE_EQ(parseIsoTime("2024-02-29"), parseIsoTime("2024-03-01") - 86400.0);
  EXPECT_DOUBLE_EQ(parseIsoTime("2000-02-29T23:59:59Z"), 951868799.0);  // 11016 days + 86399 s
  const fs::path d = freshDir();
  const std::string report = (d / "REPORT.json").string(), db = (d / "h.sqlite").string();
  std::ofstream(report) << R"({"format": "rotacal-report/1", "cycle": "touch154", "residual_rms_um": 0.7,
    "location_errors": {"dx_AY": {"value": 14.6, "unit": "um", "u": 0.3}}})";
  const ShellRun r = sh(kCli + " history add " + report + " --machine-id m --db " + db + " --time 2024-02-31");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_FALSE(fs::exists(db));
}

TEST(Store, AReportWithANegativeUncertaintyIsNotAdded) {
  const fs::path d = freshDir();
  const std::string report = (d / "REPORT.json").string(), db = (d / "h.sqlite").string();
  std::ofstream(report) << "{\"format\": \"rotacal-report/1\", \"cycle\": \"touch154\", \"residual_rms_um\": 0.7,\n"
                           " \"location_errors\": {\n"
                           "  \"dx_AY\": {\"value\": 14.6, \"unit\": \"um\", \"u\": 0.3},\n"
                           "  \"dy_AY\": {\"value\": 1.0, \"unit\": \"um\", \"u\": -1}}}\n";
  const ShellRun r = sh(kCli + " history add " + report + " --machine-id m --db " + db + " --time 2024-02-28");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_EQ(r.out.rfind("rotacal: error: " + report + ":4: field 'u'", 0), 0u) << r.out;
  EXPECT_FALSE(fs::exists(db));
}

TEST(Store, ATrendWeighsByWhatDiffersBetweenCalibrations) {
  // REPORT.json's u is u_c, which holds the machine's own systematic errors (the same in every
  // calibration). The store reads u_between where the report has it, else u_a (the data's
  // part), and u alone only from a report that has neither (written when u was the data's).
  const auto stored = [](const std::string& entry) {
    const JsonDoc doc = parseJsonText(R"({"format": "rotacal-report/1", "cycle": "touch154", "residual_rms_um": 0.7,
      "location_errors": {"dx_AY": )" + entry + "}}",
                                      "REPORT.json");
    const Calibration c = calibrationFromReport(doc, "m", 0.0);
    return c.parameters.at(0).u;
  };
  EXPECT_DOUBLE_EQ(stored(R"({"value": 1, "unit": "um", "u": 4.5, "u_a": 0.2, "u_b": 4.4955, "u_c": 4.5, "u_between": 0.3})"),
                   0.3);
  EXPECT_DOUBLE_EQ(stored(R"({"value": 1, "unit": "um", "u": 4.5, "u_a": 0.2, "u_b": 4.4955, "u_c": 4.5})"), 0.2);
  EXPECT_DOUBLE_EQ(stored(R"({"value": 1, "unit": "um", "u": 0.25})"), 0.25);
}

}  // namespace
}  // namespace rotacal::history
