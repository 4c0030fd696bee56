// The D-optimal pose design against a search that does not go through it: every subset of a
// small candidate set (exhaustive), every single exchange of the design (local optimality), and
// the regular grid a user would pick with the same number of poses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <algorithm>

#include "core/pose_design.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

const Eigen::Vector3d kSphere(120.0, -80.0, 150.0);

std::vector<Pose> grid(const KinematicModel& m, const std::vector<double>& tilts, const std::vector<double>& turns) {
  std::vector<Pose> out;
  for (double t : tilts)
    for (double c : turns) {
      Pose p;
      if (m.name == "table_ac") p = {t, 0, c};
      else if (m.name == "table_bc") p = {0, t, c};
      else if (m.name == "head_table") p = {0, t, c};
      else p = {t, c, 0};
      out.push_back(p);
    }
  return out;
}

TEST(PoseDesign, FindsTheBestSubsetOfASmallCandidateSet) {
  const KinematicModel m = kinematicModel("table_ac", kSphere);
  const std::vector<Pose> cand = grid(m, {0, -45, -90}, {0, 120, 240});
  PoseDesignOptions o;
  o.poses = 4;
  const PoseDesign d = designPoses(m, cand, o);
  double best = -std::numeric_limits<double>::infinity();
  std::vector<int> subset;
  std::function<void(int)> rec = [&](int from) {
    if (static_cast<int>(subset.size()) == o.poses) {
      best = std::max(best, poseSetLogDet(m, cand, subset, o));
      return;
    }
    for (int k = from; k < static_cast<int>(cand.size()); ++k) {
      subset.push_back(k);
      rec(k + 1);
      subset.pop_back();
    }
  };
  rec(0);  // 126 subsets
  ASSERT_TRUE(std::isfinite(best));
  EXPECT_NEAR(d.log_det, best, 1e-9 * std::abs(best));
  EXPECT_NEAR(poseSetLogDet(m, cand, d.chosen, o), d.log_det, 1e-9 * std::abs(best));
}

class EveryConfiguration : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryConfiguration, NoSingleExchangeImprovesTheDesignAndItBeatsARegularGrid) {
  const KinematicModel m = kinematicModel(GetParam(), kSphere, 250.0);
  const std::vector<double> tilts = {-90, -75, -60, -45, -30, -15, 0, 15, 30};
  const bool heads = m.name == "head_ab";  // two tilting axes: the second one's angles from the tilts too
  const std::vector<Pose> cand =
      grid(m, tilts, heads ? tilts : std::vector<double>{0, 30, 60, 90, 120, 150, 180, 210, 240, 270, 300, 330});
  PoseDesignOptions o;
  o.poses = 8;
  o.centre_sd_mm = Eigen::Vector3d(umToMm(0.5), umToMm(0.5), umToMm(0.7));
  const PoseDesign d = designPoses(m, cand, o);
  ASSERT_EQ(d.chosen.size(), 8u);
  for (size_t c = 0; c < d.chosen.size(); ++c)
    for (int k = 0; k < static_cast<int>(cand.size()); ++k) {
      if (std::find(d.chosen.begin(), d.chosen.end(), k) != d.chosen.end()) continue;
      std::vector<int> s = d.chosen;
      s[c] = k;
      EXPECT_LE(poseSetLogDet(m, cand, s, o), d.log_det + 1e-9 * std::abs(d.log_det)) << GetParam();
    }
  // The regular grid with as many poses: two tilts (0 and -90) x four C angles (on the head-head
  // machine two A angles x four B angles).
  std::vector<int> regular;
  for (size_t k = 0; k < cand.size(); ++k) {
    const Pose& p = cand[k];
    const double t = m.name == "head_ab" ? p.A : (m.name == "table_ac" ? p.A : p.B);
    const double c = m.name == "head_ab" ? p.B : p.C;
    const bool c_ok = heads ? (c == 0 || c == 30 || c == -90 || c == -45) : std::fmod(c, 90.0) == 0.0;
    if ((t == 0 || t == -90) && c_ok) regular.push_back(static_cast<int>(k));
  }
  ASSERT_EQ(regular.size(), 8u) << GetParam();
  EXPECT_GT(d.log_det, poseSetLogDet(m, cand, regular, o)) << GetParam();
  {
    // For the record: the largest u of a separable length and angle, designed against regular.
    Eigen::MatrixXd Jr(3 * static_cast<Eigen::Index>(regular.size()), m.size());
    for (size_t k = 0; k < regular.size(); ++k)
      Jr.middleRows(3 * static_cast<Eigen::Index>(k), 3) =
          o.centre_sd_mm.cwiseInverse().asDiagonal() * J_X_p(m, Eigen::VectorXd::Zero(m.size()), cand[static_cast<size_t>(regular[k])]);
    std::vector<IdentifiabilityParameter> names;
    for (const auto& q : m.parameters) names.push_back({q.name, q.kind});
    const Identifiability reg = identifiability(Jr, names);
    double dl = 0, da = 0, rl = 0, ra = 0;
    for (int i = 0; i < m.size(); ++i) {
      const bool len = m.parameters[static_cast<size_t>(i)].kind == ParamKind::Length;
      if (d.identifiability.separable[static_cast<size_t>(i)]) (len ? dl : da) = std::max(len ? dl : da, d.identifiability.u_report[i]);
      if (reg.separable[static_cast<size_t>(i)]) (len ? rl : ra) = std::max(len ? rl : ra, reg.u_report[i]);
    }
    std::printf("%s: 8 designed poses: largest u %.3f um, %.4f mdeg (log det %.2f); regular 2 x 4: %.3f um, %.4f mdeg (%.2f)\n",
                GetParam().c_str(), dl, da, d.log_det, rl, ra, poseSetLogDet(m, cand, regular, o));
  }
  // What the design separates is what the whole candidate set separates.
  EXPECT_EQ(d.identifiability.rank, m.size() - static_cast<int>(d.identifiability.combinations.size()));
  int separable = 0;
  for (int i = 0; i < m.size(); ++i) separable += d.identifiability.separable[static_cast<size_t>(i)] ? 1 : 0;
  EXPECT_GE(separable, 4) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(PoseDesign, EveryConfiguration, ::testing::ValuesIn(kinematicConfigurations()));

TEST(PoseDesign, RefusesMorePosesThanCandidatesAndBadOptions) {
  const KinematicModel m = kinematicModel("table_ac", kSphere);
  PoseDesignOptions o;
  o.poses = 5;
  EXPECT_THROW(designPoses(m, grid(m, {0}, {0, 90}), o), std::invalid_argument);
  o.poses = 0;
  EXPECT_THROW(designPoses(m, grid(m, {0, -90}, {0, 90, 180}), o), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
