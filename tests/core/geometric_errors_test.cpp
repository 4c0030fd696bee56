// The geometric error model against independent expressions: the chain with a C axis's component
// errors written out as its own HTM product (the three-sphere model of 001 Table 1 at A = 0,
// 000 Eq. (1) elsewhere), and the interpolation of sampled component errors against the Fourier
// series they were sampled from, evaluated in closed form between the samples.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/compensation.hpp"
#include "core/geometric_errors.hpp"
#include "core/transforms.hpp"
#include "core/units.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

// A band-limited error motion of 001's size: 3 um cos 2C radial, 1.5 um sin 3C axial, 2 urad
// cos 2C wobble, 5 urad sin C + 3 urad cos 4C angular (lengths mm, angles rad).
ComponentVector series(double c_deg) {
  const double c = degToRad(c_deg);
  ComponentVector v;
  v << 3e-3 * std::cos(2 * c), -1e-3 * std::sin(2 * c), 1.5e-3 * std::sin(3 * c), 2e-6 * std::cos(2 * c),
      1e-6 * std::sin(5 * c), 5e-6 * std::sin(c) + 3e-6 * std::cos(4 * c);
  return v;
}

ComponentErrors sampled(int n, double first_deg = 0.0) {
  ComponentErrors c;
  c.axis = 'C';
  for (int i = 0; i < n; ++i) {
    const double a = first_deg + 360.0 * i / n;
    c.angle_deg.push_back(a);
    c.values.push_back(series(a));
  }
  return c;
}

