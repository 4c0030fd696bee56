#include "bench/drawn_effects_spheres.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include <fmt/format.h>

#include "bench/drawn_effect.hpp"
#include "bench/independent_machine.hpp"
#include "core/error_model.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/spaceframe/diagnose.hpp"
#include "cycles/spaceframe/frame.hpp"
#include "cycles/spaceframe/screen.hpp"
#include "cycles/spheres3/diagnose.hpp"

namespace rotacal::drawn {

namespace {

constexpr double kAlpha = 0.01;  // the CLI's default, the clean-world benches'

/// The cycle's bundled example machine and the contributors it declares (as `diagnose` reads
/// them; table5.json where a machine names none, as rotacal_real_machine_bench does).
MachineModel exampleMachine(const std::string& cycle) {
  return loadMachine(std::string(ROTACAL_SOURCE_DIR) + "/" + cycleByName(cycle).example().machine);
}
ContributorSet declaredOf(const MachineModel& m) {
  return m.contributors ? *m.contributors : loadContributors(std::string(ROTACAL_SOURCE_DIR) + "/examples/contributors/table5.json");
}

std::string times(const std::string& what, double k) { return k == 1.0 ? what : fmt::format("{} x {:g}", what, k); }

/// A component error of the C axis, `size` cos(order C) in component k (EXC EYC EZC EAC EBC ECC;
/// mm or rad), as the clean world's spheres3Table_m_w applies it: the error transform T_E(C)
/// between the C axis's location and its rotation. Here it is put in front of the drawn A/C chain
/// (the truth's own location errors, read when the effect is applied): T_E about the machine's
/// origin instead of the axis's true line differs by T_E's angle times the axis's offset
/// (3 arcsec x 30 um = 0.4 nm), far below anything measured.
Hide componentOfC(int k, double size, int order) {
  return [k, size, order](Truth* t) {
    const LocationErrors e = t->errors;
    t->table_transform = [e, k, size, order](const Pose& p, double) {
      ComponentVector c = ComponentVector::Zero();
      c[k] = size * std::cos(order * degToRad(p.C));
      return Eigen::Isometry3d(spheres3Table_m_w(Eigen::Vector4d::Zero(), c, 0.0) * T_m_w(e, p));
    };
  };
}

/// The table's position drifting by `um_per_h` in the machine's X (the clean world's drift).
Hide tableDriftX(double um_per_h) {
  return [um_per_h](Truth* t) {
    const LocationErrors e = t->errors;
    t->table_transform = [e, um_per_h](const Pose& p, double ts) {
      Eigen::Isometry3d T = T_m_w(e, p);
      T.pretranslate(Eigen::Vector3d(umToMm(um_per_h) * ts / 3600.0, 0, 0));
      return T;
    };
  };
}

/// Linear axis `moved`'s error proportional to the read position along `along` (um/m): a scale
/// where they are one axis, a squareness where not.
Hide linearError(int moved, int along, double um_per_m) {
  return [moved, along, um_per_m](Truth* t) {
    t->linear_axis_error = [moved, along, um_per_m](const Eigen::Vector3d& c) {
      return Eigen::Vector3d(Eigen::Vector3d::Unit(moved) * um_per_m * 1e-6 * c[along]);
    };
  };
}

struct Tally {
  int n = 0, found = 0, inadequate = 0, none = 0, named = 0, within = 0, refused = 0;
  std::vector<double> gains;
  void add(const JudgeSummary& s, const SphereEffect& e) {
    ++n;
    if (s.verdict == JudgeVerdict::EffectFound) ++found;
    if (s.verdict == JudgeVerdict::ModelInadequate) ++inadequate;
    if (s.verdict == JudgeVerdict::NoSignificantEffect) ++none;
    if (std::getenv("ROTACAL_BENCH_VERBOSE")) {
      std::fprintf(stderr, "  %s\n", s.message.c_str());
      for (const auto& c : s.candidate_tests)
        if (c.step == 0)
          std::fprintf(stderr, "    step 0 %s: delta chi2 %.1f (k %d), p %.3g, gain %.3g +- %.3g: %s\n", c.cause.c_str(), c.delta_chi2, c.k,
                       c.p_value, c.gain, c.gain_se, c.reason.c_str());
      for (const auto& f : s.findings) std::fprintf(stderr, "    finding %s (p %.3g, gain %.3g +- %.3g)\n", f.cause.c_str(), f.p_value, f.gain, f.gain_se);
    }
    bool any = false;
    for (const auto& f : s.findings) {
      const bool names = e.cause.empty() || f.cause == e.cause ||
                         std::find(f.confounded_with.begin(), f.confounded_with.end(), e.cause) != f.confounded_with.end();
      if (!names) continue;
      any = true;
      gains.push_back(f.gain);
      // As touch154_drawn counts it: the parameter of an accepted finding, the model then
      // explaining the data.
      if (!e.param.empty() && f.cause == e.cause && s.verdict == JudgeVerdict::EffectFound)
        for (const auto& p : f.parameters)
          if (p.name == e.param && std::abs(p.value - e.truth) < 3.0 * p.u) ++within;
    }
    // A signal the plan cannot attribute names its causes in the verdict's sentence.
    const size_t shared = s.message.find("shared by");
    any = any || (!e.cause.empty() && shared != std::string::npos && s.message.find(e.cause, shared) != std::string::npos);
    named += any && !e.cause.empty() ? 1 : 0;
  }
  std::string medianGain() const {
    if (gains.empty()) return "-";
    std::vector<double> g = gains;
    std::nth_element(g.begin(), g.begin() + static_cast<std::ptrdiff_t>(g.size() / 2), g.end());
    return fmt::format("{:.3g} ({})", g[g.size() / 2], g.size());
  }
  void print(const SphereEffect& e, double k) const {
    fmt::print("| {} | {} | {} | {} | {} | {} | {} | {} | {} |{}\n", e.what, k == 0.0 ? std::string() : fmt::format("{:g}", k), n, found,
               inadequate, none, e.param.empty() ? std::string("-") : fmt::format("{} ({})", within, e.param),
               e.cause.empty() ? std::string("-") : std::to_string(named), medianGain(),
               refused ? fmt::format(" refused on {}", refused) : std::string());
    std::fflush(stdout);
  }
};

template <typename Judge>
void row(const Judge& judge, int seeds, std::uint64_t seed0, const SphereEffect& e, double k) {
  // Run only the rows whose name contains ROTACAL_BENCH_ONLY, or is it when it starts with '='.
  const char* only = std::getenv("ROTACAL_BENCH_ONLY");
  if (only && (only[0] == '=' ? e.what != only + 1 : e.what.find(only) == std::string::npos)) return;
  Tally t;
  for (int s = 0; s < seeds; ++s) {
    try {
      t.add(judge(seed0 + static_cast<std::uint64_t>(s), e), e);
    } catch (const std::exception& ex) {
      ++t.refused;
      if (std::getenv("ROTACAL_BENCH_VERBOSE")) std::fprintf(stderr, "  refused: %s\n", ex.what());
    }
  }
  t.print(e, k);
}

/// ROTACAL_BENCH_DRAW_OFF=setup,form,linear_axes,pretravel,repeatability,roughness: those
/// contributors not drawn (the declaration the judge reads is unchanged).
void switchOff(independent::DrawOptions* d) {
  const char* off = std::getenv("ROTACAL_BENCH_DRAW_OFF");
  if (!off) return;
  const std::string o = std::string(",") + off + ",";
  const auto has = [&o](const char* w) { return o.find(std::string(",") + w + ",") != std::string::npos; };
  d->setup = !has("setup");
  d->form = !has("form");
  d->linear_axes = !has("linear_axes");
  d->pretravel = !has("pretravel");
  d->repeatability = !has("repeatability");
  d->roughness = !has("roughness");
  fmt::print("not drawn: {}\n", off);
}

const char* kHeader =
    "| hidden on a drawn machine (size) | x | machines | effect_found | model_inadequate | no_significant_effect | named "
    "within 3 u | named at all | held-out gain of the naming finding, median (findings) |\n|---|---|---|---|---|---|---|---|---|\n";

}  // namespace

Spheres3World::Spheres3World()
    : machine(exampleMachine("spheres3")),
      declared(declaredOf(machine)),
      plan(makePlan("spheres3", machine, cycleByName("spheres3").example().options)),
      noise(spheres3DeclaredNoise(plan, &declared)) {}

JudgeSummary Spheres3World::judge(std::uint64_t seed, const Hide& effect, int repeats) const {
  const independent::Machine drawn = independent::drawMachine(declared, machine, draw, seed);
  Spheres3DiagnosisOptions o;
  o.judge.alpha = kAlpha;
  o.sigma_um = plan.machine.probe.repeatability_um;  // as the cycle's diagnose
  o.noise = &noise;
  return diagnoseSpheres3(plan, independent::measureWithEffect(plan, drawn, effect, repeats, kRepeatEvery_s), o).judged;
}

std::vector<SphereEffect> spheres3Effects(double k) {
  // 001's sizes (bench/spheres3_judge_bench.cpp): 3 um of second-order radial motion (an oval
  // bearing), 000 Table 5's 30 um/m squareness, 3 um/h of drift over four repeats 30 min apart;
  // the axial, tilt and angular families at 3 um / 3 arcsec in cos 2C (assumed, of 001's order).
  const double arcsec3 = mdegToRad(3.0 / 3.6);
  return {
      {times("radial error motion EXC = 3 cos 2C um", k), componentOfC(0, umToMm(3.0 * k), 2), kSpheres3Radial, "EXC_cos2C", 3.0 * k, 1},
      {times("axial error motion EZC = 3 cos 2C um", k), componentOfC(2, umToMm(3.0 * k), 2), kSpheres3Axial, "EZC_cos2C", 3.0 * k, 1},
      {times("tilt error motion EAC = 3 arcsec cos 2C", k), componentOfC(3, k * arcsec3, 2), kSpheres3Tilt, "EAC_cos2C", k * 3.0 / 3.6, 1},
      {times("angular positioning error ECC = 3 arcsec cos 2C", k), componentOfC(5, k * arcsec3, 2), kSpheres3Angular, "ECC_cos2C",
       k * 3.0 / 3.6, 1},
      {times("squareness S_xy = 30 um/m", k), linearError(0, 1, 30.0 * k), kSpheres3Squareness, "S_xy", 30.0 * k, 1},
      {times("X scale 30 um/m", k), linearError(0, 0, 30.0 * k), kSpheres3Scale, "X_scale", 30.0 * k, 1},
      {times("drift 3 um/h in X, 4 repeats 30 min apart", k), tableDriftX(3.0 * k), kSpheres3Drift, "X/h", 3.0 * k, 4},
  };
}

SpaceframeWorld::SpaceframeWorld()
    : machine(exampleMachine("spaceframe")),
      declared(declaredOf(machine)),
      plan(makePlan("spaceframe", machine, cycleByName("spaceframe").example().options)),
      noise(spaceframeDeclaredNoise(plan, &declared)) {}

JudgeSummary SpaceframeWorld::judge(std::uint64_t seed, const Hide& effect) const {
  const independent::Machine drawn = independent::drawMachine(declared, machine, draw, seed);
  const std::vector<MeasurementRun> runs = independent::measureWithEffect(plan, drawn, effect, 1, 0.0);
  // As the cycle's diagnose: the judge sees the touches the screen keeps.
  const SpaceframeScreen screened = screenSpaceframeTouches(plan, runs, noise);
  SpaceframeDiagnosisOptions o;
  o.judge.alpha = kAlpha;
  o.sigma_um = plan.machine.probe.repeatability_um;
  o.noise = &noise;
  o.held_out_ids = screened.heldOutIds();
  const SpaceframeDiagnosis d = diagnoseSpaceframe(plan, runs, o);
  if (!d.baseline.converged) throw std::runtime_error("spaceframe diagnosis: the baseline did not converge");
  return d.judged;
}

std::vector<SphereEffect> spaceframeEffects(double k) {
  // The clean world's sizes (rotacal_diagnose_bench spaceframe): 000 Table 5's 30 um/m
  // squareness, 4 um/h of dz_AY, 20 um/m of X scale. The frame's temperature: 20 um/m, a steel
  // frame (11.5 um/m/K) 1.7 K off the temperature it was calibrated at (assumed).
  const double e = 20.0 * k;
  return {
      {times("squareness S_xy = 30 um/m", k), linearError(0, 1, 30.0 * k), "linear_axis_squareness", "S_xy", 30.0 * k, 1},
      {times("drift dz_AY 4 um/h", k),
       [k](Truth* t) {
         t->drift = [k](double ts) {
           ErrorVector d = ErrorVector::Zero();
           d[2] = umToMm(4.0 * k) * ts / 3600.0;
           return d;
         };
       },
       "thermal_drift", "dz_AY/h", 4.0 * k, 1},
      {times("X scale 20 um/m", k), linearError(0, 0, 20.0 * k), "linear_axis_scale", "s_x", 20.0 * k, 1},
      // The frame grows about its origin: each sphere moves by e times its lever (003 Table 1).
      {times("frame temperature e = 20 um/m", k),
       [e](Truth* t) {
         for (int s = 1; s <= 7; ++s) t->sphere_center_error_w_mm[s] = e * 1e-6 * spaceFrameTable1_mm()[static_cast<size_t>(s - 1)];
       },
       "frame_temperature", "e", e, 1},
  };
}

void spheres3DrawnBench(int clean_seeds, int effect_seeds) {
  const auto t0 = std::chrono::steady_clock::now();
  Spheres3World w;
  switchOff(&w.draw);
  fmt::print("spheres3 ({} points) on machines drawn from {} by the independent generator, judged against it, alpha {:.2f}\n{}",
             w.plan.points.size(), w.declared.file, kAlpha, kHeader);
  const auto judge = [&w](std::uint64_t seed, const SphereEffect& e) { return w.judge(seed, e.hide, e.repeats); };
  row(judge, clean_seeds, 11000, {"nothing, one run", [](Truth*) {}, "", "", 0.0, 1}, 0.0);
  row(judge, clean_seeds, 11500, {"nothing, 4 repeats 30 min apart", [](Truth*) {}, "", "", 0.0, 4}, 0.0);
  std::uint64_t seed0 = 12000;
  for (double k : {1.0, 3.0, 10.0})
    for (const auto& e : spheres3Effects(k)) row(judge, effect_seeds, seed0 += 100, e, k);
  fmt::print("({:.0f} s)\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

void spaceframeDrawnBench(int clean_seeds, int effect_seeds) {
  const auto t0 = std::chrono::steady_clock::now();
  SpaceframeWorld w;
  switchOff(&w.draw);
  fmt::print("spaceframe (phi -90,-45,0; {} points) on machines drawn from {} by the independent generator, judged against it "
             "after the cycle's outlier screen, alpha {:.2f}\n{}",
             w.plan.points.size(), w.declared.file, kAlpha, kHeader);
  const auto judge = [&w](std::uint64_t seed, const SphereEffect& e) { return w.judge(seed, e.hide); };
  row(judge, clean_seeds, 21000, {"nothing", [](Truth*) {}, "", "", 0.0, 1}, 0.0);
  std::uint64_t seed0 = 22000;
  for (double k : {1.0, 3.0, 10.0})
    for (const auto& e : spaceframeEffects(k)) row(judge, effect_seeds, seed0 += 100, e, k);
  fmt::print("({:.0f} s)\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

}  // namespace rotacal::drawn
