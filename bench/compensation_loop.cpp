#include "bench/compensation_loop.hpp"

#include <algorithm>
#include <cmath>

#include "controllers/dialect.hpp"
#include "core/compensation.hpp"
#include "core/geometric_errors.hpp"
#include "core/rng.hpp"
#include "core/simulation.hpp"
#include "core/transforms.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "postproc/report_errors.hpp"

namespace rotacal {
namespace {

// One term a cos(k C) + b sin(k C) of an error motion.
struct Harmonic {
  int k;
  double a, b;
};

double evaluate(const std::vector<Harmonic>& h, double rad) {
  double v = 0.0;
  for (const auto& t : h) v += t.a * std::cos(t.k * rad) + t.b * std::sin(t.k * rad);
  return v;
}

// The true machine, written out: 000 Eq. (1) with the A axis's error motion EYA before the A
// rotation and the C axis's six error motions before the C rotation.
struct TrueMachine {
  LocationErrors location;
  std::array<std::vector<Harmonic>, 6> c_motion;  // EXC EYC EZC (mm) EAC EBC ECC (rad)
  std::vector<Harmonic> eya;                      // mm, function of A

  Eigen::Isometry3d T_m_w(const Pose& q) const {
    const auto& e = location;
    const double a = degToRad(q.A), c = degToRad(q.C);
    return Dx(e.get("dx_AY")) * Dy(e.get("dy_AY")) * Dz(e.get("dz_AY")) * Da(e.get("a_AY")) * Db(e.get("b_AY")) *
           Dc(e.get("c_AY")) * Dy(evaluate(eya, a)) * Da(-a) * Dy(e.get("dy_CA")) * Db(e.get("b_CA")) *
           Dx(evaluate(c_motion[0], c)) * Dy(evaluate(c_motion[1], c)) * Dz(evaluate(c_motion[2], c)) *
           Da(evaluate(c_motion[3], c)) * Db(evaluate(c_motion[4], c)) * Dc(evaluate(c_motion[5], c)) * Dc(-c);
  }
};

// 001-size errors: location errors of 000 Table 4's size (lengths 15 um, angles 0.3 mdeg, k = 1),
// the C axis's error motions of 001 Fig. 8-10's size (radial 1.5 um per harmonic 2-3, axial
// 0.7 um at 1-3, tilts 2 urad at 2-3, angular 3 urad at 1-4), and 1 um sin 2A of EYA.
TrueMachine draw(std::uint64_t seed) {
  Rng rng(1818, seed);
  TrueMachine t;
  t.location.kinematics = Kinematics::TableAC;
  const auto& params = locationParameters(Kinematics::TableAC);
  for (int i = 0; i < kNumLocationErrors; ++i)
    t.location.setReportValue(i, (params[i].kind == ParamKind::Length ? 15.0 : 0.3) * rng.normal());
  auto harmonics = [&](int k0, int k1, double sd) {
    std::vector<Harmonic> h;
    for (int k = k0; k <= k1; ++k) h.push_back({k, sd * rng.normal(), sd * rng.normal()});
    return h;
  };
  t.c_motion[0] = harmonics(2, 3, umToMm(1.5));
  t.c_motion[1] = harmonics(2, 3, umToMm(1.5));
  t.c_motion[2] = harmonics(1, 3, umToMm(0.7));
  t.c_motion[3] = harmonics(2, 3, 2e-6);
  t.c_motion[4] = harmonics(2, 3, 2e-6);
  t.c_motion[5] = harmonics(1, 4, 3e-6);
  t.eya = {{2, 0.0, umToMm(1.0)}};
  return t;
}

JsonDoc analyzed(const ProbePlan& plan, const TrueMachine& tm, double noise_um, std::uint64_t seed,
                 const std::string& name) {
  Truth truth;
  truth.errors.kinematics = plan.machine.kinematics;
  truth.noise_um = noise_um;
  truth.table_transform = [tm](const Pose& q, double) { return tm.T_m_w(q); };
  SimulationOptions so;
  so.seed = seed;
  const MeasurementRun run = simulate(plan, truth, so);
  const Dialect& csv = dialectByName("csv");
  const DialectIO io{"csv",
                     [&csv](const std::string& text, const std::string& file, const ProbePlan& p) {
                       return csv.parseResults(text, file, p);
                     },
                     [&csv](const ProbePlan& p, const MeasurementRun& r) { return csv.writeResults(p, r); }};
  AnalyzeRequest req;
  req.plan = &plan;
  req.results = {InputFile{name + ".csv", csv.writeResults(plan, run)}};
  req.dialect = &io;
  const CycleDocuments d = cycleByName(plan.cycle).analyze(req);
  JsonDoc doc;
  doc.value = d.doc;
  doc.file = name + ".json";
  doc.text = d.doc.dump(1);
  return doc;
}

// The tool point seen from the workpiece on the true machine for a command.
Eigen::Vector3d reached(const TrueMachine& tm, const MachineCommand& c) { return tm.T_m_w(c.pose).inverse() * c.x_m_mm; }

double spheresError(const TrueMachine& tm, const ProbePlan& spheres3, const GeometricErrors* errors) {
  double worst = 0.0;
  std::vector<Eigen::Vector3d> centres;
  for (const auto& p : spheres3.points)
    if (p.sphere &&
        std::none_of(centres.begin(), centres.end(), [&](const Eigen::Vector3d& c) { return (c - p.sphere->center_w_mm).norm() < 1e-9; }))
      centres.push_back(p.sphere->center_w_mm);
  for (int i = 0; i < 12; ++i) {
    const Pose q{0.0, 0.0, -180.0 + 30.0 * i};
    for (const auto& s : centres) {
      MachineCommand c{T_m_w_nominal(Kinematics::TableAC, q) * s, q};
      if (errors) {
        const CompensatedCommand cc = compensatePose(*errors, q);
        c = MachineCommand{compensatedPosition(*errors, q, c.x_m_mm, cc.pose), cc.pose};
      }
      worst = std::max(worst, (reached(tm, c) - s).norm());
    }
  }
  return mmToUm(worst);
}

MachineCommand pathPoint(int k) {
  const double tilt = -15.0 * std::abs(((k + 6) % 12) - 6);
  const Pose q{tilt, 0.0, -180.0 + 15.0 * k};
  const double c = degToRad(q.C);
  const Eigen::Vector3d p_w(150.0 * std::cos(c), 150.0 * std::sin(c), 100.0);
  return {T_m_w_nominal(Kinematics::TableAC, q) * p_w, q};
}

Eigen::Vector3d nominalWorkpiece(const MachineCommand& c) {
  return T_m_w_nominal(Kinematics::TableAC, c.pose).inverse() * c.x_m_mm;
}

MachineCommand lerp(const MachineCommand& a, const MachineCommand& b, double s) {
  return {a.x_m_mm + s * (b.x_m_mm - a.x_m_mm),
          Pose{a.pose.A + s * (b.pose.A - a.pose.A), 0.0, a.pose.C + s * (b.pose.C - a.pose.C)}};
}

double pathError(const TrueMachine& tm, const GeometricErrors* errors, int* pieces) {
  constexpr int kSamples = 50;
  double worst = 0.0;
  for (int k = 0; k < 24; ++k) {
    const MachineCommand from = pathPoint(k), to = pathPoint(k + 1);
    if (!errors) {
      for (int i = 0; i <= kSamples; ++i) {
        const MachineCommand c = lerp(from, to, static_cast<double>(i) / kSamples);
        worst = std::max(worst, (reached(tm, c) - nominalWorkpiece(c)).norm());
      }
      continue;
    }
    const CompensatedMove m = compensateMove(*errors, from, to);
    *pieces += static_cast<int>(m.ends.size());
    const CompensatedCommand s = compensatePose(*errors, from.pose);
    MachineCommand start{compensatedPosition(*errors, from.pose, from.x_m_mm, s.pose), s.pose};
    double s0 = 0.0;
    for (size_t p = 0; p < m.ends.size(); ++p) {
      for (int i = 0; i <= kSamples; ++i) {
        const double sigma = static_cast<double>(i) / kSamples;
        const MachineCommand nominal = lerp(from, to, s0 + sigma * (m.s[p] - s0));
        const MachineCommand actual = lerp(start, m.ends[p], sigma);
        worst = std::max(worst, (reached(tm, actual) - nominalWorkpiece(nominal)).norm());
      }
      start = m.ends[p];
      s0 = m.s[p];
    }
  }
  return mmToUm(worst);
}

}  // namespace

LoopSetup loopSetup(const std::string& machine_file) {
  LoopSetup s;
  s.machine = loadMachine(machine_file);
  s.touch154 = cycleByName("touch154").plan(s.machine, {});
  s.spheres3 = cycleByName("spheres3").plan(s.machine, {});
  return s;
}

LoopResult runLoop(const LoopSetup& setup, std::uint64_t seed, double noise_um, bool with_eya) {
  TrueMachine tm = draw(seed);
  if (!with_eya) tm.eya.clear();
  const JsonDoc r1 = analyzed(setup.touch154, tm, noise_um, 2 * seed + 1, "touch154");
  const JsonDoc r3 = analyzed(setup.spheres3, tm, noise_um, 2 * seed + 2, "spheres3");
  const GeometricErrors both = errorsFromReports({r1, r3}, Kinematics::TableAC, false).errors;
  const GeometricErrors alone = errorsFromReports({r3}, Kinematics::TableAC, false).errors;
  LoopResult r;
  r.spheres_before_um = spheresError(tm, setup.spheres3, nullptr);
  r.spheres_after_um = spheresError(tm, setup.spheres3, &both);
  r.spheres_after_spheres3_only_um = spheresError(tm, setup.spheres3, &alone);
  r.path_before_um = pathError(tm, nullptr, nullptr);
  r.path_after_um = pathError(tm, &both, &r.pieces);
  return r;
}

}  // namespace rotacal