TEST(GeometricErrors, TrigonometricInterpolationReproducesTheSeriesBetweenSamples) {
  // 12 samples carry harmonics up to 6 (cos 6C only): every term of series() is below 6.
  for (double first : {0.0, -180.0, 7.5}) {
    const ComponentErrors c = sampled(12, first);
    ASSERT_TRUE(c.equallySpaced());
    for (double a = -400.0; a <= 400.0; a += 3.7)
      EXPECT_LT((c.at(a) - series(a)).cwiseAbs().maxCoeff(), 1e-15) << "first " << first << " C " << a;
  }
  // At the samples the interpolation is the sample, whatever the band.
  const ComponentErrors c8 = sampled(8);
  for (size_t i = 0; i < c8.angle_deg.size(); ++i)
    EXPECT_LT((c8.at(c8.angle_deg[i]) - c8.values[i]).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(GeometricErrors, UnequalSpacingInterpolatesLinearlyOverTheTurn) {
  ComponentErrors c;
  c.angle_deg = {0.0, 90.0, 200.0};
  for (double v : {1.0, 2.0, 4.0}) c.values.push_back(ComponentVector::Constant(v));
  ASSERT_FALSE(c.equallySpaced());
  EXPECT_NEAR(c.at(45.0)[0], 1.5, 1e-15);
  EXPECT_NEAR(c.at(145.0)[0], 3.0, 1e-15);
  EXPECT_NEAR(c.at(280.0)[0], 2.5, 1e-15);   // between 200 and 360 (= 0): 4 -> 1
  EXPECT_NEAR(c.at(-80.0)[0], 2.5, 1e-15);   // the same angle a turn earlier
}

TEST(GeometricErrors, ComponentErrorsEnterBeforeTheAxisRotation) {
  GeometricErrors g(test::table4Mean());
  g.components.push_back(sampled(12));
  std::string why;
  ASSERT_TRUE(g.validate(&why)) << why;
  const LocationErrors& e = g.location;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> A(-110.0, 20.0), C(-180.0, 180.0);
  for (int k = 0; k < 50; ++k) {
    const Pose q{A(rng), 0.0, C(rng)};
    const ComponentVector v = series(q.C);
    // 000 Eq. (1) written out, the C axis's error motion between its location and its rotation.
    const Eigen::Isometry3d expected = Dx(e.get("dx_AY")) * Dy(e.get("dy_AY")) * Dz(e.get("dz_AY")) *
                                       Da(e.get("a_AY")) * Db(e.get("b_AY")) * Dc(e.get("c_AY")) *
                                       Da(-degToRad(q.A)) * Dy(e.get("dy_CA")) * Db(e.get("b_CA")) * Dx(v[0]) *
                                       Dy(v[1]) * Dz(v[2]) * Da(v[3]) * Db(v[4]) * Dc(v[5]) * Dc(-degToRad(q.C));
    EXPECT_LT((T_m_w(g, q).matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-12) << "pose " << k;
  }
  // Without component errors the model is the location chain.
  const GeometricErrors loc(e);
  const Pose q{-30.0, 0.0, 40.0};
  EXPECT_LT((T_m_w(loc, q).matrix() - T_m_w(e, q).matrix()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(GeometricErrors, InvalidTablesAreRefused) {
  ComponentErrors c = sampled(12);
  std::string why;
  EXPECT_TRUE(c.validate(&why)) << why;
  c.angle_deg[3] = c.angle_deg[2];
  EXPECT_FALSE(c.validate(&why));
  EXPECT_NE(why.find("ascend"), std::string::npos) << why;
  c = sampled(12);
  c.values.pop_back();
  EXPECT_FALSE(c.validate(&why));
  EXPECT_NE(why.find("values"), std::string::npos) << why;
  GeometricErrors g(test::table4Mean());
  ComponentErrors b = sampled(12);
  b.axis = 'B';  // an A/C table has no B axis
  g.components.push_back(b);
  EXPECT_FALSE(g.validate(&why));
  EXPECT_NE(why.find("has no B axis"), std::string::npos) << why;
  g.components = {sampled(12), sampled(12)};
  EXPECT_FALSE(g.validate(&why));
  EXPECT_NE(why.find("given twice"), std::string::npos) << why;
}

TEST(GeometricErrors, CompensationWithComponentErrorsLandsOnTheNominalPoint) {
  GeometricErrors g(test::table4Mean());
  g.components.push_back(sampled(12));
  const GeometricErrors zero(LocationErrors{});
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> A(-105.0, 15.0), C(-180.0, 180.0), X(-200.0, 200.0);
  for (int k = 0; k < 100; ++k) {
    const Pose q{A(rng), 0.0, C(rng)};
    const Eigen::Vector3d x(X(rng), X(rng), X(rng));
    const CompensatedCommand cc = compensatePose(g, q);
    const Eigen::Vector3d x2 = compensatedPosition(g, q, x, cc.pose);
    const Eigen::Vector3d p = T_m_w(g, cc.pose).inverse() * x2;
    const Eigen::Vector3d p0 = T_m_w(zero, q).inverse() * x;
    EXPECT_LT((p - p0).norm(), 1e-9) << "pose " << k;
    if (std::abs(q.A) > 2.5) {
      EXPECT_LT(cc.direction_residual_rad, 1e-12) << "A " << q.A;
    }
  }
}

// A dense independent check of a compensated move: 400 points along each piece, against the
// 8 per piece the subdivision evaluates.
double denseDeviation(const GeometricErrors& g, const MachineCommand& from, const MachineCommand& to,
                      const CompensatedMove& m, MachineCommand start) {
  double worst = 0.0, s0 = 0.0;
  for (size_t i = 0; i < m.ends.size(); ++i) {
    worst = std::max(worst, pieceDeviation(g, from, to, s0, m.s[i], start, m.ends[i], 400));
    start = m.ends[i];
    s0 = m.s[i];
  }
  return worst;
}

TEST(CompensateMove, ALongRotaryMoveIsSplitUntilItStaysOnTheNominalPath) {
  // Issue 18: one G1 from A 0 to A -90 with 000 Table 4's errors left 1.16 um mid-move.
  const GeometricErrors g(test::table4Mean());
  const MachineCommand from{Eigen::Vector3d(50.0, -40.0, 120.0), Pose{0.0, 0.0, 0.0}};
  const MachineCommand to{Eigen::Vector3d(50.0, 80.0, 60.0), Pose{-90.0, 0.0, 45.0}};
  const CompensatedMove m = compensateMove(g, from, to);
  const MachineCommand start{compensatedPosition(g, from.pose, from.x_m_mm, compensatePose(g, from.pose).pose),
                             compensatePose(g, from.pose).pose};
  EXPECT_GT(mmToUm(m.unsplit_deviation_mm), 0.5);
  EXPECT_GT(m.ends.size(), 1u);
  std::printf("A 0 -> -90 with Table 4: unsplit %.3f um, %zu pieces, %.3f um\n", mmToUm(m.unsplit_deviation_mm),
              m.ends.size(), mmToUm(m.max_deviation_mm));
  EXPECT_LE(m.max_deviation_mm, 0.2e-3);
  EXPECT_LT(denseDeviation(g, from, to, m, start), 0.21e-3);
  // The last end is the move's own compensated end.
  const CompensatedCommand end = compensatePose(g, to.pose);
  EXPECT_LT((m.ends.back().x_m_mm - compensatedPosition(g, to.pose, to.x_m_mm, end.pose)).norm(), 1e-12);
  // A purely linear move at a fixed pose is a rigid motion of the line: never split.
  const MachineCommand a{Eigen::Vector3d(0, 0, 50), Pose{-45.0, 0.0, 10.0}};
  const MachineCommand b{Eigen::Vector3d(100, 30, 20), Pose{-45.0, 0.0, 10.0}};
  const CompensatedMove lin = compensateMove(g, a, b);
  EXPECT_EQ(lin.ends.size(), 1u);
  EXPECT_LT(lin.max_deviation_mm, 1e-9);
}

TEST(CompensateMove, FifteenDegreeStepsWithThreeTimesTable4StayWithinHalfAMicrometre) {
  // Issue 18's acceptance: a five-axis path with 15 deg rotary steps and 3 x 000 Table 4's errors
  // plus the C axis's error motion, every point of every compensated move within 0.5 um of the
  // nominal path (the tolerance is the default 0.2 um; the check is dense and independent).
  LocationErrors e = test::table4Mean();
  e.values *= 3.0;
  GeometricErrors g(e);
  g.components.push_back(sampled(12));
  double worst = 0.0, worst_unsplit = 0.0;
  for (int i = 0; i < 24; ++i) {
    // Each move turns both axes by 15 deg: C on round, A down to -90 and back.
    auto tilt = [](int k) { return -15.0 * std::abs(((k + 6) % 12) - 6); };
    const double c0 = -180.0 + 15.0 * i, c1 = c0 + 15.0, a0 = tilt(i), a1 = tilt(i + 1);
    // The tool at a point of radius 200 mm, 150 mm above the table.
    auto onPath = [](double a, double c) {
      const Eigen::Vector3d p_w(200.0 * std::cos(degToRad(c)), 200.0 * std::sin(degToRad(c)), 150.0);
      return MachineCommand{T_m_w_nominal(Kinematics::TableAC, Pose{a, 0.0, c}) * p_w, Pose{a, 0.0, c}};
    };
    const MachineCommand from = onPath(a0, c0), to = onPath(a1, c1);
    const CompensatedMove m = compensateMove(g, from, to);
    const CompensatedCommand s = compensatePose(g, from.pose);
    worst = std::max(worst, denseDeviation(g, from, to, m,
                                           MachineCommand{compensatedPosition(g, from.pose, from.x_m_mm, s.pose), s.pose}));
    worst_unsplit = std::max(worst_unsplit, m.unsplit_deviation_mm);
  }
  EXPECT_LT(worst, 0.5e-3);
  EXPECT_GT(worst_unsplit, worst);  // the splitting did something
  std::printf("15 deg steps, 3 x Table 4 + C error motion: unsplit %.3f um, split %.3f um (dense)\n",
              mmToUm(worst_unsplit), mmToUm(worst));
}

}  // namespace
}  // namespace rotacal
