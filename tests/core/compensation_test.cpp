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

TEST(Compensation, AtAZeroTheTiltNoRotaryAxisUndoesIsReportedNotChased) {
  // At A = 0 the C axis is parallel to the tool. Tilts about Y (b_AY of the A axis, b_CA of the
  // C axis) tilt the tool relative to the piece about Y, which neither A (about X) nor C (about
  // the tool) can undo: the damped solve leaves C almost where it was (a tilt of 5 mdeg would
  // need 90 deg of C) and reports |b_AY + b_CA| as the residual.
  LocationErrors e;
  e.set("b_AY", mdegToRad(2.0));
  e.set("b_CA", mdegToRad(3.0));
  const Pose q;  // A = 0, C = 0
  const CompensatedCommand cc = compensatePose(e, q);
  EXPECT_LT(std::abs(cc.pose.C), 1e-3);  // deg
  EXPECT_NEAR(cc.direction_residual_rad, mdegToRad(5.0), 1e-3 * mdegToRad(5.0));
  // A tilt about X at A = 0 (a_AY) is undone by A itself, undamped.
  LocationErrors ea;
  ea.set("a_AY", mdegToRad(5.0));
  const CompensatedCommand ca = compensatePose(ea, q);
  EXPECT_NEAR(ca.pose.A, 0.005, 1e-9);  // Da(a_AY) Da(-A2) = Da(-A): A2 = A + a_AY (deg)
  EXPECT_LT(ca.direction_residual_rad, 1e-12);
}

TEST(Compensation, TheCommandIsContinuousThroughTheSingularPose) {
  // A path through A = 0 in steps of 0.005 deg at C = 30 deg with 3 x 000 Table 4's errors: the
  // compensated C must change smoothly (the former cap switched it off by about 0.1 deg between
  // neighbouring blocks), stay bounded, and be exact beyond the blend tilt.
  const LocationErrors e = scaled(test::table4Mean(), 3.0);
  const CompensationOptions o;
  double previous_dC = 0.0, worst_jump = 0.0, worst_dC = 0.0;
  bool first = true;
  for (int i = -800; i <= 800; ++i) {
    Pose q;
    q.A = 0.005 * i;
    q.C = 30.0;
    const CompensatedCommand cc = compensatePose(e, q, o);
    const double dC = cc.pose.C - q.C;
    if (!first) worst_jump = std::max(worst_jump, std::abs(dC - previous_dC));
    worst_dC = std::max(worst_dC, std::abs(dC));
    previous_dC = dC;
    first = false;
    if (std::abs(q.A) > o.singular_blend_deg + 1e-9) {
      EXPECT_LT(cc.direction_residual_rad, 1e-12) << "A " << q.A;
    }
  }
  // The undamped correction 1/sin(A) x tilt changes by ~tilt x 0.005 deg / sin^2 between
  // neighbours; the damped one by at most its slope near A = 0: tilt / sin^2(2 deg) per rad.
  // The tilt C restores near A = 0 is bounded by the angular errors that tilt the tool about Y
  // there (b_AY, b_CA, c_AY: 0.8 mdeg in sum of magnitudes, scaled by 3).
  const double tilt_rad = mdegToRad(3.0 * 0.8);
  const double s1 = std::sin(degToRad(o.singular_blend_deg));
  EXPECT_LT(worst_jump, radToDeg(tilt_rad / (s1 * s1) * degToRad(0.005)) * 1.5);
  EXPECT_LT(worst_dC, radToDeg(1.3 * tilt_rad / s1));
  EXPECT_GT(worst_dC, 1e-4);  // C does move to restore the direction near the blend
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
  std::string why;
  EXPECT_TRUE(o.validate(&why)) << why;
  o.tool_axis_m = Eigen::Vector3d(0, 0, 2);
  EXPECT_FALSE(o.validate(&why));
  EXPECT_NE(why.find("tool_axis_m"), std::string::npos) << why;
  EXPECT_THROW(compensatePose(LocationErrors{}, Pose{}, o), std::invalid_argument);
  o = CompensationOptions{};
  o.singular_blend_deg = 0;
  EXPECT_FALSE(o.validate(&why));
  EXPECT_NE(why.find("singular_blend_deg"), std::string::npos) << why;
  SubdivisionOptions s;
  EXPECT_TRUE(s.validate(&why)) << why;
  s.max_deviation_mm = 0;
  EXPECT_FALSE(s.validate(&why));
  EXPECT_NE(why.find("max_deviation_mm"), std::string::npos) << why;
}

}  // namespace
}  // namespace rotacal
