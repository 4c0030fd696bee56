// The tooltip cycle's catalogued causes hidden on heads as their contributors file declares them,
// not on clean ones: each head drawn by the independent generator (bench/independent_machine.hpp
// drawHead: 004's head with the linear axes' random positioning error carrying the pivot, tilted
// beams, per-reading laser scatter, from examples/contributors/tooltip_004.json) with its own
// dR off (the generator's pivot contributor is itself the catalogued pivot_length cause), the
// effect added by rotacal's exact tooltip simulator (bench/drawn_effects_tooltip.hpp), screened
// and judged against the declaration the head came from, as `diagnose --contributors` does. The
// rates over 200 clean and 50 effect heads are in docs/diagnosis.md (build/bench/
// rotacal_diagnose_bench tooltip_drawn).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bench/drawn_effects_tooltip.hpp"
#include "bench/independent_machine.hpp"
#include "core/contributors.hpp"
#include "core/machine.hpp"
#include "cycles/cycle.hpp"
#include "cycles/tooltip/diagnose.hpp"
#include "cycles/tooltip/noise.hpp"
#include "cycles/tooltip/screen.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

struct HeadWorld {
  MachineModel machine = loadMachine(test::sourcePath("examples/machines/head_ab.json"));
  ContributorSet declared = loadContributors(test::sourcePath("examples/contributors/tooltip_004.json"));
  ProbePlan stat = makePlan("tooltip", machine, {});
  ProbePlan dyn = makePlan("tooltip", machine, {{"sweeps", "1"}});
  ProbePlan dyn2 = makePlan("tooltip", machine, {{"sweeps", "2"}});
  ProbePlan shortTool = makePlan("tooltip", machine, {{"radius_mm", "200"}});
  double R = tooltipOptionsFrom(stat.options, stat.machine).radius_mm;

  independent::Head head(std::uint64_t seed) const {
    independent::HeadDrawOptions o;
    o.pivot = false;  // dR = 0: the clean head
    return independent::drawHead(declared, machine, o, seed);
  }
  JudgeSummary judge(const std::vector<const ProbePlan*>& plans, std::uint64_t seed, const independent::TooltipEffect& e) const {
    return independent::diagnoseDrawnHead(plans, head(seed), e, declared).summary;
  }
  /// The u the declared machine alone gives `cause`'s parameters on `plans` (one clean head's
  /// problem: the declaration, not the draw, sets it).
  std::vector<double> declaredU(const std::vector<const ProbePlan*>& plans, const std::string& cause) const {
    std::vector<TooltipSet> sets;
    for (size_t p = 0; p < plans.size(); ++p)
      sets.push_back({plans[p], {independent::measureHeadWithEffect(*plans[p], head(1), [](TooltipTruth*) {}, static_cast<int>(p))}});
    return independent::declaredCauseU(tooltipJudgeSetup(sets, 0.254, &declared).problem, cause);
  }
};

const HeadWorld& world() {
  static const HeadWorld w;
  return w;
}

// The superposition against the generator itself: a pivot error added through the simulator
// reads as the generator's own dR does (the generator draws dR into the head; the two share no
// code), to the second-order cross terms (dR times the declared 2 mrad beam tilts and the
// angular errors' mdeg: well under 0.1 um at dR = 50 um).
TEST(DrawnHead, EffectBySuperpositionMatchesTheGeneratorsOwnPivotError) {
  const HeadWorld& w = world();
  independent::Head h = w.head(31);
  const TooltipRun added = independent::measureHeadWithEffect(w.stat, h, [](TooltipTruth* t) { t->dR_um += 50.0; });
  h.dR_mm = 0.050;
  const TooltipRun drawn = independent::measureHead(w.stat, h);
  ASSERT_EQ(added.size(), drawn.size());
  double worst = 0.0;
  for (size_t k = 0; k < drawn.size(); ++k)
    worst = std::max({worst, std::abs(added[k].t_um - drawn[k].t_um), std::abs(added[k].z_um - drawn[k].z_um)});
  EXPECT_LT(worst, 0.1);
  EXPECT_GT(std::abs(drawn.back().z_um - independent::measureHead(w.stat, w.head(31)).back().z_um), 10.0);  // it moved
}

TEST(DrawnHead, CleanSeedsRaiseNoCauseOnHeadsAsDeclared) {
  // No effect, 10 heads on the bundled plan and on its dynamic test (one sweep). The bench
  // measures 4 and 3 alarms in 200 with the laser zero declared (6 and 8 before, docs/diagnosis.md);
  // at 4 % three or more of 10 has probability 0.6 %. (Two tools and two sweeps alarm on 3.5 % and
  // 1.5 % there: not asserted, reported.)
  const HeadWorld& w = world();
  for (const std::vector<const ProbePlan*>& plans : {std::vector<const ProbePlan*>{&w.stat}, {&w.dyn}}) {
    int alarms = 0;
    for (std::uint64_t seed = 31000; seed < 31010; ++seed)
      alarms += w.judge(plans, seed, [](TooltipTruth*) {}).verdict != JudgeVerdict::NoSignificantEffect;
    EXPECT_LE(alarms, 2) << plans.front()->options.size() << " option(s)";
  }
}

