// The one-sphere cycle on the A/B dual rotary table (examples/machines/ab_table.json: a B axis on
// the bed carrying an A table, LinuxCNC's xyzab_tdr_kins), closed on the exact simulator whose
// truth is written here by hand with Eigen's own transforms (AngleAxis, Translation), not the
// chains of core/error_model.cpp (the papers' style eight) or core/kinematic_model.cpp (the
// ISO 230-7 model the fit uses):
//  - rotacal's A/B chain is the hand truth, and its Jacobian the finite differences of it;
//  - the grid is B x A; every touch stays off the stem's half, within the strokes, and the
//    programs pass the verifier in every dialect;
//  - noise-free triggers give back the eight location errors to second order and the truth's
//    sphere positions at poses outside the plan to 1e-6 um; the two directions no sphere shows
//    are A's zero (with the sphere's set-up) and A's tilt about Y (with B's zero);
//  - with the probe's noise the truth lies within 2u as often as claimed;
//  - the offsets: LinuxCNC's xyzab_tdr_kins pins (previous, change, new) and what the module
//    cannot hold, named with its route; the other controls refuse with their reason.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "controllers/dialect.hpp"
#include "controllers/linuxcnc/hal.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/one_sphere/analyze.hpp"
#include "cycles/one_sphere/budget.hpp"
#include "cycles/one_sphere/plan.hpp"
#include "test_util.hpp"
#include "tests/cycles/verify_programs.hpp"

