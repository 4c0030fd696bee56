#include "bench/drawn_effects_tooltip.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/machine.hpp"
#include "cycles/cycle.hpp"
#include "cycles/judge_contract.hpp"
#include "cycles/tooltip/noise.hpp"
#include "cycles/tooltip/screen.hpp"

#ifndef ROTACAL_SOURCE_DIR
#define ROTACAL_SOURCE_DIR "."
#endif

namespace rotacal::independent {

TooltipRun measureHeadWithEffect(const ProbePlan& plan, const Head& head, const TooltipEffect& effect, int run) {
  Head again = head;
  again.reading_seed = head.reading_seed + 1000003ULL * static_cast<std::uint64_t>(run);
  TooltipRun measured = measureHead(plan, again);
  TooltipTruth base;  // the drawn head in the simulator's terms, noise-free
  base.dR_um = 1e3 * head.dR_mm;
  base.offset_mdeg = head.angular_mdeg[0];
  base.slope_mdeg_per_90deg = head.angular_mdeg[1];
  base.sin_mdeg = head.angular_mdeg[2];
  base.sin2_mdeg = head.angular_mdeg[3];
  TooltipTruth with = base;
  effect(&with);
  const TooltipRun without_effect = simulateTooltip(plan, base, 1), with_effect = simulateTooltip(plan, with, 1);
  if (with_effect.size() != measured.size() || without_effect.size() != measured.size())
    throw std::logic_error("the generator and the simulator read different numbers of readings");
  for (size_t k = 0; k < measured.size(); ++k) {
    if (std::abs(with_effect[k].angle_deg - measured[k].angle_deg) > 1e-9 ||
        std::abs(without_effect[k].angle_deg - measured[k].angle_deg) > 1e-9)
      throw std::logic_error("the generator's and the simulator's readings are in different orders");
    measured[k].t_um += with_effect[k].t_um - without_effect[k].t_um;
    measured[k].z_um += with_effect[k].z_um - without_effect[k].z_um;
  }
  return measured;
}

TooltipDiagnosis diagnoseDrawnHead(const std::vector<const ProbePlan*>& plans, const Head& head, const TooltipEffect& effect,
                                   const ContributorSet& declared) {
  std::vector<TooltipSet> sets;
  for (size_t p = 0; p < plans.size(); ++p) {
    const std::vector<TooltipRun> runs = {measureHeadWithEffect(*plans[p], head, effect, static_cast<int>(p))};
    // As `diagnose`: the judge sees the readings the screen keeps.
    const TooltipScreen screen = screenTooltipReadings(*plans[p], runs, tooltipDeclaredNoise(*plans[p], &declared, &runs.front()));
    sets.push_back({plans[p], withoutScreened(runs, screen)});
  }
  TooltipDiagnosisOptions o;
  o.contributors = &declared;
  return diagnoseTooltip(sets, o);
}

std::vector<double> declaredCauseU(const JudgeProblem& pb, const std::string& cause) {
  const auto it = std::find_if(pb.causes.begin(), pb.causes.end(), [&](const JudgeCause& c) { return c.name == cause; });
  if (it == pb.causes.end()) throw std::invalid_argument("no cause " + cause + " on this plan");
  const Eigen::Index p = pb.J0.cols(), k = it->J.cols();
  Eigen::MatrixXd J(pb.J0.rows(), p + k);
  J << pb.J0, it->J;
  const Eigen::MatrixXd C = pb.covariance.size() ? pb.covariance : Eigen::MatrixXd(pb.sigma.array().square().matrix().asDiagonal());
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(C);
  const Eigen::MatrixXd info = J.transpose() * ldlt.solve(J);
  const Eigen::MatrixXd cov = info.completeOrthogonalDecomposition().pseudoInverse();
  std::vector<double> u;
  for (Eigen::Index j = 0; j < k; ++j) u.push_back(std::sqrt(cov(p + j, p + j)));
  return u;
}

namespace {

/// One hidden cause: its truth in the cause's parameters, and the same read in the confounded
/// partner's terms (one tool: dR = 1 um moves the tip as s_t = s_Z = -1000 / R um/m).
struct Row {
  std::string what;
  TooltipEffect effect;
  std::string cause;
  std::vector<double> truth;               // the cause's parameters
  std::vector<double> truth_as_partner;    // the same effect read as the partner cause (empty: not a value of it)
  std::string partner;                     // the cause one tool cannot tell it from (named with it: found)
};

struct Tally {
  int n = 0, found = 0, inadequate = 0, none = 0, named = 0, within = 0;
  std::vector<double> gain_pct;
  std::map<std::string, int> other;  // causes named that are not the hidden one
  void print(const std::string& what) const {
    std::vector<double> g = gain_pct;
    std::sort(g.begin(), g.end());
    const std::string gain = g.empty() ? std::string("-") : fmt::format("{:.0f} %", g[g.size() / 2]);
    std::string others;
    for (const auto& [c, k] : other) others += fmt::format("{}{} {}", others.empty() ? "; other causes named: " : ", ", c, k);
    std::printf("%-58s %3d seeds: effect_found %3d, model_inadequate %3d, no_significant_effect %3d; named %3d, within 3 u "
                "%3d; held-out gain (median of named) %s%s\n",
                what.c_str(), n, found, inadequate, none, named, within, gain.c_str(), others.c_str());
    std::fflush(stdout);
  }
};

/// Tallies one diagnosis against the hidden row (empty cause: no effect).
void add(Tally* t, const JudgeSummary& s, const Row& row) {
  ++t->n;
  t->found += s.verdict == JudgeVerdict::EffectFound;
  t->inadequate += s.verdict == JudgeVerdict::ModelInadequate;
  t->none += s.verdict == JudgeVerdict::NoSignificantEffect;
  if (std::getenv("ROTACAL_BENCH_VERBOSE")) {
    std::fprintf(stderr, "  %s\n", s.message.c_str());
    for (const auto& c : s.candidate_tests)
      std::fprintf(stderr, "    step %d %s: delta chi2 %.1f (k %d), p %.3g, gain %.3g +- %.3g: %s\n", c.step, c.cause.c_str(),
                   c.delta_chi2, c.k, c.p_value, c.gain, c.gain_se, c.reason.c_str());
  }
  for (const auto& f : s.findings) {
    const bool is_cause = !row.cause.empty() && f.cause == row.cause;
    const bool is_partner = !row.partner.empty() && f.cause == row.partner &&
                            std::find(f.confounded_with.begin(), f.confounded_with.end(), row.cause) != f.confounded_with.end();
    if (!is_cause && !is_partner) {
      ++t->other[f.label()];
      continue;
    }
    ++t->named;
    t->gain_pct.push_back(holdoutGainPct(s, f));
    // Read as the partner with no terms to read the truth in (a Y scale read as dR): named only.
    const std::vector<double>& truth = is_cause ? row.truth : row.truth_as_partner;
    bool within = s.verdict == JudgeVerdict::EffectFound && !truth.empty() && f.parameters.size() == truth.size();
    for (size_t i = 0; within && i < truth.size(); ++i)
      within = std::abs(f.parameters[i].value - truth[i]) <= 3.0 * f.parameters[i].u;
    t->within += within;
  }
}

}  // namespace

void tooltipDrawnBench(int clean_seeds, int effect_seeds) {
  const MachineModel m = loadMachine(std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/head_ab.json");
  const ContributorSet cs = loadContributors(std::string(ROTACAL_SOURCE_DIR) + "/examples/contributors/tooltip_004.json");
  // The bundled plan (A 0..90 deg by 5 at R = 381 mm, static), its dynamic test (one sweep
  // 0 -> 90 -> -90 -> 0: each angle read at two times since its zero, where a drift is testable),
  // and a second tool length (R = 200 mm, 004 gives one; the clean-world test's second).
  const ProbePlan stat = makePlan("tooltip", m, {});
  const ProbePlan dyn = makePlan("tooltip", m, {{"sweeps", "1"}});
  const ProbePlan dyn2 = makePlan("tooltip", m, {{"sweeps", "2"}});
  const ProbePlan shortTool = makePlan("tooltip", m, {{"radius_mm", "200"}});
  const double R = tooltipOptionsFrom(stat.options, stat.machine).radius_mm;
  HeadDrawOptions draw;
  draw.pivot = false;  // the clean drawn head: dR = 0 (the generator's pivot contributor off)
  const auto head = [&](int seed) { return drawHead(cs, m, draw, 20000 + static_cast<std::uint64_t>(seed)); };
  const TooltipEffect none = [](TooltipTruth*) {};
  const auto run = [&](const std::vector<const ProbePlan*>& plans, const Row& row, int seeds) {
    const char* only = std::getenv("ROTACAL_BENCH_ONLY");
    if (only && row.what.find(only) == std::string::npos) return;
    Tally t;
    for (int s = 0; s < seeds; ++s) add(&t, diagnoseDrawnHead(plans, head(s), row.effect, cs).summary, row);
    t.print(row.what);
  };

  // The sizes: k times the u the declared machine alone gives each parameter on its plan
  // (declaredCauseU on the first clean head's problem), so that they are beyond what the
  // declaration makes; k = 5: a one-parameter test at alpha 1 % (2.58 u, less the judge's
  // Bonferroni share) then passes on about 97 % of draws.
  const auto u = [&](const std::vector<const ProbePlan*>& plans, const std::string& cause) {
    std::vector<TooltipSet> sets;
    for (size_t p = 0; p < plans.size(); ++p) sets.push_back({plans[p], {measureHeadWithEffect(*plans[p], head(0), none, static_cast<int>(p))}});
    return declaredCauseU(tooltipJudgeSetup(sets, tooltipOptionsFrom(stat.options, stat.machine).noise_um, &cs).problem, cause);
  };
  const std::vector<double> u_dR = u({&stat}, "pivot_length"), u_s = u({&stat}, "linear_axis_scale"),
                            u_drift = u({&dyn}, "thermal_drift"), u_dR2 = u({&stat, &shortTool}, "pivot_length"),
                            u_s2 = u({&stat, &shortTool}, "linear_axis_scale");
  std::printf("tooltip on heads drawn from examples/contributors/tooltip_004.json by the independent generator (dR = 0: its "
              "pivot contributor off), one run, screened and judged against that declaration as `diagnose --contributors`, "
              "alpha %.2f\n",
              JudgeOptions{}.alpha);
  std::printf("declared u on the bundled plan: dR %.2f um, s_Y %.2f um/m, s_Z %.2f um/m; dynamic test (sweeps 1): dY/h %.2f, "
              "dZ/h %.2f um/h; two tools (381, 200 mm): dR %.2f um, s_Y %.2f, s_Z %.2f um/m\n",
              u_dR[0], u_s[0], u_s[1], u_drift[0], u_drift[1], u_dR2[0], u_s2[0], u_s2[1]);

  run({&stat}, {"static, drawn head, no effect", none, "", {}, {}, ""}, clean_seeds);
  run({&dyn}, {"dynamic (sweeps 1), drawn head, no effect", none, "", {}, {}, ""}, clean_seeds);
  run({&dyn2}, {"dynamic (sweeps 2), drawn head, no effect", none, "", {}, {}, ""}, clean_seeds);
  run({&stat, &shortTool}, {"two tools (381, 200 mm), drawn head, no effect", none, "", {}, {}, ""}, clean_seeds);
  const std::vector<double> u_drift2 = u({&dyn2}, "thermal_drift");
  for (double k : {3.0, 5.0, 10.0, 20.0}) {
    const double dR = k * u_dR[0];
    run({&stat},
        {fmt::format("pivot dR = {:.0f} um ({:g} u)", dR, k), [dR](TooltipTruth* t) { t->dR_um += dR; }, "pivot_length", {dR},
         {-dR * 1000.0 / R, -dR * 1000.0 / R}, "linear_axis_scale"},
        effect_seeds);
    // The Y axis alone off scale (its scale's own temperature): not the pivot's isotropic pattern.
    const double sY = k * u_s[0];
    run({&stat},
        {fmt::format("Y scale s_Y = {:.0f} um/m ({:g} u)", sY, k), [sY](TooltipTruth* t) { t->scale_t_um_m += sY; },
         "linear_axis_scale", {sY, 0.0}, {}, "pivot_length"},
        effect_seeds);
    const double dY = k * u_drift[0];
    run({&dyn},
        {fmt::format("dynamic: tip drift dY = {:.1f} um/h ({:g} u)", dY, k), [dY](TooltipTruth* t) { t->drift_t_um_h += dY; },
         "thermal_drift", {dY, 0.0}, {}, ""},
        effect_seeds);
    const double dY2 = k * u_drift2[0];
    run({&dyn2},
        {fmt::format("dynamic (sweeps 2): tip drift dY = {:.1f} um/h ({:g} u)", dY2, k), [dY2](TooltipTruth* t) { t->drift_t_um_h += dY2; },
         "thermal_drift", {dY2, 0.0}, {}, ""},
        effect_seeds);
    const double dR2 = k * u_dR2[0];
    run({&stat, &shortTool},
        {fmt::format("two tools: pivot dR = {:.0f} um ({:g} u)", dR2, k), [dR2](TooltipTruth* t) { t->dR_um += dR2; },
         "pivot_length", {dR2}, {}, ""},
        effect_seeds);
    // Isotropic: on one tool exactly a pivot error; two tools tell them apart.
    const double s2 = k * u_s2[0];
    run({&stat, &shortTool},
        {fmt::format("two tools: isotropic scale s = {:.0f} um/m ({:g} u)", s2, k),
         [s2](TooltipTruth* t) {
           t->scale_t_um_m += s2;
           t->scale_z_um_m += s2;
         },
         "linear_axis_scale", {s2, s2}, {}, ""},
        effect_seeds);
  }
}

}  // namespace rotacal::independent
