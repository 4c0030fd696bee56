// The 154-point plan of 000 Sec. 4.2: 7 poses, 28 / 14 points, inside the strokes, and each
// point's machine data consistent with its workpiece data through the nominal kinematics.
#include <gtest/gtest.h>

#include <map>

#include "cycles/cycle.hpp"
#include "core/probe_plan.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

TEST(Touch154, HasSevenPosesWith28And14Points) {
  const ProbePlan plan = test::touch154Plan();
  ASSERT_EQ(plan.points.size(), 154u);
  std::map<std::string, int> per_pose;
  for (const auto& p : plan.points) ++per_pose[p.pose_name];
  for (const char* n : {"I", "II", "III", "IV"}) EXPECT_EQ(per_pose[n], 28) << n;
  for (const char* n : {"V", "VI", "VII"}) EXPECT_EQ(per_pose[n], 14) << n;
}

TEST(Touch154, AtMinus90ProbesUpFaceTopAndTwoPointsPerSide) {
  const ProbePlan plan = test::touch154Plan();
  for (const char* pose : {"V", "VI", "VII"}) {
    std::map<Face, int> faces;
    for (const auto& p : plan.points)
      if (p.pose_name == pose) ++faces[p.face];
    EXPECT_EQ(faces[Face::Top], 6) << pose;
    int four = 0, two = 0;
    for (Face f : {Face::PosX, Face::PosY, Face::NegX, Face::NegY}) {
      if (faces[f] == 4) ++four;
      if (faces[f] == 2) ++two;
    }
    EXPECT_EQ(four, 1) << pose << ": the face pointing up";
    EXPECT_EQ(two, 2) << pose << ": the faces pointing sideways";
  }
}

TEST(Touch154, MachineDataFollowFromWorkpieceData) {
  const ProbePlan plan = test::touch154Plan();
  const double r = plan.machine.probe.ball_radius_mm();
  for (const auto& p : plan.points) {
    const Eigen::Isometry3d T = T_m_w_nominal(Kinematics::TableAC, p.pose);
    EXPECT_LT((T * (p.contact_w_mm + r * p.normal_w) - p.trigger_m_mm).norm(), 1e-9);
    EXPECT_LT((T.linear() * p.normal_w + p.approach_m).norm(), 1e-12);
    EXPECT_GE(-p.approach_m.z(), -0.05) << "no probing upward into a face that points down";
  }
}

TEST(Touch154, EveryWaypointInsideStrokesAndTimesIncrease) {
  const ProbePlan plan = test::touch154Plan();
  EXPECT_TRUE(strokeViolations(plan).empty());
  for (size_t i = 1; i < plan.points.size(); ++i) EXPECT_GT(plan.points[i].t_s, plan.points[i - 1].t_s);
}

TEST(Touch154, PlanSurvivesJsonRoundTrip) {
  const ProbePlan plan = test::touch154Plan();
  const ProbePlan back = planFromJson(parseJsonText(planToJson(plan).dump(1), "plan.json"));
  ASSERT_EQ(back.points.size(), plan.points.size());
  for (size_t i = 0; i < plan.points.size(); ++i) {
    EXPECT_LT((back.points[i].trigger_m_mm - plan.points[i].trigger_m_mm).norm(), 1e-12);
    EXPECT_EQ(back.points[i].target, plan.points[i].target);
  }
}

TEST(Touch154, LayoutIsAParameterAndBadOptionsAreRefused) {
  const auto m = test::acMachine();
  const ProbePlan wide = makePlan("touch154", m, {{"side_offsets_mm", "-40,-10,10,40"}});
  EXPECT_EQ(wide.points.size(), 154u);
  EXPECT_THROW(makePlan("touch154", m, {{"bogus", "1"}}), std::invalid_argument);
  EXPECT_THROW(makePlan("touch154", m, {{"side_offsets_mm", "-60,0"}}), std::invalid_argument);
  EXPECT_THROW(makePlan("no_such_cycle", m, {}), std::invalid_argument);
}

TEST(Touch154, PlanThatLeavesTheStrokeIsRefused) {
  MachineModel m = test::acMachine();
  m.z.max = 250.0;  // below the indexing height the swept piece needs
  EXPECT_THROW(makePlan("touch154", m, {}), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
