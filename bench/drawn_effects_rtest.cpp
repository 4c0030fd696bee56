#include "bench/drawn_effects_rtest.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "core/declared_noise.hpp"
#include "core/machine.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/rtest/analyze.hpp"

namespace rotacal::independent {

namespace {

void addEffect(const RtestReading& with, const RtestReading& without, RtestReading* measured) {
  if (with.pose_id != measured->pose_id || without.pose_id != measured->pose_id || std::abs(with.t_s - measured->t_s) > 1e-6 ||
      std::abs(without.t_s - measured->t_s) > 1e-6)
    throw std::logic_error("the generator's and the simulator's R-test readings are not the same readings");
  measured->dq_w_mm += with.dq_w_mm - without.dq_w_mm;
}

}  // namespace

RtestSeries measureRtestWithEffect(const ProbePlan& plan, const RtestMachine& drawn, const RtestEffect& effect) {
  RtestSeries measured = measureRtest(plan, drawn);
  Truth base;
  base.errors = drawn.location;
  RtestTruthExtras base_x;
  base_x.sphere_offset_m_mm = drawn.sphere_offset_mm;
  Truth with_t = base;
  RtestTruthExtras with_x = base_x;
  effect(&with_t, &with_x);
  RtestSimOptions o;  // noise-free, the reset at the series' start as the generator's
  const RtestSeries without = simulateRtest(plan, base, base_x, o);
  const RtestSeries with = simulateRtest(plan, with_t, with_x, o);
  if (with.cycles.size() != measured.cycles.size() || without.cycles.size() != measured.cycles.size())
    throw std::logic_error("the generator and the simulator measured different numbers of R-test cycles");
  for (size_t c = 0; c < measured.cycles.size(); ++c) {
    RtestCycle& m = measured.cycles[c];
    const RtestCycle &w = with.cycles[c], &wo = without.cycles[c];
    if (w.readings.size() != m.readings.size() || wo.readings.size() != m.readings.size() ||
        m.reset.has_value() != w.reset.has_value() || m.reread.has_value() != w.reread.has_value())
      throw std::logic_error("the generator and the simulator read different R-test cycles");
    for (size_t i = 0; i < m.readings.size(); ++i) addEffect(w.readings[i], wo.readings[i], &m.readings[i]);
    if (m.reset) addEffect(*w.reset, *wo.reset, &*m.reset);
    if (m.reread) addEffect(*w.reread, *wo.reread, &*m.reread);
  }
  return measured;
}

RtestDiagnosis diagnoseAsDeclared(const ProbePlan& plan, const ContributorSet& declared, const std::vector<RtestCycle>& cycles,
                                  double alpha) {
  RtestDiagnosisOptions o;
  o.judge.alpha = alpha;
  o.sensor_sigma_um = rtestSensorNoiseUm(plan);
  const DeclaredNoise noise = rtestDeclaredNoise(plan, &declared, cycles.empty() ? nullptr : &cycles.front());
  o.reading_sigma_um = std::sqrt(noise.white_um2);
  o.declaration = noise.declaration;
  o.structured_um2 = noise.structured_um2;
  o.structured_draws_um = noise.structured_draws_um;
  return diagnoseRtest(plan, cycles, o);
}

Eigen::Vector3d drawnSphereDriftUmPerH(const RtestMachine& drawn) { return mmToUm(1.0) * 3600.0 * drawn.drift_mm_per_s; }

namespace {

constexpr double kAlpha = 0.01;  // the CLI's default (cycles/cycle.hpp)

/// What a row checks within 3 u: the finding's parameter `name` against `truth` of the machine.
struct Check {
  std::string name;
  std::function<double(const RtestMachine&)> truth;
};

struct Row {
  std::string what;
  RtestEffect effect;
  std::string cause;  // the judge's candidate that names it ("" none)
  std::optional<Check> check;
};

struct Tally {
  int n = 0, found = 0, inadequate = 0, none = 0, named = 0, within = 0, linear = 0, spindle = 0, table = 0, other = 0;
  int reread = 0;  // analyze's re-read check flagged a cycle (a sensor step), beside the judge
  std::vector<double> gains;
  void print(const std::string& what, double seconds) const {
    std::vector<double> g = gains;
    std::sort(g.begin(), g.end());
    const std::string median = g.empty() ? std::string("-") : fmt::format("{:.3g}", g[g.size() / 2]);
    std::printf("  %-62s %3d seeds: effect_found %3d, model_inadequate %3d, no_significant_effect %3d; named %3d, named "
                "within 3 u %3d, held-out gain (median) %s; thermal_drift explained by the linear axes' drift %d, the spindle's %d, "
                "worded as "
                "the table %d; another cause named %d; analyze's re-read check flags a step %d  (%.2f s per diagnosis)\n",
                what.c_str(), n, found, inadequate, none, named, within, median.c_str(), linear, spindle, table, other, reread,
                seconds);
    std::fflush(stdout);
  }
};

void tally(Tally* t, const ProbePlan& plan, const RtestDiagnosis& d, const RtestMachine& m, const Row& row) {
  const JudgeSummary& s = d.summary;
  ++t->n;
  t->found += s.verdict == JudgeVerdict::EffectFound;
  t->inadequate += s.verdict == JudgeVerdict::ModelInadequate;
  t->none += s.verdict == JudgeVerdict::NoSignificantEffect;
  if (std::getenv("ROTACAL_BENCH_VERBOSE")) std::fprintf(stderr, "%s", rtestDiagnosisText(plan, d).c_str());
  for (const auto& c : d.analysis.cycles) t->reread += c.sensor_step;
  for (const auto& f : s.findings) {
    if (f.cause == "thermal_drift") {
      // Who explains the drift signal alone (the judge's nested tests, rtestFindingSummary's words).
      for (const auto& c : d.confounds) {
        t->linear += c.explains && c.entry.cause == "linear_axis_drift";
        t->spindle += c.explains && c.entry.cause == "spindle_growth";
      }
      t->table += rtestFindingSummary(plan, d, f).find("the rotary table's errors change") != std::string::npos;
    }
    // A finding other than the row's cause and the drift every drawn machine carries.
    t->other += f.cause != row.cause && f.cause != "thermal_drift";
    if (row.cause.empty() || f.cause != row.cause) continue;
    ++t->named;
    t->gains.push_back(f.gain);
    if (row.check && s.verdict == JudgeVerdict::EffectFound) {
      const JudgeEstimate* e = f.parameter(row.check->name);
      if (!e) throw std::logic_error("the finding has no parameter " + row.check->name);
      t->within += std::abs(e->value - row.check->truth(m)) < 3.0 * e->u;
    }
  }
}

void trial(const ProbePlan& plan, const ContributorSet& cs, const RtestDrawOptions& draw, std::uint64_t seed0, int seeds,
           const Row& row) {
  // ROTACAL_BENCH_ONLY=a,b: run only the rows whose name contains a or b (rows split over processes).
  if (const char* only = std::getenv("ROTACAL_BENCH_ONLY")) {
    bool any = false;
    const std::string list = only;
    for (size_t b = 0, e; b <= list.size(); b = e + 1) {
      e = std::min(list.find(',', b), list.size());
      any = any || (e > b && row.what.find(list.substr(b, e - b)) != std::string::npos);
    }
    if (!any) return;
  }
  Tally t;
  const auto start = std::chrono::steady_clock::now();
  for (int s = 0; s < seeds; ++s) {
    const RtestMachine m = drawRtestMachine(cs, plan, draw, seed0 + static_cast<std::uint64_t>(s));
    const RtestSeries series = measureRtestWithEffect(plan, m, row.effect);
    tally(&t, plan, diagnoseAsDeclared(plan, cs, series.cycles, kAlpha), m, row);
  }
  t.print(row.what, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / std::max(1, seeds));
}

RtestEffect none() {
  return [](Truth*, RtestTruthExtras*) {};
}

/// The sensors' zero stepping by `um` along the nest's x at `at_s` (a knock, a lost count).
RtestEffect sensorStep(double at_s, double um) {
  return [at_s, um](Truth*, RtestTruthExtras* x) { x->sensor_steps.push_back({at_s, Eigen::Vector3d(umToMm(um), 0, 0)}); };
}

/// The sphere drifting against the table at `um_per_h` (machine frame): the spindle's growth
/// (Z) or the linear axes' drift.
RtestEffect sphereDrift(const Eigen::Vector3d& um_per_h) {
  return [um_per_h](Truth*, RtestTruthExtras* x) {
    x->sphere_drift_m_mm = [um_per_h](double t_s) { return Eigen::Vector3d(umToMm(1.0) * um_per_h * t_s / 3600.0); };
  };
}

}  // namespace

void rtestDrawnBench(int clean_seeds, int effect_seeds) {
  const std::string src = ROTACAL_SOURCE_DIR;
  const MachineModel machine = loadMachine(src + "/examples/machines/bc_trunnion.json");
  const ContributorSet cs = loadContributors(src + "/examples/contributors/rtest_002.json");
  const RtestDrawOptions as_declared;

  // The bundled example's plan (`plan --cycle rtest`): one measuring cycle with its reset and
  // re-read. The declared per-cycle drift is part of the structured declaration there.
  {
    const ProbePlan plan = makePlan("rtest", machine, {});
    const std::vector<double> reads = rtestReadTimes(plan);
    std::printf("rtest, the bundled example's plan (one cycle of %zu poses, %.0f s, reset and re-read), on machines drawn from "
                "examples/contributors/rtest_002.json by the independent generator (bench/independent_rtest), judged against "
                "it, alpha %.2f\n",
                plan.points.size(), rtestCycleTime_s(plan), kAlpha);
    trial(plan, cs, as_declared, 12000, clean_seeds, {"one cycle: drawn machine, no effect", none(), "", std::nullopt});
    // 1 um: the clean-world tests' step, five times the declared 0.22 um per reading; the
    // declaration makes no step (its drift over the ~20 s from the last pose to the re-read is
    // 0.01 um at 1 sigma).
    trial(plan, cs, as_declared, 12500, effect_seeds,
          {"one cycle: sensor step 1 um in x before the re-read", sensorStep(0.5 * (plan.points.back().t_s + reads.back()), 1.0),
           "sensor_step_in_cycle_1", Check{"dx", [](const RtestMachine&) { return 1.0; }}});
  }

  // 002's thermal schedule (`--set thermal=1`: a measuring cycle every 15 min over 3 h while B
  // reciprocates). The generator holds the declared per-cycle drift over the whole series (linear
  // from its start): the machine as declared drifts by 0.05, 0.1, 0.05 um per 155 s cycle at
  // 1 sigma, 1.2, 2.3, 1.2 um/h, 002's own drift (the contributors file's note derives it from
  // 002 Figs. 8-10). That drift is what the judge must name: the clean rows are the machine with
  // the drift switched off in the generator (nothing else changes in the draw).
  const ProbePlan plan = makePlan("rtest", machine, {{"thermal", "1"}});
  const RtestSchedule sch = rtestSchedule(plan);
  std::printf("rtest, 002's thermal schedule (thermal=1: %d cycles every %.0f min over %.1f h), same machines and judge\n",
              sch.cycles(), sch.interval_s / 60.0, sch.duration_s / 3600.0);
  RtestDrawOptions no_drift;
  no_drift.drift = false;
  trial(plan, cs, no_drift, 11000, clean_seeds, {"thermal: drawn machine, its drift off, no effect", none(), "", std::nullopt});
  // The machine as declared: its own drift, read as dy_CB moving by -v_y at every B.
  trial(plan, cs, as_declared, 11000, clean_seeds,
        {"thermal: drawn machine as declared (its drift over 3 h)", none(), "thermal_drift",
         Check{"dy_CB(B=30)/h", [](const RtestMachine& m) { return -drawnSphereDriftUmPerH(m).y(); }}});
  // 002 Sec. 4.4's c_BY drift, 0.3 mdeg/h at every B: a rotation of the table, which no sphere
  // drift (all the declaration makes) can read as.
  trial(plan, cs, as_declared, 11500, effect_seeds,
        {"thermal: table drift c_BY +0.3 mdeg/h at every B",
         [](Truth* t, RtestTruthExtras*) {
           t->drift = [](double s) {
             ErrorVector d = ErrorVector::Zero();
             d[5] = mdegToRad(0.3 * s / 3600.0);
             return d;
           };
         },
         "thermal_drift", Check{"c_BY(B=30)/h", [](const RtestMachine&) { return 0.3; }}});
  // The SJTU spindle's first 3 h (1.3 um/h along Z), on top of the drawn drift (1.2 um/h in Z
  // at 1 sigma, and X, Y).
  trial(plan, cs, as_declared, 11600, effect_seeds,
        {"thermal: spindle growth 1.3 um/h (SJTU's first 3 h)", sphereDrift({0, 0, 1.3}), "thermal_drift",
         Check{"dz_BY(B=30)/h", [](const RtestMachine& m) { return -(1.3 + drawnSphereDriftUmPerH(m).z()); }}});
  // The linear axes drifting three times 002's drift (-2, -6, -2 um/h): beyond the declaration's
  // 1 sigma (1.2, 2.3, 1.2 um/h) on every axis.
  trial(plan, cs, as_declared, 11700, effect_seeds,
        {"thermal: linear-axis drift (-2, -6, -2) um/h", sphereDrift({-2.0, -6.0, -2.0}), "thermal_drift",
         Check{"dy_CB(B=30)/h", [](const RtestMachine& m) { return -(-6.0 + drawnSphereDriftUmPerH(m).y()); }}});
  // Sensor steps at the clean-world tests' 1 um (five times the declared scatter of a reading).
  const std::vector<double> reads = rtestReadTimes(plan);
  trial(plan, cs, as_declared, 11800, effect_seeds,
        {"thermal: sensor step 1 um in x between cycles 6 and 7", sensorStep(6 * sch.interval_s - 60.0, 1.0), "sensor_step_cycle_7",
         Check{"dx", [](const RtestMachine&) { return 1.0; }}});
  trial(plan, cs, as_declared, 11900, effect_seeds,
        {"thermal: sensor step 1 um in x in cycle 7 before its re-read",
         sensorStep(6 * sch.interval_s + 0.5 * (plan.points.back().t_s + reads.back()), 1.0), "sensor_step_in_cycle_7",
         Check{"dx", [](const RtestMachine&) { return 1.0; }}});
}

}  // namespace rotacal::independent
