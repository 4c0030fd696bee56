// The three-sphere cycle (001): plan layout and safety, the sphere fit against its closed form,
// and the identification against the exact simulator with known location and component errors.
#include <gtest/gtest.h>

#include <cmath>

#include "cycles/cycle.hpp"
#include "cycles/spheres3/plan.hpp"
#include "cycles/spheres3/analyze.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

ProbePlan spheresPlan(const CycleOptions& o = {}) { return makePlan("spheres3", test::acMachine(), o); }

TEST(Spheres3Plan, LayoutCounts) {
  const ProbePlan plan = spheresPlan();
  // 001: 12 angles 30 deg apart, 3 spheres, 5 touches each.
  EXPECT_EQ(plan.poses.size(), 12u);
  EXPECT_EQ(plan.points.size(), 12u * 3u * 5u);
  const double r = plan.machine.probe.ball_radius_mm();
  for (const auto& p : plan.points) {
    ASSERT_TRUE(p.sphere);
    EXPECT_DOUBLE_EQ(p.pose.A, 0.0);
    // The nominal trigger is rho = R + r from the nominal centre, against the approach.
    const Eigen::Vector3d c_m = T_m_w_nominal(plan.machine.kinematics, p.pose) * p.sphere->center_w_mm;
    EXPECT_NEAR((p.trigger_m_mm - c_m).norm(), p.sphere->radius_mm + r, 1e-12);
    EXPECT_NEAR((p.trigger_m_mm - c_m).normalized().dot(-p.approach_m), 1.0, 1e-12);
  }
  // Different heights, and the 45 deg option gives 8 angles.
  EXPECT_EQ(spheresPlan({{"c_step_deg", "45"}}).points.size(), 8u * 15u);
  EXPECT_THROW(spheresPlan({{"c_step_deg", "7"}}), std::invalid_argument);
  EXPECT_THROW(spheresPlan({{"sphere2_w_mm", "0,220,60"}}), std::invalid_argument);  // overlaps sphere 1
  EXPECT_THROW(spheresPlan({{"bogus", "1"}}), std::invalid_argument);
}

TEST(Spheres3Plan, WorksOnTheBCMachine) {
  const ProbePlan plan = makePlan("spheres3", loadMachine(test::sourcePath("examples/machines/bc_trunnion.json")), {});
  EXPECT_EQ(plan.points.size(), 180u);
  for (const auto& p : plan.poses) EXPECT_DOUBLE_EQ(p.pose.B, 0.0);
}

TEST(Spheres3Plan, PathClimbsBeforeMovingAndIndexesAtIndexZ) {
  const ProbePlan plan = spheresPlan();
  const auto path = plannedPath(plan);
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(path.front().kind, Waypoint::Kind::ClimbZ);  // Z alone first: the start is unknown
  // Then the C index, then the first XY move at the index height (not a dive from an unknown XY).
  ASSERT_GE(path.size(), 4u);
  EXPECT_EQ(path[1].kind, Waypoint::Kind::Index);
  EXPECT_EQ(path[2].kind, Waypoint::Kind::Rapid);
  EXPECT_NEAR(path[2].position_m.z(), plan.index_z_mm, 1e-9);
  EXPECT_EQ(path[3].kind, Waypoint::Kind::Position);
  EXPECT_LT((path[3].position_m - path[2].position_m).head<2>().norm(), 1e-9);  // straight down
  Eigen::Vector3d prev = path.front().position_m;
  for (const auto& w : path) {
    // Feed moves (down to a start, probing, retract) never move in XY and Z at once, except
    // the probing line itself.
    if (w.kind == Waypoint::Kind::Position) {
      EXPECT_LT((w.position_m - prev).head<2>().norm(), 1e-9);
    }
    if (w.kind == Waypoint::Kind::Index) {
      EXPECT_NEAR(w.position_m.z(), plan.index_z_mm, 1e-9);
    }
    // A rapid that moves in XY does it at the safe height (above every sphere and the piece).
    if (w.kind == Waypoint::Kind::Rapid && (w.position_m - prev).head<2>().norm() > 1e-9) {
      EXPECT_GE(prev.z(), plan.poses.front().safe_z_mm - 1e-9);
      EXPECT_GE(w.position_m.z(), plan.poses.front().safe_z_mm - 1e-9);
    }
    prev = w.position_m;
  }
  double top = 0;
  for (const auto& p : plan.points) top = std::max(top, p.sphere->center_w_mm.z() + p.sphere->radius_mm);
  EXPECT_GT(plan.poses.front().safe_z_mm, top + plan.machine.probe.ball_radius_mm());
}

