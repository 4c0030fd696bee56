// The compensated command against its definition, checked through the inverse path: on the
// machine with errors, the compensated command must put the controlled point on the workpiece
// point the nominal command reaches on the nominal machine, with the nominal tool direction
// wherever the rotary axes can give it.
#include <gtest/gtest.h>

#include <random>

#include "core/compensation.hpp"
#include "core/units.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

// Exact HTM products of a few hundred mm: rounding of double arithmetic only.
constexpr double kPositionTolMm = 1e-9;

LocationErrors scaled(const LocationErrors& e, double k) {
  LocationErrors s = e;
  s.values *= k;
  return s;
}

Eigen::Vector3d workpiecePoint(const LocationErrors& e, const Pose& q, const Eigen::Vector3d& x) {
  return T_m_w(e, q).inverse() * x;
}

TEST(Compensation, ControlledPointLandsOnTheNominalWorkpiecePoint) {
  const LocationErrors e = scaled(test::table4Mean(), 10.0);  // 0.1-0.3 mm, 5 mdeg: far from linear
  LocationErrors zero;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> A(-105.0, 15.0), C(-180.0, 180.0), X(-300.0, 300.0);
  for (int k = 0; k < 200; ++k) {
    Pose q;
    q.A = A(rng);
    q.C = C(rng);
    const Eigen::Vector3d x(X(rng), X(rng), X(rng));
    const CompensatedCommand cc = compensatePose(e, q);
    const Eigen::Vector3d x2 = compensatedPosition(e, q, x, cc.pose);
    EXPECT_LT((workpiecePoint(e, cc.pose, x2) - workpiecePoint(zero, q, x)).norm(), kPositionTolMm) << "pose " << k;
    // Away from A = 0 both rotary axes orient the tool: the direction is restored to rounding.
    if (std::abs(q.A) > 5.0) {
      EXPECT_LT(cc.direction_residual_rad, 1e-12) << "A " << q.A;
    }
    // Without compensation the same command misses by the errors' size.
    EXPECT_GT((workpiecePoint(e, q, x) - workpiecePoint(zero, q, x)).norm(), 0.05);
  }
}

TEST(Compensation, AtAZeroTheTiltAboutTheToolAxisPlaneIsReportedNotChased) {
  // At A = 0 the C axis is parallel to the tool. A tilt of the C axis about Y (b_CA) tilts the
  // tool relative to the piece about Y, which no rotary axis of an A/C table can undo without
  // turning C by ~90 deg: the solve leaves it (C unchanged) and reports it as the residual.
  LocationErrors e;
  e.set("b_CA", mdegToRad(5.0));
  const Pose q;  // A = 0, C = 0
  const CompensatedCommand cc = compensatePose(e, q);
  EXPECT_NEAR(cc.pose.C, 0.0, 1e-12);
  EXPECT_NEAR(cc.direction_residual_rad, mdegToRad(5.0), 1e-9);  // the whole tilt stays
  // A tilt about X at A = 0 (a_AY) is undone by A itself.
  LocationErrors ea;
  ea.set("a_AY", mdegToRad(5.0));
  const CompensatedCommand ca = compensatePose(ea, q);
  EXPECT_NEAR(ca.pose.A, 0.005, 1e-9);  // Da(a_AY) Da(-A2) = Da(-A): A2 = A + a_AY (deg)
  EXPECT_LT(ca.direction_residual_rad, 1e-12);
}

TEST(Compensation, ZeroErrorsChangeNothing) {
  LocationErrors zero;
  Pose q;
  q.A = -37.0;
  q.C = 123.0;
  const CompensatedCommand cc = compensatePose(zero, q);
  EXPECT_DOUBLE_EQ(cc.pose.A, q.A);
  EXPECT_DOUBLE_EQ(cc.pose.C, q.C);
  const Eigen::Vector3d x(10, -20, 30);
  EXPECT_LT((compensatedPosition(zero, q, x, cc.pose) - x).norm(), 1e-12);
}

TEST(Compensation, OptionsAreValidated) {
  CompensationOptions o;
  o.tool_axis_m = Eigen::Vector3d(0, 0, 2);
  EXPECT_THROW(o.validate(), std::invalid_argument);
  o = CompensationOptions{};
  o.max_rotary_change_deg = 0;
  EXPECT_THROW(o.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