// Each cause at 10 u: ten times the scatter the declared machine alone gives its estimate on its
// plan (declaredCauseU), so that no draw of the declaration makes it. Not fewer: the judge tests
// each cause at alpha / (m + 1) (0.0025-0.0033: 3 u) and then asks a held-out gain above 2 of its
// standard errors, which on this correlated declaration scatters as much again (docs/diagnosis.md:
// the bench's rows at 3, 5, 10 and 20 u, seeds 20000-20049, none of them these).
constexpr double kSizeInU = 10.0;

struct Found {
  int named = 0;   // heads with a finding that names the cause (alone, or in the pair one tool cannot tell apart)
  int within = 0;  // ... effect_found, and the truth within 3 u in the finding's own terms
};

/// Over 5 heads: findings that name `cause` alone or as the pair with `partner` (one tool), each
/// with a held-out gain; the truth read in the finding's terms (`as_partner` when read as the
/// partner; empty: the partner's terms hold no value of it, named only).
Found found(const std::vector<const ProbePlan*>& plans, const independent::TooltipEffect& effect, const std::string& cause,
            const std::vector<double>& truth, const std::string& partner = "", const std::vector<double>& as_partner = {}) {
  Found n;
  for (std::uint64_t seed = 32000; seed < 32005; ++seed) {
    const JudgeSummary s = world().judge(plans, seed, effect);
    for (const auto& f : s.findings) {
      const bool own = f.cause == cause;
      const bool pair = !partner.empty() && f.cause == partner &&
                        std::find(f.confounded_with.begin(), f.confounded_with.end(), cause) != f.confounded_with.end();
      if (!own && !pair) continue;
      EXPECT_GT(f.gain, 0.0) << s.message;
      ++n.named;
      const std::vector<double>& t = own ? truth : as_partner;
      if (t.empty()) continue;
      if (f.parameters.size() != t.size()) {
        ADD_FAILURE() << f.cause << " has " << f.parameters.size() << " parameters";
        continue;
      }
      bool within = s.verdict == JudgeVerdict::EffectFound;
      for (size_t i = 0; i < t.size(); ++i) within = within && std::abs(f.parameters[i].value - t[i]) <= 3.0 * f.parameters[i].u;
      n.within += within;
    }
  }
  return n;
}

// The counts below: the bench's rate at 10 u over 50 other heads, and the fewest of 5 that such
// a rate gives with probability below 1 % (binomial).

TEST(DrawnHead, HiddenPivotOnOneToolIsFoundWithItsParametersWithin3u) {
  // One tool: dR is the isotropic scale s = -1000 dR / R um/m exactly; the judge names the pair
  // in one finding read as either, which counts as found when its estimate, in the finding's
  // terms, holds the truth. Bench: within 3 u on 50 of 50 (at least 4 of 5: below 0.4 % at any
  // rate from 98 %).
  const HeadWorld& w = world();
  const double dR = kSizeInU * w.declaredU({&w.stat}, "pivot_length")[0];
  const double s = -1000.0 * dR / w.R;
  EXPECT_GE(found({&w.stat}, [dR](TooltipTruth* t) { t->dR_um += dR; }, "pivot_length", {dR}, "linear_axis_scale", {s, s}).within, 4)
      << "dR " << dR << " um";
}

TEST(DrawnHead, HiddenScaleFoundOnOneTool) {
  // The Y axis alone off scale. One tool's pivot column lies in the scale's span, and the judge
  // names the pair read as dR on about half the heads (no value of a Y scale: named only, then
  // model_inadequate when the scale's remainder shows). Bench: named on 48 of 50 (at least 3 of
  // 5: 0.1 % below); its value is checked with two tools below.
  const HeadWorld& w = world();
  const double sY = kSizeInU * w.declaredU({&w.stat}, "linear_axis_scale")[0];
  EXPECT_GE(found({&w.stat}, [sY](TooltipTruth* t) { t->scale_t_um_m += sY; }, "linear_axis_scale", {sY, 0.0}, "pivot_length").named, 3)
      << "s_Y " << sY << " um/m";
}