// Closed form of the linearised 5-touch fit (4 at the equator, 1 on top): a touch moved by d_j
// along its outward normal gives dx = (d+x - d-x)/2, dy = (d+y - d-y)/2,
// drho = mean of the four side touches, dz = d_top - drho; variances 1/2, 1/2, 5/4.
TEST(Spheres3Fit, MatchesTheClosedForm) {
  const Eigen::Vector3d x0(12.3, -45.6, 78.9);
  const double rho = 22.0;
  const Eigen::Vector3d n[5] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitX(),
                                -Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  const double d[5] = {1.1e-3, -0.4e-3, 0.3e-3, 0.9e-3, -0.7e-3};  // mm
  std::vector<Eigen::Vector3d> pts;
  for (int j = 0; j < 5; ++j) pts.push_back(x0 + (rho + d[j]) * n[j]);
  const SphereFit f = fitSphereCentre(pts, x0 + Eigen::Vector3d(0.5, -0.5, 0.5), {rho - 0.3, true, 50});
  const double drho = (d[0] + d[1] + d[2] + d[3]) / 4;
  // Second-order terms: d^2 / rho ~ 5e-8 mm.
  EXPECT_NEAR(f.centre_mm.x() - x0.x(), (d[0] - d[2]) / 2, 1e-7);
  EXPECT_NEAR(f.centre_mm.y() - x0.y(), (d[1] - d[3]) / 2, 1e-7);
  EXPECT_NEAR(f.centre_mm.z() - x0.z(), d[4] - drho, 1e-7);
  EXPECT_NEAR(f.rho_mm - rho, drho, 1e-7);
  EXPECT_EQ(f.dof, 1);
  // Exact points: exact centre, and the covariance of the symmetric layout (1/2, 1/2, 5/4).
  std::vector<Eigen::Vector3d> exact;
  for (int j = 0; j < 5; ++j) exact.push_back(x0 + rho * n[j]);
  const SphereFit e = fitSphereCentre(exact, x0 + Eigen::Vector3d(1, 1, 1), {rho + 1, true, 50});
  EXPECT_LT((e.centre_mm - x0).norm(), 1e-12);
  EXPECT_NEAR(e.cov_centre_per_sigma2(0, 0), 0.5, 1e-9);
  EXPECT_NEAR(e.cov_centre_per_sigma2(1, 1), 0.5, 1e-9);
  EXPECT_NEAR(e.cov_centre_per_sigma2(2, 2), 1.25, 1e-9);
  EXPECT_NEAR(e.cov_centre_per_sigma2(0, 2), 0.0, 1e-9);
}

// The true table: the location errors of 000 Eq. (1) at A = 0, with the component errors
// inserted just before the C rotation (the frame of ISO 230-7's error motions).
struct ComponentTruth {
  std::vector<std::pair<ComponentTerm, double>> terms;  // coefficient mm or rad
  ComponentVector at(double c_rad) const {
    ComponentVector v = ComponentVector::Zero();
    for (const auto& [t, a] : terms) v += a * t.value(c_rad);
    return v;
  }
};

