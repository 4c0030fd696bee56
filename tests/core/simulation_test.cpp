// The exact simulator against an independent computation: the ball centre is moved along the
// approach line and mapped back into the workpiece frame through the inverse HTM, and the
// contact is found by bisection on its distance to the true face plane.
#include <gtest/gtest.h>

#include "core/probe_plan.hpp"
#include "core/simulation.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

// Bisection to 1e-13 mm of the distance function; the closed-form contact is exact to rounding.
constexpr double kContactTolMm = 1e-10;

double contactByBisection(const ProbePlan& plan, const ProbePoint& p, const Truth& truth) {
  const Plane w = truth.artefact.face(*plan.machine.artefact, p.face);
  const Eigen::Isometry3d Tinv = T_m_w(truth.errors, p.pose).inverse();
  const double r = plan.machine.probe.ball_radius_mm();
  auto gap = [&](double s) { return w.normal.dot(Tinv * (p.trigger_m_mm + s * p.approach_m) - w.point) - r; };
  double lo = -plan.machine.approach_mm, hi = plan.machine.overtravel_mm;
  EXPECT_GT(gap(lo), 0.0);
  EXPECT_LT(gap(hi), 0.0);
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (gap(mid) > 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Truth roughTruth() {
  Truth t = test::truthWith(test::table4Mean());
  t.artefact.setup.translation_mm = Eigen::Vector3d(0.5, -0.3, 0.1);
  t.artefact.setup.rotation_rad = Eigen::Vector3d(0.001, -0.0015, 0.002);
  t.artefact.form[static_cast<size_t>(Face::Top)].tilt_v_rad = 0.002;
  t.artefact.form[static_cast<size_t>(Face::PosX)].tilt_u_rad = 0.0002;
  t.artefact.form[static_cast<size_t>(Face::NegY)].offset_mm = 0.02;
  return t;
}

TEST(Simulation, TriggersMatchBisectionOnTheExactGeometry) {
  const ProbePlan plan = test::touch154Plan();
  const Truth truth = roughTruth();
  const MeasurementRun run = simulate(plan, truth, {});
  ASSERT_EQ(run.points.size(), plan.points.size());
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const ProbePoint& p = plan.points[i];
    const double s = contactByBisection(plan, p, truth);
    EXPECT_NEAR(p.approach_m.dot(run.points[i].position_m_mm - p.trigger_m_mm), s, kContactTolMm) << "point " << p.id;
    // The ball moves along the approach line only.
    const Eigen::Vector3d d = run.points[i].position_m_mm - p.trigger_m_mm;
    EXPECT_LT((d - d.dot(p.approach_m) * p.approach_m).norm(), 1e-12);
  }
}

TEST(Simulation, PerfectMachineTriggersAtNominal) {
  const ProbePlan plan = test::touch154Plan();
  const MeasurementRun run = simulate(plan, Truth{}, {});
  for (size_t i = 0; i < plan.points.size(); ++i)
    EXPECT_LT((run.points[i].position_m_mm - plan.points[i].trigger_m_mm).norm(), 1e-12);
}

TEST(Simulation, NoiseHasTheRequestedSpreadAndIsSeeded) {
  const ProbePlan plan = test::touch154Plan();
  Truth t;
  t.noise_um = 0.7;
  const MeasurementRun a = simulate(plan, t, {42});
  const MeasurementRun b = simulate(plan, t, {42});
  double ss = 0;
  for (size_t i = 0; i < plan.points.size(); ++i) {
    EXPECT_EQ(a.points[i].position_m_mm, b.points[i].position_m_mm);
    ss += std::pow(mmToUm(alongApproach(plan.points[i], a.points[i])), 2);
  }
  const double sd = std::sqrt(ss / static_cast<double>(plan.points.size()));
  // 154 samples: the sample sd of a normal has a relative sd of 1/sqrt(2*154) = 5.7 %; 4 sd.
  EXPECT_NEAR(sd, 0.7, 0.7 * 0.23);
}

TEST(Simulation, LinearAxisErrorMovesTheTriggerByItsNormalComponent) {
  // The controller reads c while the ball sits at c + E(c): the recorded trigger moves by
  // -n.E along the normal. E here is a scale error of X (10 um/m) plus a 2 um Y offset.
  const ProbePlan plan = test::touch154Plan();
  Truth t;
  t.linear_axis_error = [](const Eigen::Vector3d& c) { return Eigen::Vector3d(1e-5 * c.x(), 0.002, 0.0); };
  const MeasurementRun run = simulate(plan, t, {});
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const ProbePoint& p = plan.points[i];
    const Eigen::Vector3d n = -p.approach_m;
    // Exact for this E: the fixed point of s = n.E(c0 + s u) (linear in s), solved by hand.
    const Eigen::Vector3d E0 = t.linear_axis_error(p.trigger_m_mm);
    const double dEx_ds = 1e-5 * p.approach_m.x();
    const double s = n.dot(E0) / (1.0 - n.x() * dEx_ds);  // u = -n, n.u = -1
    EXPECT_NEAR(alongApproach(p, run.points[i]), s, 1e-12) << "point " << p.id;
  }
}

