#pragma once
// What the one-sphere tests of a spindle head (head_table_test.cpp, head_ab_test.cpp) check the
// same way: the fit's held parameters and values in report units, the verifier carrying the ball
// along the spindle, the truth within 2u as often as claimed, and a truth file in the model's
// ISO 230-7 names driving the simulator as the hand-written truth does.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "controllers/dialect.hpp"
#include "controllers/motion_reader.hpp"
#include "core/errors.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/check_rules.hpp"
#include "cycles/cycle.hpp"
#include "cycles/one_sphere/analyze.hpp"
#include "cycles/one_sphere/budget.hpp"
#include "postproc/program_check.hpp"

namespace rotacal::test {

/// Injected errors: um and mdeg, by ISO 230-7 name.
using Injected = std::map<std::string, double>;
/// A truth written by hand (Eigen's own transforms) for a machine and its injected errors.
using HandTruth = std::function<Truth(const Injected&)>;

inline double at(const Injected& e, const std::string& k) {
  const auto it = e.find(k);
  return it == e.end() ? 0.0 : it->second;
}

/// Injected errors in the simulator's units, for the hand-written truths.
struct InjectedSI {
  Injected e;
  double mm(const char* k) const { return umToMm(at(e, k)); }
  double rad(const char* k) const { return mdegToRad(at(e, k)); }
};

/// By hand (Eigen's AngleAxis and Translation, not the model's chains): a head axis at its place
/// (the two translations across it), tilted about the other two directions, at its zero, turned
/// by +angle (ISO 841).
inline Eigen::Isometry3d aHeadByHand(const InjectedSI& x, double a_deg) {
  using Eigen::AngleAxisd;
  return Eigen::Isometry3d(Eigen::Translation3d(0.0, x.mm("Y0A"), x.mm("Z0A")) *
                           AngleAxisd(x.rad("B0A"), Eigen::Vector3d::UnitY()) * AngleAxisd(x.rad("C0A"), Eigen::Vector3d::UnitZ()) *
                           AngleAxisd(x.rad("A0A") + degToRad(a_deg), Eigen::Vector3d::UnitX()));
}
inline Eigen::Isometry3d bHeadByHand(const InjectedSI& x, double b_deg) {
  using Eigen::AngleAxisd;
  return Eigen::Isometry3d(Eigen::Translation3d(x.mm("X0B"), 0.0, x.mm("Z0B")) *
                           AngleAxisd(x.rad("A0B"), Eigen::Vector3d::UnitX()) * AngleAxisd(x.rad("C0B"), Eigen::Vector3d::UnitZ()) *
                           AngleAxisd(x.rad("B0B") + degToRad(b_deg), Eigen::Vector3d::UnitY()));
}

/// A truth by hand from the table's frame and the head's frame at a pose: the ball L + dL down
/// the spindle from the head's frame, dX_T dY_T off it; the sphere's set-up as its centre's error.
using FrameByHand = std::function<Eigen::Isometry3d(const InjectedSI&, const Pose&)>;
inline Truth truthByHand(const MachineModel& m, const Injected& e, const FrameByHand& table, const FrameByHand& head) {
  const InjectedSI x{e};
  const double L = m.head->pivot_to_ball_mm;
  Truth t;
  t.table_transform = [x, table](const Pose& p, double) { return table(x, p); };
  t.head_ball = [x, head, L](const Pose& p, double) {
    return Eigen::Vector3d(head(x, p) * Eigen::Vector3d(x.mm("dX_T"), x.mm("dY_T"), -(L + x.mm("dL"))));
  };
  t.sphere_center_error_w_mm[1] = Eigen::Vector3d(x.mm("dX_S"), x.mm("dY_S"), x.mm("dZ_S"));
  return t;
}

inline std::string heldNames(const SphereCycleResult& r) {
  std::string s;
  for (size_t i = 0; i < r.names.size(); ++i)
    if (r.identifiability.held[i]) s += (s.empty() ? "" : " ") + r.names[i].name;
  return s;
}

inline double reportValue(const SphereCycleResult& r, size_t i) {
  const double v = r.x[static_cast<Eigen::Index>(i)];
  return r.names[i].kind == ParamKind::Length ? mmToUm(v) : radToMdeg(v);
}

/// A pose's touches on a head machine, the sphere's centre at c_m: the ball L along the spindle
/// from the pivot the axes read, each trigger a ball on the sphere, its contact on the stylus's
/// side (the stylus never reaches round the sphere) and off the stem's half. Returns the touches.
inline std::vector<const ProbePoint*> expectHeadTouches(const ProbePlan& plan, const PlanPose& pose,
                                                        const Eigen::Vector3d& c_m, double rho) {
  const MachineModel& m = plan.machine;
  const Eigen::Vector3d d = stylusAxis_m(m, pose.pose);
  const Eigen::Vector3d b = ballFromAxes_m(m, pose.pose);
  EXPECT_NEAR(b.norm(), m.head->pivot_to_ball_mm, 1e-9);
  EXPECT_NEAR(b.dot(d), -m.head->pivot_to_ball_mm, 1e-9);
  std::vector<const ProbePoint*> out;
  for (const auto& p : plan.points) {
    if (p.pose_name != pose.name) continue;
    out.push_back(&p);
    const Eigen::Vector3d ball = p.trigger_m_mm + b;
    EXPECT_NEAR((ball - c_m).norm(), rho, 1e-9) << p.id;
    const Eigen::Vector3d normal = (ball - c_m).normalized();
    EXPECT_GE(normal.dot(d), -1e-9) << pose.name << " point " << p.id << ": the stylus reaches round the sphere";
    EXPECT_GE(normal.z(), -1e-9) << pose.name << " point " << p.id << ": the stem's half";
    EXPECT_NEAR(p.approach_m.dot(normal), -1.0, 1e-12) << pose.name << " point " << p.id << ": a touch along its normal";
  }
  return out;
}

/// Every separable parameter as injected (1e-6 um / 1e-7 mdeg; 0 for those the model has not, dR
/// and the squareness), and no held one injected. Returns how many were compared.
inline int expectEverySeparableAsInjected(const SphereCycleResult& r, const Injected& e) {
  int checked = 0;
  for (size_t i = 0; i < r.names.size(); ++i) {
    const bool length = r.names[i].kind == ParamKind::Length;
    const double want = i < static_cast<size_t>(r.model.size()) ? at(e, r.names[i].name) : 0.0;
    if (r.identifiability.held[i]) {
      EXPECT_EQ(want, 0.0) << r.names[i].name << " is held but was injected";
      continue;
    }
    EXPECT_NEAR(reportValue(r, i), want, length ? 1e-6 : 1e-7) << r.names[i].name;
    ++checked;
  }
  return checked;
}

/// The plan with its safe heights as a table machine's would be (the ball at the reading): the
/// head puts the ball L lower, through the sphere, and the verifier must say so.
inline void expectTheVerifierCarriesTheBall(const ProbePlan& plan) {
  ProbePlan wrong = plan;
  for (auto& p : wrong.poses) p.safe_z_mm += ballFromAxes_m(plan.machine, p.pose).z();
  const Cycle& cycle = cycleOfPlan(wrong);
  const std::string text = dialectByName("linuxcnc").writeProgram(cycle.program(wrong, "linuxcnc"));
  const ProgramCheckSetup s = programCheckSetup(wrong.machine, "linuxcnc", ctl::numbersPrograms("linuxcnc"), &wrong, true);
  const ProgramCheckResult r = checkProgram(ctl::readMotions("linuxcnc", text), s);
  ASSERT_FALSE(r.violations.empty());
  EXPECT_NE(r.violations.front().problem.find("sphere"), std::string::npos) << r.violations.front().problem;
}

/// `runs` (200) noisy repeats at the declared repeatability, half the machines without a set-up error
/// (what the plan holds must not depend on the data); the fraction of the model's separable
/// parameters (sphere set-up aside) within 2 u, over `cases` of them.
inline double withinTwiceU(const ProbePlan& plan, const Injected& injected, const HandTruth& truth_of,
                           const std::string& held, int* cases, int runs = 200) {
  auto no_setup = injected;
  for (const char* k : {"dX_S", "dY_S", "dZ_S"}) no_setup.erase(k);
  int inside = 0, all = 0;
  for (int seed = 1; seed <= runs; ++seed) {
    const auto& truth_errors = seed % 2 ? injected : no_setup;
    Truth truth = truth_of(truth_errors);
    truth.noise_um = plan.machine.probe.repeatability_um;
    const SphereCycleResult r = identifySphereCycle(plan, {simulate(plan, truth, {static_cast<std::uint64_t>(seed)})});
    EXPECT_EQ(heldNames(r), held) << "seed " << seed;
    const UncertaintyBudget b = sphereBudget(plan, r, nullptr, BudgetOptions{});
    const Eigen::VectorXd u = b.uC();
    for (int k = 0; k < b.size(); ++k) {
      const std::string& name = b.names[static_cast<size_t>(k)];
      const int i = r.model.parameterIndex(name);
      if (i < 0 || (name.rfind("d", 0) == 0 && name.back() == 'S')) continue;
      inside += std::abs(reportValue(r, static_cast<size_t>(i)) - at(truth_errors, name)) <= 2.0 * u[k] ? 1 : 0;
      ++all;
    }
  }
  *cases = all;
  return static_cast<double>(inside) / all;
}

/// A truth file naming the injected errors drives the simulator as the hand truth does (to
/// 1e-6 um); one naming `foreign` (not this machine's) is refused at its line, listing `known`.
inline void expectTheTruthFileDrivesTheSimulator(const ProbePlan& plan, const Injected& injected,
                                                 const HandTruth& truth_of, const std::string& foreign,
                                                 const std::string& known) {
  Json j = {{"format", "rotacal-truth/1"}};
  for (const auto& [k, v] : injected) {
    const bool angle = k.size() == 3 && k[1] == '0' && (k[0] == 'A' || k[0] == 'B' || k[0] == 'C');
    j["location_errors"][k] = {{"value", v}, {"unit", angle ? "mdeg" : "um"}};
  }
  const Truth from_file = truthFromJson(parseJsonText(j.dump(), "truth.json"), plan.machine);
  const MeasurementRun a = simulate(plan, from_file, {1});
  // The file's set-up goes into the model's table chain; the hand truth carries it as the sphere's.
  const MeasurementRun b = simulate(plan, truth_of(injected), {1});
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t k = 0; k < a.points.size(); ++k)
    EXPECT_LT(mmToUm((a.points[k].position_m_mm - b.points[k].position_m_mm).norm()), 1e-6) << k;
  Json bad = j;
  bad["location_errors"][foreign] = {{"value", 1.0}, {"unit", "um"}};
  try {
    (void)truthFromJson(parseJsonText(bad.dump(1), "truth.json"), plan.machine);
    FAIL() << foreign << " was accepted on a " << kinematicsName(plan.machine.kinematics) << " machine";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("truth.json:"), std::string::npos) << err.what();
    EXPECT_NE(std::string(err.what()).find(known), std::string::npos) << err.what();
  }
}

}  // namespace rotacal::test