Truth truthWithComponents(const LocationErrors& e, const ComponentTruth& ct) {
  Truth t = test::truthWith(e);
  t.table_transform = [e, ct](const Pose& pose, double) {
    const double c = degToRad(pose.C);
    const ComponentVector v = ct.at(c);
    return Eigen::Isometry3d(T_m_w(e, pose) * Dc(c) * Dx(v[0]) * Dy(v[1]) * Dz(v[2]) * Da(v[3]) * Db(v[4]) *
                             Dc(v[5]) * Dc(-c));
  };
  return t;
}

ComponentTruth someComponentErrors() {
  using K = ComponentTerm::Kind;
  ComponentTruth ct;
  ct.terms = {{{K::Cos, 0, 2}, umToMm(3.0)},          // second-order radial, 3 um (issue 6)
              {{K::Sin, 1, 3}, umToMm(-1.5)},
              {{K::CounterCos, 0, 1}, umToMm(2.0)},   // elliptic first harmonic
              {{K::Cos, 2, 1}, umToMm(1.2)},          // axial wobble
              {{K::Sin, 2, 4}, umToMm(0.8)},
              {{K::Cos, 3, 2}, mdegToRad(0.4)},       // tilt error motion
              {{K::CounterSin, 3, 1}, mdegToRad(-0.3)},
              {{K::Sin, 4, 5}, mdegToRad(0.2)},
              {{K::Cos, 5, 1}, mdegToRad(1.0)},       // angular positioning error
              {{K::Cos, 5, 6}, mdegToRad(0.3)}};
  return ct;
}

// First-order C location of the 000 chain at A = 0 (spheres3_identification.hpp).
Eigen::Vector4d expectedLocation(const LocationErrors& e) {
  return {e.get("dx_AY"), e.get("dy_AY") + e.get("dy_CA"), e.get("a_AY"), e.get("b_AY") + e.get("b_CA")};
}

// Exact data: the simulator's truth with location and component errors, the spheres off their
// nominal places.
MeasurementRun exactRun(const ProbePlan& plan, const LocationErrors& e, const ComponentTruth& ct) {
  Truth truth = truthWithComponents(e, ct);
  truth.sphere_center_error_w_mm = {{1, {0.05, -0.02, 0.01}}, {2, {-0.03, 0.04, -0.02}}, {3, {0.0, 0.01, 0.03}}};
  return simulate(plan, truth, {});
}

// The exact data's truth recovered: the C axis's location to 1e-3 of the error size (0.027 um for
// the offsets, Oyc = 27.1 um; 5e-4 mdeg for the tilts) and the component errors at every angle to
// 1e-3 of their size (about 5 um, 1 mdeg).
void expectRecovers(const Spheres3Result& r, const LocationErrors& e, const ComponentTruth& ct) {
  const Eigen::Vector4d want = expectedLocation(e);
  EXPECT_NEAR(mmToUm(r.location[0]), mmToUm(want[0]), 0.027);
  EXPECT_NEAR(mmToUm(r.location[1]), mmToUm(want[1]), 0.027);
  EXPECT_NEAR(radToMdeg(r.location[2]), radToMdeg(want[2]), 5e-4);
  EXPECT_NEAR(radToMdeg(r.location[3]), radToMdeg(want[3]), 5e-4);
  for (size_t a = 0; a < r.c_deg.size(); ++a) {
    const ComponentVector v = ct.at(degToRad(r.c_deg[a]));
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(mmToUm(r.values(static_cast<Eigen::Index>(a), k)), mmToUm(v[k]), 5e-3) << componentNames()[k] << a;
    for (int k = 3; k < 6; ++k)
      EXPECT_NEAR(radToMdeg(r.values(static_cast<Eigen::Index>(a), k)), radToMdeg(v[k]), 1e-3)
          << componentNames()[k] << a;
  }
}