TEST(Simulation, OutOfRangeSurfaceIsANoTrigger) {
  const ProbePlan plan = test::touch154Plan();
  Truth t;
  t.artefact.setup.translation_mm = Eigen::Vector3d(0, 0, -3.0);  // top 3 mm low: past the 2 mm overtravel
  EXPECT_THROW(simulate(plan, t, {}), std::runtime_error);
}


// Ball on sphere against bisection of the centre distance along the approach line.
TEST(Simulation, BallSphereContactIsTheFirstTouchOnTheWayIn) {
  const Eigen::Vector3d x(10.0, -20.0, 30.0);
  const double r = 3.0, R = 12.7;
  const Eigen::Vector3d u = Eigen::Vector3d(-1.0, 0.3, -0.2).normalized();
  const Eigen::Vector3d c0 = x - (r + R) * u + Eigen::Vector3d(0.0, 0.4, 0.7);  // off the centre line
  const double s = ballSphereContact(c0, u, r, x, R);
  EXPECT_NEAR((c0 + s * u - x).norm(), r + R, 1e-12);  // on the contact sphere, to rounding
  double lo = s - 5.0, hi = s + 1e-3;                      // outside before, inside just after
  auto gap = [&](double t) { return (c0 + t * u - x).norm() - (r + R); };
  ASSERT_GT(gap(lo), 0.0);
  ASSERT_LT(gap(hi), 0.0);
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (gap(mid) > 0 ? lo : hi) = mid;
  }
  EXPECT_NEAR(s, 0.5 * (lo + hi), 1e-10);
  EXPECT_THROW(ballSphereContact(c0 + 50.0 * Eigen::Vector3d::UnitY(), u, r, x, R), std::invalid_argument);
}

TEST(Simulation, SphereTouchFollowsTheTrueTableAndTheSphereError) {
  // A one-point sphere plan on the A/C machine: the trigger moves by the sphere's error plus
  // what the location errors do to its centre, projected on the approach (exact for a touch
  // through the centre).
  ProbePlan plan = test::touch154Plan();
  ProbePoint p;
  p.id = 1;
  p.pose.A = -30.0;
  p.pose.C = 45.0;
  SphereTarget st{2, Eigen::Vector3d(120.0, 0.0, 50.0), 12.7};
  p.sphere = st;
  const double r = plan.machine.probe.ball_radius_mm();
  LocationErrors nominal;
  nominal.kinematics = plan.machine.kinematics;
  const Eigen::Vector3d c_m = T_m_w(nominal, p.pose) * st.center_w_mm;
  p.approach_m = -Eigen::Vector3d::UnitZ();
  p.trigger_m_mm = c_m + (r + st.radius_mm) * Eigen::Vector3d::UnitZ();
  p.pose_name = "S";
  plan.points = {p};
  plan.poses = {{"S", p.pose, plan.index_z_mm}};  // a plan file's points name its poses
  Truth truth;
  truth.errors = nominal;
  truth.errors.set("dx_AY", 0.010);
  truth.errors.set("dz_AY", 0.020);
  truth.errors.set("a_AY", 1e-4);
  truth.sphere_center_error_w_mm[2] = Eigen::Vector3d(0.0, 0.0, 0.005);
  const MeasurementRun run = simulate(plan, truth, SimulationOptions{});
  const Eigen::Vector3d true_c = T_m_w(truth.errors, p.pose) * (st.center_w_mm + Eigen::Vector3d(0, 0, 0.005));
  EXPECT_NEAR((run.points[0].position_m_mm - true_c).norm(), r + st.radius_mm, 1e-12);
  // The plan round-trips its sphere through PLAN.json.
  const ProbePlan back = planFromJson(JsonDoc{planToJson(plan), "plan.json", ""});
  ASSERT_TRUE(back.points[0].sphere.has_value());
  EXPECT_EQ(back.points[0].sphere->id, 2);
  EXPECT_DOUBLE_EQ(back.points[0].sphere->radius_mm, 12.7);
  EXPECT_TRUE(back.points[0].sphere->center_w_mm.isApprox(st.center_w_mm));
}

}  // namespace
}  // namespace rotacal