TEST(DrawnHead, HiddenDriftFoundInTheDynamicTest) {
  // Two sweeps 0 -> 90 -> -90 -> 0: each angle read at four times since its zero. (One sweep:
  // the drift's Delta chi2 passes, its held-out gain over the commanded angles mostly does not:
  // docs/diagnosis.md.) Bench: named on 42 of 50, within 3 u on 36 (at least 2 and 1 of 5: 0.3 %
  // and 0.2 % below).
  const HeadWorld& w = world();
  const double dY = kSizeInU * w.declaredU({&w.dyn2}, "thermal_drift")[0];
  const Found n = found({&w.dyn2}, [dY](TooltipTruth* t) { t->drift_t_um_h += dY; }, "thermal_drift", {dY, 0.0});
  EXPECT_GE(n.named, 2) << "dY/h " << dY << " um/h";
  EXPECT_GE(n.within, 1) << "dY/h " << dY << " um/h";
}

TEST(DrawnHead, HiddenScaleFoundApartFromPivotWithTwoTools) {
  // Two tool lengths: a scale moves the tip in proportion to R, a pivot error does not. An
  // isotropic scale (one tool's exact pivot error) found as the scale, a pivot error as itself.
  // Bench: the scale within 3 u on 41 of 50 (at least 2 of 5: 0.5 % below), the pivot on 47 of
  // 50 (at least 3 of 5: 0.2 % below).
  const HeadWorld& w = world();
  const double s = kSizeInU * w.declaredU({&w.stat, &w.shortTool}, "linear_axis_scale")[0];
  EXPECT_GE(found({&w.stat, &w.shortTool},
                  [s](TooltipTruth* t) {
                    t->scale_t_um_m += s;
                    t->scale_z_um_m += s;
                  },
                  "linear_axis_scale", {s, s})
                .within,
            2)
      << "s " << s << " um/m";
  const double dR = kSizeInU * w.declaredU({&w.stat, &w.shortTool}, "pivot_length")[0];
  EXPECT_GE(found({&w.stat, &w.shortTool}, [dR](TooltipTruth* t) { t->dR_um += dR; }, "pivot_length", {dR}).within, 3)
      << "dR " << dR << " um";
}

// Repeats close the loop on the laser's zero: each head read three times by the generator (a new
// zero and per-reading scatter each run, the zero's scatter carried into its sweep's readings),
// screened and judged against the declaration with its per-run part, as `analyze` and `diagnose
// --results R1 R2 [R3]` do. With two runs and with three, the screen may lose a good reading on
// at most kMaxAlarms of kHeads heads and the judge may say model_inadequate on at most as many:
// at each one's alpha (1 %) P(X > kMaxAlarms) is below 1 % (binomial, computed below). Before
// the zero was declared, the bench's rates were 16 % and 29.5 % (screen) and 46.5 % and 72 %
// (model_inadequate) with 2 and 3 runs (docs/real_machines.md).
TEST(DrawnHead, RepeatsKeepTheirRatesOnHeadsAsDeclared) {
  const HeadWorld& w = world();
  constexpr int kHeads = 40, kMaxAlarms = 2;
  constexpr double kAlpha = 0.01;
  // P(X > kMaxAlarms) for X ~ Binomial(kHeads, kAlpha): the bound's own false-failure rate.
  double p_within = 0.0, term = std::pow(1.0 - kAlpha, kHeads);
  for (int k = 0; k <= kMaxAlarms; ++k) {
    p_within += term;
    term *= static_cast<double>(kHeads - k) / (k + 1) * kAlpha / (1.0 - kAlpha);
  }
  EXPECT_LT(1.0 - p_within, 0.01);
  int screened[2] = {0, 0}, inadequate[2] = {0, 0};
  for (std::uint64_t seed = 33000; seed < 33000 + kHeads; ++seed) {
    const independent::Head head = w.head(seed);
    std::vector<TooltipRun> all;
    for (int r = 0; r < 3; ++r) all.push_back(independent::measureHeadWithEffect(w.stat, head, [](TooltipTruth*) {}, r));
    for (int i = 0; i < 2; ++i) {
      const std::vector<TooltipRun> runs(all.begin(), all.begin() + 2 + i);
      const TooltipScreen screen = screenTooltipReadings(w.stat, runs, tooltipDeclaredNoise(w.stat, &w.declared, &runs.front()));
      screened[i] += !screen.screen.excluded.empty() || screen.screen.too_many ? 1 : 0;
      TooltipDiagnosisOptions o;
      o.contributors = &w.declared;
      const TooltipDiagnosis d = diagnoseTooltip({{&w.stat, withoutScreened(runs, screen)}}, o);
      inadequate[i] += d.summary.verdict == JudgeVerdict::ModelInadequate ? 1 : 0;
    }
  }
  std::printf("tooltip repeats on %d drawn heads: screen alarms %d (2 runs), %d (3 runs); model_inadequate %d, %d\n", kHeads,
              screened[0], screened[1], inadequate[0], inadequate[1]);
  for (int i = 0; i < 2; ++i) {
    EXPECT_LE(screened[i], kMaxAlarms) << 2 + i << " runs";
    EXPECT_LE(inadequate[i], kMaxAlarms) << 2 + i << " runs";
  }
}

}  // namespace
}  // namespace rotacal
