// spheres3's and spaceframe's catalogued causes on machines as their contributors file declares
// them, not on clean ones: each machine drawn by the independent generator
// (bench/independent_machine.hpp) from the cycle's bundled example (ac_trunnion.json and the
// table5.json it names), the effect added by rotacal's exact simulator (bench/drawn_effect.hpp),
// judged against the declaration the machine came from (bench/drawn_effects_spheres.hpp). The
// rates over 50 machines per effect and size, on other seeds, are in docs/diagnosis.md
// (build/bench/rotacal_diagnose_bench spheres3_drawn, spaceframe_drawn).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "bench/drawn_effects_spheres.hpp"
#include "cycles/spheres3/diagnose.hpp"

namespace rotacal::drawn {
namespace {

const Spheres3World& spheres3() {
  static const Spheres3World w;
  return w;
}
const SpaceframeWorld& spaceframe() {
  static const SpaceframeWorld w;
  return w;
}

/// The effect of `cause` at k x the clean world's size.
SphereEffect effectOf(const std::vector<SphereEffect>& effects, const std::string& cause) {
  for (const auto& e : effects)
    if (e.cause == cause) return e;
  throw std::logic_error("no effect for " + cause);
}

/// The finding naming `e.cause`, with its parameter `e.param` within 3 u of the truth.
::testing::AssertionResult foundWithin3u(const JudgeSummary& s, const SphereEffect& e) {
  if (s.verdict != JudgeVerdict::EffectFound) return ::testing::AssertionFailure() << e.what << ": " << s.message;
  const JudgeFinding* f = s.finding(e.cause);
  if (!f) return ::testing::AssertionFailure() << e.what << ": not named: " << s.message;
  for (const auto& p : f->parameters)
    if (p.name == e.param) {
      if (std::abs(p.value - e.truth) < 3.0 * p.u) return ::testing::AssertionSuccess();
      return ::testing::AssertionFailure() << e.what << ": " << p.name << " = " << p.value << " +- " << p.u << " for " << e.truth;
    }
  return ::testing::AssertionFailure() << e.what << ": no parameter " << e.param;
}

TEST(DrawnSpheres, Spheres3CleanSeedsRaiseNoCauseOnMachinesAsDeclared) {
  // No effect: 10 machines of one run and 5 of four repeats at alpha 1 %; two or more alarms in
  // 15 has probability 1.0 % under a correct judge.
  int alarms = 0;
  for (std::uint64_t seed = 31000; seed < 31015; ++seed) {
    const JudgeSummary s = spheres3().judge(seed, [](Truth*) {}, seed < 31010 ? 1 : 4);
    if (s.verdict != JudgeVerdict::NoSignificantEffect) ++alarms;
  }
  EXPECT_LE(alarms, 1);
}

TEST(DrawnSpheres, Spheres3HiddenHarmonicFoundInEachErrorMotionFamilyAtTheCleanWorldsSize) {
  // 3 um / 3 arcsec in cos 2C (001's order): the declared machine's linear axes and set-up move
  // the three spheres together at each C angle, not as a harmonic of C, so each family is named
  // at the clean world's size (bench: within 3 u on most of 50 machines, docs/diagnosis.md).
  const std::vector<SphereEffect> effects = spheres3Effects(1.0);
  std::uint64_t seed = 32000;
  for (const char* cause : {kSpheres3Radial, kSpheres3Axial, kSpheres3Tilt, kSpheres3Angular}) {
    const SphereEffect e = effectOf(effects, cause);
    for (int i = 0; i < 2; ++i, ++seed) EXPECT_TRUE(foundWithin3u(spheres3().judge(seed, e.hide, e.repeats), e)) << "seed " << seed;
  }
}

TEST(DrawnSpheres, Spheres3HiddenDriftFoundWithItsRateWithin3u) {
  // 3 um/h in X over four repeats 30 min apart: table5 declares no drift, so no draw of the
  // declared machine makes one; found at the clean world's size.
  const SphereEffect e = effectOf(spheres3Effects(1.0), kSpheres3Drift);
  for (std::uint64_t seed = 32100; seed < 32103; ++seed)
    EXPECT_TRUE(foundWithin3u(spheres3().judge(seed, e.hide, e.repeats), e)) << "seed " << seed;
}

TEST(DrawnSpheres, Spheres3HiddenSquarenessBeyondTheDeclarationIsFoundWithItsParametersWithin3u) {
  // 300 um/m: ten times the clean world's 30 um/m, which is one standard uncertainty of what
  // table5 declares (3 um / 100 mm) and so the declared machine's own.
  const SphereEffect e = effectOf(spheres3Effects(10.0), kSpheres3Squareness);
  for (std::uint64_t seed = 32200; seed < 32203; ++seed)
    EXPECT_TRUE(foundWithin3u(spheres3().judge(seed, e.hide, e.repeats), e)) << "seed " << seed;
}

TEST(DrawnSpheres, Spheres3HiddenScaleFoundAsWhatThePlanCannotAttribute) {
  // 300 um/m of X scale: its isotropic part is a sphere position on this plan (the Jacobians'
  // closed form, tests/cycles/spheres3), so never a finding of its own, and never "no significant
  // effect": the verdict names it among what shares the signal.
  const SphereEffect e = effectOf(spheres3Effects(10.0), kSpheres3Scale);
  for (std::uint64_t seed = 32300; seed < 32302; ++seed) {
    const JudgeSummary s = spheres3().judge(seed, e.hide, e.repeats);
    EXPECT_EQ(s.verdict, JudgeVerdict::ModelInadequate) << s.message;
    bool confounded = false;
    for (const auto& c : s.confounded) confounded = confounded || c.cause == kSpheres3Scale;
    EXPECT_TRUE(confounded) << s.message;
  }
}

TEST(DrawnSpheres, SpaceframeCleanSeedsRaiseNoCauseOnMachinesAsDeclared) {
  // 5 machines at alpha 1 % (each diagnosis takes about 5 s of CPU on this 763-touch plan): two or
  // more alarms has probability 0.1 % under a correct judge.
  int alarms = 0;
  for (std::uint64_t seed = 41000; seed < 41005; ++seed)
    alarms += spaceframe().judge(seed, [](Truth*) {}).verdict != JudgeVerdict::NoSignificantEffect ? 1 : 0;
  EXPECT_LE(alarms, 1);
}

TEST(DrawnSpheres, SpaceframeHiddenDriftFoundWithItsRateWithin3u) {
  // 12 um/h of dz_AY: three times the clean world's 4 um/h, which over this one 763-touch run the
  // declared machine's shared linear-axis and set-up errors hide on some machines.
  const SphereEffect e = effectOf(spaceframeEffects(3.0), "thermal_drift");
  for (std::uint64_t seed = 42000; seed < 42002; ++seed)
    EXPECT_TRUE(foundWithin3u(spaceframe().judge(seed, e.hide), e)) << "seed " << seed;
}

TEST(DrawnSpheres, SpaceframeHiddenSquarenessBeyondTheDeclarationIsFoundWithItsParametersWithin3u) {
  // 300 um/m: ten times the clean world's 30 um/m, which is one standard uncertainty of what
  // table5 declares (3 um / 100 mm) and so the declared machine's own.
  const SphereEffect e = effectOf(spaceframeEffects(10.0), "linear_axis_squareness");
  for (std::uint64_t seed = 42100; seed < 42102; ++seed)
    EXPECT_TRUE(foundWithin3u(spaceframe().judge(seed, e.hide), e)) << "seed " << seed;
}

TEST(DrawnSpheres, SpaceframeFrameTemperatureIsFoundWithItsParametersWithin3u) {
  // The frame grown by 200 um/m about its origin (ten times 20 um/m, 1.7 K of steel): each sphere
  // moves by up to 36 um (003 Table 1's levers reach 181 mm), beyond what the declared set-up and
  // linear axes make of the frame. To this plan the growth is exactly an isotropic scale of the
  // axes less a set-up shift (docs/diagnosis.md, spaceframe): the judge may name it as one
  // finding with the scale, whose three scales then read the growth, s = -e (the axes reading
  // short by what the frame grew).
  const SphereEffect e = effectOf(spaceframeEffects(10.0), "frame_temperature");
  for (std::uint64_t seed = 42200; seed < 42202; ++seed) {
    const JudgeSummary s = spaceframe().judge(seed, e.hide);
    ASSERT_EQ(s.verdict, JudgeVerdict::EffectFound) << s.message;
    const JudgeFinding* f = s.finding("frame_temperature");
    if (!f) {
      f = s.finding("linear_axis_scale");
      ASSERT_NE(f, nullptr) << s.message;
      ASSERT_NE(std::find(f->confounded_with.begin(), f->confounded_with.end(), "frame_temperature"), f->confounded_with.end())
          << s.message;
      for (const auto& p : f->parameters) EXPECT_NEAR(p.value, -e.truth, 3.0 * p.u) << p.name << ", seed " << seed;
    } else {
      EXPECT_NEAR(f->parameters[0].value, e.truth, 3.0 * f->parameters[0].u) << "seed " << seed;
    }
  }
}

}  // namespace
}  // namespace rotacal::drawn