namespace rotacal {
namespace {

MachineModel abTable() { return loadMachine(test::sourcePath("examples/machines/ab_table.json")); }

// um and mdeg, in locationParameters(TableAB)'s order: dx_BY dy_AB dz_BY a_BY b_BY c_BY c_AB dz_AB.
LocationErrors abErrors() {
  LocationErrors e;
  e.kinematics = Kinematics::TableAB;
  const double v[8] = {12.0, -8.0, 20.0, 1.5, -2.0, 0.8, -1.2, 6.0};
  for (int i = 0; i < 8; ++i) e.setReportValue(i, v[i]);
  return e;
}

// The A/B table by hand: B's three orientation errors, its place, the B motion (the table turns
// by -B about Y), A's offset from B in Z and its squareness about Z, the A motion (by -A about X).
Eigen::Isometry3d byHand(const LocationErrors& e, const Pose& p) {
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  return Eigen::Isometry3d(AngleAxisd(e.get("a_BY"), Vector3d::UnitX()) * AngleAxisd(e.get("b_BY"), Vector3d::UnitY()) *
                           AngleAxisd(e.get("c_BY"), Vector3d::UnitZ()) *
                           Eigen::Translation3d(e.get("dx_BY"), e.get("dy_AB"), e.get("dz_BY")) *
                           AngleAxisd(-degToRad(p.B), Vector3d::UnitY()) * Eigen::Translation3d(0.0, 0.0, e.get("dz_AB")) *
                           AngleAxisd(e.get("c_AB"), Vector3d::UnitZ()) * AngleAxisd(-degToRad(p.A), Vector3d::UnitX()));
}

Truth handTruth(const LocationErrors& e) {
  Truth t;
  t.errors = e;  // for the reports only: the simulator takes the table from table_transform
  t.table_transform = [e](const Pose& p, double) { return byHand(e, p); };
  return t;
}

class TableAB : public ::testing::Test {
 protected:
  MachineModel m = abTable();
  ProbePlan plan = makePlan("one_sphere", m, {});
  LocationErrors truth_errors = abErrors();
};

TEST_F(TableAB, TheChainIsTheHandTruthAndItsJacobianTheFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0), angle(-120.0, 120.0);
  for (int k = 0; k < 50; ++k) {
    LocationErrors e;
    e.kinematics = Kinematics::TableAB;
    for (int i = 0; i < 8; ++i) e.setReportValue(i, 1000.0 * u(rng));  // 1000 x realistic: the second order shows
    const Pose p{angle(rng), angle(rng), 0.0};
    const Eigen::Vector3d pw(200.0 * u(rng), 200.0 * u(rng), 200.0 * u(rng));
    EXPECT_LT(((T_m_w(e, p) * pw) - byHand(e, p) * pw).norm(), 1e-12) << k;
    const auto J = J_pm_e(e, p, pw);
    for (int i = 0; i < 8; ++i) {
      const bool len = locationParameters(Kinematics::TableAB)[static_cast<size_t>(i)].kind == ParamKind::Length;
      const double h = len ? 1e-6 : 1e-8;
      LocationErrors hi = e, lo = e;
      hi.values[i] += h;
      lo.values[i] -= h;
      const Eigen::Vector3d fd = (byHand(hi, p) * pw - byHand(lo, p) * pw) / (2 * h);
      // truncation ~h^2 |p|, rounding ~1e-16 x 400 mm / h
      EXPECT_LT((J.col(i) - fd).norm(), len ? 1e-7 : 1e-5) << k << " " << locationParameters(Kinematics::TableAB)[static_cast<size_t>(i)].name;
    }
  }
  // Nominal: the table turns by -A about X, then by -B about Y (xyzab_tdr_kins' type 1 at R = D = 0).
  const Pose p{30.0, -40.0, 0.0};
  const Eigen::Matrix3d want = (Eigen::AngleAxisd(degToRad(40.0), Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(degToRad(-30.0), Eigen::Vector3d::UnitX())).toRotationMatrix();
  EXPECT_LT((T_m_w_nominal(Kinematics::TableAB, p).linear() - want).norm(), 1e-15);
}

TEST_F(TableAB, TheGridIsBTimesAAndEveryProgramPassesTheVerifier) {
  const SphereLayout l = sphereLayoutOf(plan);
  EXPECT_EQ(l.turn_axis, 'A');
  EXPECT_EQ(plan.options.count("a_list"), 1u);
  EXPECT_EQ(plan.poses.size(), 25u);  // B x A, -60 .. 60 in 30 deg steps
  for (const auto& pose : plan.poses) {
    EXPECT_EQ(pose.pose.C, 0.0) << pose.name;
    const Eigen::Isometry3d T = byHand(LocationErrors{Kinematics::TableAB, ErrorVector::Zero()}, pose.pose);
    const Eigen::Vector3d stem = T.linear() * -Eigen::Vector3d::UnitZ();
    int n = 0;
    for (const auto& p : plan.points) {
      if (p.pose_name != pose.name) continue;
      ++n;
      const Eigen::Vector3d normal = (p.trigger_m_mm - T * l.center_w_mm).normalized();
      EXPECT_LE(normal.dot(stem), 1e-9) << pose.name << " point " << p.id;
      EXPECT_NEAR((p.trigger_m_mm - T * l.center_w_mm).norm(), l.radius_mm + m.probe.ball_radius_mm(), 1e-9);
    }
    EXPECT_GE(n, 4) << pose.name;
  }
  EXPECT_TRUE(strokeViolations(plan).empty());
  // Heidenhain's cycle 0 probes along one machine axis: the turned sides of the diagonal poses are refused.
  EXPECT_EQ(test::expectEveryDialectProgramPasses(plan, "heidenhain", "axis-aligned"), 5);
}

TEST_F(TableAB, NoiseFreeTriggersGiveBackTheEightAndTheTruthsSpherePositions) {
  const SphereCycleResult r = identifySphereCycle(plan, {simulate(plan, handTruth(truth_errors), {1})});
  ASSERT_TRUE(r.summary.usable()) << r.summary.briefReport();
  EXPECT_LT(r.residual_sd_um, 1e-6);
  std::string held;
  for (size_t i = 0; i < r.names.size(); ++i)
    if (r.identifiability.held[i]) held += (held.empty() ? "" : " ") + r.names[i].name;
  EXPECT_EQ(held, "B0A A0A");
  const SphereLayout l = sphereLayoutOf(plan);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> tilt(-90, 90), turn(-60, 60);
  for (int k = 0; k < 30; ++k) {
    const Pose pose{turn(rng), tilt(rng), 0.0};
    const Eigen::Vector3d want = byHand(truth_errors, pose) * l.center_w_mm;
    const Eigen::Vector3d got = sphereCentreInAxes(r.model, r.x.head(r.model.size()), pose);
    EXPECT_LT(mmToUm((got - want).norm()), 1e-6) << "pose " << k;
  }
  // The eight: the model's to first order; the second order of errors of tens of um and a few
  // mdeg is below 0.01 um / 0.001 mdeg.
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const bool len = locationParameters(m.kinematics)[static_cast<size_t>(i)].kind == ParamKind::Length;
    EXPECT_NEAR(r.location.reportValue(i), truth_errors.reportValue(i), len ? 0.01 : 0.001)
        << locationParameters(m.kinematics)[static_cast<size_t>(i)].name;
  }
  EXPECT_LT(r.mapping_residual_um, 0.01);
}

TEST_F(TableAB, TheTruthLiesWithinTwiceTheUncertaintyAsOftenAsClaimed) {
  // 200 noisy repeats at the declared repeatability: each of the 8 within 2 u in 95.45 % of cases;
  // accepted 92.5-98.5 % (1600 cases: sd 0.5 %).
  Truth truth = handTruth(truth_errors);
  truth.noise_um = m.probe.repeatability_um;
  int inside = 0, all = 0;
  for (int seed = 1; seed <= 200; ++seed) {
    const SphereCycleResult r = identifySphereCycle(plan, {simulate(plan, truth, {static_cast<std::uint64_t>(seed)})});
    const UncertaintyBudget b = sphereBudget(plan, r, nullptr, BudgetOptions{});
    const Eigen::VectorXd u = b.uC();
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const std::string iso = r.names[static_cast<size_t>(r.location_index_in_x[static_cast<size_t>(i)])].name;
      int q = -1;
      for (int k = 0; k < b.size(); ++k)
        if (b.names[static_cast<size_t>(k)] == iso) q = k;
      ASSERT_GE(q, 0) << iso;
      inside += std::abs(r.location.reportValue(i) - truth_errors.reportValue(i)) <= 2.0 * u[q] ? 1 : 0;
      ++all;
    }
  }
  const double rate = static_cast<double>(inside) / all;
  std::printf("one_sphere table_ab: truth within 2u in %.1f %% of %d cases\n", 100.0 * rate, all);
  EXPECT_GT(rate, 0.925);
  EXPECT_LT(rate, 0.985);
}