TEST(Spheres3Identification, RecoversLocationAndComponentErrorsNoiseFree) {
  const ProbePlan plan = spheresPlan();
  const LocationErrors e = test::table4Mean();
  const ComponentTruth ct = someComponentErrors();
  const MeasurementRun run = exactRun(plan, e, ct);
  const Spheres3Result r = identifySpheres3(plan, {run}, {});
  EXPECT_EQ(r.parameters, 6 * 12 + 3);
  EXPECT_EQ(r.rank, r.parameters);
  expectRecovers(r, e, ct);
  // The fit explains the exact data; the linearisation has converged.
  EXPECT_LT(r.residual_rms_um, 1e-4);
  EXPECT_LT(mmToUm(r.last_step_mm), 1e-6);
  EXPECT_LT(r.volumetric_after_um.maxCoeff(), 1e-3);
  EXPECT_GT(r.volumetric_before_um.maxCoeff(), 10.0);
}

TEST(Spheres3Identification, ASphereMissingATouchGivesWhatItsOtherTouchesFix) {
  // The outlier screen leaves out a top touch (a chip there) or two opposite side touches (a chip
  // under one of them, the data not telling which). On exact data (the simulator's truth, location
  // and component errors, spheres off their nominal places) the identification with them held out
  // still recovers the truth to the same tolerances as with every touch: the sphere at that angle
  // then weighs only the coordinates its other touches fix (x, y without the top; y, z without
  // the X pair), which the other spheres' and angles' data complete.
  const ProbePlan plan = spheresPlan();
  const LocationErrors e = test::table4Mean();
  const ComponentTruth ct = someComponentErrors();
  const MeasurementRun run = exactRun(plan, e, ct);
  // Touch order per sphere and angle: +X side, +Y, -X, -Y, top (plan.hpp); point ids in plan order.
  const int top = plan.points[5 * 3 * 4 + 5 * 1 + 4].id;  // sphere 2 at the fifth angle
  const int x_plus = plan.points[5 * 3 * 7 + 5 * 2 + 0].id, x_minus = plan.points[5 * 3 * 7 + 5 * 2 + 2].id;  // sphere 3, eighth angle
  ASSERT_LT(plan.points[5 * 3 * 4 + 5 * 1 + 4].approach_m.z(), -0.99);
  ASSERT_GT(std::abs(plan.points[5 * 3 * 7 + 5 * 2].approach_m.x()), 0.99);
  ASSERT_GT(std::abs(plan.points[5 * 3 * 7 + 5 * 2 + 2].approach_m.x()), 0.99);
  Spheres3Options o;
  o.hold_out_touch = [&](int, const ProbePoint& p) { return p.id == top || p.id == x_plus || p.id == x_minus; };
  const Spheres3Result r = identifySpheres3(plan, {run}, o);
  EXPECT_EQ(r.rank, r.parameters);
  int partial = 0;
  for (const auto& ob : r.observations) {
    if (ob.measured == 3) continue;
    ++partial;
    EXPECT_EQ(ob.measured, 2);
    // The coordinate not measured: the height without the top (to the spheres' tilt in the
    // machine frame, a few urad), the X line without the X pair.
    const Eigen::Vector3d axis = ob.angle == 4 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    EXPECT_NEAR((ob.unmeasured * axis).norm(), 1.0, 1e-3) << ob.angle;
    EXPECT_EQ(ob.held_point_ids.size(), ob.angle == 4 ? 1u : 2u);
  }
  EXPECT_EQ(partial, 2);
  expectRecovers(r, e, ct);
  EXPECT_LT(r.residual_rms_um, 1e-4);
  // Three side touches of one sphere fix fewer than two coordinates with the radius: refused.
  o.hold_out_touch = [&](int, const ProbePoint& p) { return p.id == top || p.id - top == -1 || p.id - top == -2; };
  EXPECT_THROW(identifySpheres3(plan, {run}, o), std::invalid_argument);
}

