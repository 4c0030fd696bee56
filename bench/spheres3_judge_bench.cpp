// rotacal_spheres3_judge_bench: printed figures of the spheres3 diagnosis through the judge
// (docs/diagnosis.md). Simulated with the spheres3 model's own exact transform and the
// probing simulator (0.7 um probe noise, declared and drawn); the judge never sees the truth.
// alpha = 0.01 (JudgeOptions' default). Run: build/bench/rotacal_spheres3_judge_bench [clean] [hidden]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <random>
#include <string>

#include <fmt/format.h>

#include "core/machine.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/spheres3/diagnose.hpp"

namespace rotacal {
namespace {

Eigen::Vector4d location(std::uint64_t seed) {  // 001's size, varied per seed
  std::mt19937_64 g(seed * 104729 + 17);
  std::normal_distribution<double> n(0.0, 1.0);
  return {umToMm(-2.0 + 5.0 * n(g)), umToMm(3.0 * n(g)), mdegToRad(0.6 * n(g)), mdegToRad(0.6 + 0.6 * n(g))};
}

struct Case {
  std::string name;
  std::string cause;   // expected judge cause ("" for none)
  std::string param;   // its parameter checked against `truth`
  double truth = 0.0;
  int runs = 1;
  std::function<void(Truth&, std::uint64_t)> hide;
  std::function<ComponentVector(double)> component;  // component errors at C (rad), when set
};

/// Component error `k` of ComponentVector (EXC EYC EZC EAC EBC ECC) = `size` cos(order C), size in
/// mm or rad.
std::function<ComponentVector(double)> cosineOfC(int k, double size, int order) {
  return [k, size, order](double cr) {
    ComponentVector e = ComponentVector::Zero();
    e[k] = size * std::cos(order * cr);
    return e;
  };
}

/// Linear axis `moved`'s error proportional to the position along `along`: a scale error where
/// they are the same axis, a squareness where not (um/m).
std::function<void(Truth&, std::uint64_t)> linearError(int moved, int along, double um_per_m) {
  return [moved, along, um_per_m](Truth& t, std::uint64_t) {
    t.linear_axis_error = [moved, along, um_per_m](const Eigen::Vector3d& p) {
      return Eigen::Vector3d(Eigen::Vector3d::Unit(moved) * um_per_m * 1e-6 * p[along]);
    };
  };
}

void run(const ProbePlan& plan, const Case& c, int seeds, std::uint64_t seed0) {
  int found = 0, inadequate = 0, none = 0, named = 0;
  for (int s = 0; s < seeds; ++s) {
    const std::uint64_t seed = seed0 + static_cast<std::uint64_t>(s);
    const Eigen::Vector4d L = location(seed);
    Truth t;
    t.errors.kinematics = Kinematics::TableAC;
    t.noise_um = 0.7;
    std::function<ComponentVector(double)> E;
    Eigen::Vector3d drift = Eigen::Vector3d::Zero();
    t.table_transform = [L, &E, &drift](const Pose& p, double ts) {
      const double cr = degToRad(p.C);
      Eigen::Isometry3d T = spheres3Table_m_w(L, E ? E(cr) : ComponentVector::Zero(), cr);
      T.pretranslate(drift * ts);
      return T;
    };
    if (c.hide) c.hide(t, seed);
    if (c.component) E = c.component;
    if (c.name.find("drift") != std::string::npos) drift = Eigen::Vector3d(umToMm(c.truth) / 3600.0, 0, 0);
    std::vector<MeasurementRun> runs;
    for (int r = 0; r < c.runs; ++r) {
      t.start_time_s = 1800.0 * r;
      runs.push_back(simulate(plan, t, {seed * 10 + static_cast<std::uint64_t>(r)}));
    }
    Spheres3DiagnosisOptions o;
    o.sigma_um = 0.7;
    const Spheres3Diagnosis d = diagnoseSpheres3(plan, runs, o);
    switch (d.judged.verdict) {
      case JudgeVerdict::EffectFound: ++found; break;
      case JudgeVerdict::ModelInadequate: ++inadequate; break;
      case JudgeVerdict::NoSignificantEffect: ++none; break;
    }
    if (d.judged.effectFound() && !c.cause.empty() && d.judged.findings.front().cause == c.cause)
      for (const auto& p : d.judged.findings.front().parameters)
        if (p.name == c.param && std::abs(p.value - c.truth) < 3.0 * p.u) ++named;
  }
  fmt::print("| {} | {} | {} | {} | {} | {} |\n", c.name, seeds, found, inadequate, none,
             c.cause.empty() ? std::string("-") : fmt::format("{} ({})", named, c.param));
  std::fflush(stdout);
}

}  // namespace
}  // namespace rotacal

int main(int argc, char** argv) {
  using namespace rotacal;
  const int clean = argc > 1 ? std::atoi(argv[1]) : 200, hidden = argc > 2 ? std::atoi(argv[2]) : 50;
  const ProbePlan plan = makePlan("spheres3", loadMachine(std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/ac_trunnion.json"), {});
  fmt::print("spheres3 through the judge: alpha 0.01, 0.7 um probe noise declared and drawn, 12 C angles x 3 spheres\n");
  fmt::print("| hidden in the simulation (size) | seeds | effect_found | model_inadequate | no_significant_effect | named within 3 u |\n|---|---|---|---|---|---|\n");
  run(plan, {"nothing (001-size location errors)", "", "", 0.0, 1, nullptr, nullptr}, clean, 1000);
  run(plan, {"nothing, 4 repeats 30 min apart", "", "", 0.0, 4, nullptr, nullptr}, clean, 5000);
  run(plan, {"radial error motion EXC = 3 cos 2C um", kSpheres3Radial, "EXC_cos2C", 3.0, 1, nullptr, cosineOfC(0, umToMm(3.0), 2)},
      hidden, 2000);
  run(plan, {"squareness S_xy = 30 um/m", kSpheres3Squareness, "S_xy", 30.0, 1, linearError(0, 1, 30.0), nullptr}, hidden, 3000);
  run(plan, {"drift 3 um/h in X, 4 repeats 30 min apart", kSpheres3Drift, "X/h", 3.0, 4, nullptr, nullptr}, hidden, 4000);
  run(plan, {"X scale 30 um/m", kSpheres3Scale, "X_scale", 30.0, 1, linearError(0, 0, 30.0), nullptr}, hidden, 6000);
  // The other families of the catalog, at sizes of 001's order (its component errors move the
  // spheres by up to 12 um; 3 arcsec over the ~100 mm sphere radius is 1.5 um): assumed.
  const double arcsec3 = mdegToRad(3.0 / 3.6);
  run(plan, {"axial error motion EZC = 3 cos 2C um", kSpheres3Axial, "EZC_cos2C", 3.0, 1, nullptr, cosineOfC(2, umToMm(3.0), 2)},
      hidden, 8000);
  run(plan, {"tilt error motion EAC = 3 arcsec cos 2C", kSpheres3Tilt, "EAC_cos2C", 3.0 / 3.6, 1, nullptr, cosineOfC(3, arcsec3, 2)},
      hidden, 9000);
  run(plan, {"angular positioning error ECC = 3 arcsec cos 2C", kSpheres3Angular, "ECC_cos2C", 3.0 / 3.6, 1, nullptr,
             cosineOfC(5, arcsec3, 2)},
      hidden, 10000);
  run(plan, {"radial waviness EXC = 3 cos 5C um (outside the catalog)", "", "", 0.0, 1, nullptr, cosineOfC(0, umToMm(3.0), 5)},
      hidden, 7000);
  return 0;
}