TEST_F(TableAB, TheOffsetsAreXyzabTdrKinsPinsAndNameWhatTheModuleCannotHold) {
  const SphereCycleResult r = identifySphereCycle(plan, {simulate(plan, handTruth(truth_errors), {1})});
  OffsetRequest o;
  o.plan = &plan;
  o.identified = r.location;
  o.u = ErrorVector::Constant(1e-4);
  o.path = "offsets.hal";
  o.previous_text = "setp xyzab_tdr_kins.z-rot-point 1.5\nsetp xyzab_tdr_kins.z-offset -10\n";
  const std::string hal = dialectByName("linuxcnc").writeOffsets(o);
  // previous + change = new, the change the identified value in mm (the B line through rot-point,
  // the A line z-offset above it in B's frame: the module's inverse, docs/e2e-linuxcnc.md)
  const auto pins = parseHalSetp(hal, "xyzab_tdr_kins");
  EXPECT_NEAR(pins.at("x-rot-point"), r.location.get("dx_BY"), 5e-7);
  EXPECT_NEAR(pins.at("y-rot-point"), r.location.get("dy_AB"), 5e-7);
  EXPECT_NEAR(pins.at("z-rot-point"), 1.5 + r.location.get("dz_BY"), 5e-7);
  EXPECT_NEAR(pins.at("z-offset"), -10.0 + r.location.get("dz_AB"), 5e-7);
  EXPECT_EQ(pins.count("x-offset"), 0u);
  EXPECT_NE(hal.find("previous"), std::string::npos);
  EXPECT_NE(hal.find("a_BY, c_BY"), std::string::npos) << hal;
  EXPECT_NE(hal.find("c_AB"), std::string::npos) << hal;
  EXPECT_NE(hal.find("rotacal compensate"), std::string::npos) << hal;
  EXPECT_NE(hal.find("G10 L2 P1 B"), std::string::npos) << hal;  // B's zero: the work offset
  for (const std::string d : {"fanuc", "haas", "siemens", "heidenhain", "okuma"}) {
    o.path = "offsets.txt";
    o.previous_text.clear();
    try {
      (void)dialectByName(d).writeOffsets(o);
      ADD_FAILURE() << d << " wrote an A/B table's offsets";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("xyzab_tdr_kins"), std::string::npos) << d << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace rotacal