TEST(Spheres3Identification, VolumetricErrorBeforeIsTheTrueDisplacement) {
  // Only component errors and sphere placement: the fitted sphere positions are the true ones, so
  // the "before" volumetric error is |T_true s - Dc(-C) s| computed here independently.
  const ProbePlan plan = spheresPlan();
  LocationErrors e;
  const ComponentTruth ct = someComponentErrors();
  Truth truth = truthWithComponents(e, ct);
  truth.sphere_center_error_w_mm = {{2, {0.1, 0.0, -0.05}}};
  const Spheres3Result r = identifySpheres3(plan, {simulate(plan, truth, {})}, {});
  for (size_t a = 0; a < r.c_deg.size(); ++a)
    for (int i = 0; i < 3; ++i) {
      Eigen::Vector3d s = r.nominal_w_mm[static_cast<size_t>(i)];
      if (i == 1) s += Eigen::Vector3d(0.1, 0.0, -0.05);
      Pose pose;
      pose.C = r.c_deg[a];
      const double want = mmToUm((truth.table_transform(pose, 0) * s - Dc(-degToRad(pose.C)) * s).norm());
      EXPECT_NEAR(r.volumetric_before_um(static_cast<Eigen::Index>(a), i), want, 1e-3);
    }
}

TEST(Spheres3Identification, NoiseWithinTheReportedUncertainty) {
  const ProbePlan plan = spheresPlan();
  const LocationErrors e = test::table4Mean();
  const ComponentTruth ct = someComponentErrors();
  Truth truth = truthWithComponents(e, ct);
  truth.noise_um = 0.7;  // = the machine's stated repeatability
  const Eigen::Vector4d want = expectedLocation(e);
  double sum_z2 = 0.0;
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Spheres3Result r = identifySpheres3(plan, {simulate(plan, truth, {seed})}, {});
    for (int i = 0; i < 4; ++i) {
      const double z = (r.location[i] - want[i]) / r.location_u[i];
      EXPECT_LT(std::abs(z), 4.0) << "seed " << seed << " " << spheres3LocationNames()[static_cast<size_t>(i)];
      sum_z2 += z * z;
      ++n;
    }
    for (size_t a = 0; a < r.c_deg.size(); ++a) {
      const ComponentVector v = ct.at(degToRad(r.c_deg[a]));
      for (int k = 0; k < 6; ++k) {
        const double z = (r.values(static_cast<Eigen::Index>(a), k) - v[k]) / r.values_u(static_cast<Eigen::Index>(a), k);
        EXPECT_LT(std::abs(z), 4.5) << "seed " << seed << " " << componentNames()[k] << " angle " << a;
        sum_z2 += z * z;
        ++n;
      }
    }
  }
  // The uncertainty is calibrated (not just large): rms of the normalised errors near 1. It uses
  // max(prior, a-posteriori) sigma, so it may sit somewhat below 1; 80 location + 1440 component
  // values pin it to about +-5 %.
  const double rms_z = std::sqrt(sum_z2 / n);
  EXPECT_GT(rms_z, 0.6);
  EXPECT_LT(rms_z, 1.2);
}

TEST(Spheres3Identification, RefusesAnImplausibleSphereRadius) {
  ProbePlan plan = spheresPlan();
  const MeasurementRun run = simulate(plan, test::truthWith(test::table4Mean()), {});
  for (auto& p : plan.points) p.sphere->radius_mm += 0.025;  // the plan says 19.025 mm
  try {
    identifySpheres3(plan, {run}, {});
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fitted radius"), std::string::npos) << e.what();
  }
}

TEST(Spheres3Identification, EveryAngleCountIsFullRank) {
  for (const char* step : {"90", "60", "45", "30", "20"}) {
    const ProbePlan plan = spheresPlan({{"c_step_deg", step}});
    Truth truth = test::truthWith(test::table4Mean());
    const Spheres3Result r = identifySpheres3(plan, {simulate(plan, truth, {})}, {});
    EXPECT_EQ(r.parameters, 6 * static_cast<int>(plan.poses.size()) + 3) << step;
    EXPECT_NEAR(mmToUm(r.location[1]), mmToUm(expectedLocation(test::table4Mean())[1]), 0.027) << step;
  }
}

}  // namespace
}  // namespace rotacal
