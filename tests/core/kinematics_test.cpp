// The exact kinematics: nominal poses are pure rotations D_a(-A) D_c(-C) (000 Eq. (1)) and
// D_b(-B) D_c(-C) (002 Eq. (3)); the analytic Jacobian J_pm_e matches central differences.
#include <gtest/gtest.h>

#include <random>

#include "core/error_model.hpp"
#include "core/units.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

// Central differences with h = 1e-6 (mm or rad): truncation ~h^2 * |p| ~ 1e-10 mm, rounding
// ~1e-16 * 300 mm / 1e-6 ~ 3e-8 mm. The Jacobian columns are O(1) (mm/mm) and O(300) (mm/rad).
constexpr double kFdStep = 1e-6;
constexpr double kFdTolMm = 1e-6;

TEST(Kinematics, NominalAcPoseIsEq1Rotation) {
  const Pose pose{-90.0, 0.0, 90.0};
  const Eigen::Vector3d p_w(10, -200, 170);
  const Eigen::Vector3d p_m = T_m_w_nominal(Kinematics::TableAC, pose) * p_w;
  // D_c(-90) then D_a(+90): (10,-200,170) -> (-200,-10,170) -> (-200,-170,-10).
  EXPECT_NEAR(p_m.x(), -200.0, 1e-12);
  EXPECT_NEAR(p_m.y(), -170.0, 1e-12);
  EXPECT_NEAR(p_m.z(), -10.0, 1e-12);
}

TEST(Kinematics, NominalBcPoseIs002Eq3Rotation) {
  const Pose pose{0.0, 30.0, 72.0};
  const Eigen::Vector3d p_w(-0.448, -91.187, 40.567);
  const Eigen::Vector3d expect = (Db(-degToRad(30.0)) * Dc(-degToRad(72.0))) * p_w;
  EXPECT_LT((T_m_w_nominal(Kinematics::TableBC, pose) * p_w - expect).norm(), 1e-12);
}

TEST(Kinematics, SingleOffsetShiftsCAxisCentre) {
  // 000 Fig. 3(a): dx_AY shifts the C-axis centre, a point at C = 180 moves by 2 dx_AY relative
  // to its nominal mirror image.
  LocationErrors e;
  e.set("dx_AY", 0.015);
  const Eigen::Vector3d p_w(50, 0, 100);
  const Eigen::Vector3d at0 = T_m_w(e, Pose{0, 0, 0}) * p_w;
  const Eigen::Vector3d at180 = T_m_w(e, Pose{0, 0, 180}) * p_w;
  EXPECT_NEAR(at0.x() + at180.x(), 2 * 0.015, 1e-12);
}

class JacobianTest : public ::testing::TestWithParam<Kinematics> {};

TEST_P(JacobianTest, AnalyticJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ang(-110, 20), c(-360, 360), pt(-300, 300), err(-1e-3, 1e-3);
  for (int trial = 0; trial < 20; ++trial) {
    LocationErrors e;
    e.kinematics = GetParam();
    for (int i = 0; i < kNumLocationErrors; ++i) e.values[i] = trial == 0 ? 0.0 : err(rng);
    Pose pose;
    if (GetParam() == Kinematics::TableAC) pose.A = ang(rng); else pose.B = ang(rng);
    pose.C = c(rng);
    const Eigen::Vector3d p_w(pt(rng), pt(rng), pt(rng));
    const auto J = J_pm_e(e, pose, p_w);
    for (int j = 0; j < kNumLocationErrors; ++j) {
      LocationErrors ep = e, em = e;
      ep.values[j] += kFdStep;
      em.values[j] -= kFdStep;
      const Eigen::Vector3d fd = (T_m_w(ep, pose) * p_w - T_m_w(em, pose) * p_w) / (2 * kFdStep);
      EXPECT_LT((fd - J.col(j)).norm(), kFdTolMm * std::max(1.0, fd.norm()))
          << "parameter " << locationParameters(e.kinematics)[j].name << " trial " << trial;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BothTables, JacobianTest, ::testing::Values(Kinematics::TableAC, Kinematics::TableBC));

TEST(Kinematics, ParameterNamesCarryIsoNames) {
  EXPECT_EQ(locationParameters(Kinematics::TableAC)[0].iso, "X0A");
  EXPECT_EQ(parameterIndex(Kinematics::TableAC, "b_CA"), 7);
  EXPECT_EQ(parameterIndex(Kinematics::TableBC, "dy_CB"), 1);
  EXPECT_EQ(parameterIndex(Kinematics::TableAC, "nope"), -1);
}

}  // namespace
}  // namespace rotacal
