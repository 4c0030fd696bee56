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
#include "core/rng.hpp"
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
      else if (m.name == "head_table" || m.name == "head_cb") p = {0, t, c};  // B tilts, C turns
      else if (m.name == "table_ab") p = {c, t, 0};  // B tilts, the A table it carries turns
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
  // two tilting axes (head_ab, table_ab): the second one's angles from the tilts too
  const bool heads = m.name == "head_ab" || m.name == "table_ab";
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
  // machine two A angles x four B angles, on the A/B table two B angles x four A angles).
  std::vector<int> regular;
  for (size_t k = 0; k < cand.size(); ++k) {
    const Pose& p = cand[k];
    const double t = m.name == "head_ab" ? p.A : (m.name == "table_ac" ? p.A : p.B);
    const double c = m.name == "head_ab" ? p.B : (m.name == "table_ab" ? p.A : p.C);
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

// Centre readings of the grid's poses (mm per model unit), and a covariance in which the readings
// of poses whose centres lie within some 60 mm share a part (as the linear axes' random errors do).
struct BudgetCase {
  KinematicModel m = kinematicModel("table_ac", kSphere);
  std::vector<Pose> cand = grid(m, {-90, -60, -30, 0, 15}, {0, 45, 90, 135, 180, 225, 270, 315});
  std::vector<Eigen::MatrixXd> rows;
  std::vector<IdentifiabilityParameter> names;
  Eigen::MatrixXd C;
  BudgetCase() {
    std::vector<Eigen::Vector3d> at;
    for (const auto& p : cand) {
      rows.push_back(J_X_p(m, Eigen::VectorXd::Zero(m.size()), p));
      const Eigen::Vector3d c = sphereCentreInAxes(m, Eigen::VectorXd::Zero(m.size()), p);
      for (int r = 0; r < 3; ++r) at.push_back(c);
    }
    for (const auto& q : m.parameters) names.push_back({q.name, q.kind});
    const auto n = static_cast<Eigen::Index>(at.size());
    C = Eigen::MatrixXd::Zero(n, n);
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = 0; j < n; ++j) {
        const double d = (at[static_cast<size_t>(i)] - at[static_cast<size_t>(j)]).norm();
        if (i % 3 == j % 3) C(i, j) = std::pow(umToMm(2.0), 2) * std::exp(-d * d / (2 * 30.0 * 30.0));
      }
    C.diagonal().array() += std::pow(umToMm(0.7), 2);
  }
};

TEST(PoseDesign, BudgetCovarianceIsTheLeastSquaresSandwich) {
  const BudgetCase b;
  PoseBudgetOptions o;
  o.weight = Eigen::VectorXd::Ones(b.m.size());
  const std::vector<int> subset = {0, 3, 9, 13, 18, 22, 26, 31, 36};
  // Independent readings: sigma^2 (J^T J)^-1, which identifiability gives as u_report.
  const double sd = umToMm(0.7);
  const Eigen::MatrixXd white = sd * sd * Eigen::MatrixXd::Identity(b.C.rows(), b.C.cols());
  const Eigen::MatrixXd V = poseSetCovariance(b.rows, b.names, white, subset, o);
  Eigen::MatrixXd Js(3 * static_cast<Eigen::Index>(subset.size()), b.m.size());
  for (size_t k = 0; k < subset.size(); ++k) Js.middleRows(3 * static_cast<Eigen::Index>(k), 3) = b.rows[static_cast<size_t>(subset[k])] / sd;
  Eigen::MatrixXd Jall(3 * static_cast<Eigen::Index>(b.cand.size()), b.m.size());
  for (size_t k = 0; k < b.cand.size(); ++k) Jall.middleRows(3 * static_cast<Eigen::Index>(k), 3) = b.rows[k];
  const Identifiability all = identifiability(Jall, b.names);
  const Identifiability id = identifiability(Js, b.names);
  for (int i = 0; i < b.m.size(); ++i) {
    if (all.held[static_cast<size_t>(i)]) {
      EXPECT_EQ(V(i, i), 0.0) << b.names[static_cast<size_t>(i)].name;
      continue;
    }
    const bool len = b.names[static_cast<size_t>(i)].kind == ParamKind::Length;
    const double u = std::sqrt(V(i, i));
    EXPECT_NEAR(len ? mmToUm(u) : radToMdeg(u), id.u_report[i], 1e-6 * id.u_report[i]) << b.names[static_cast<size_t>(i)].name;
  }
  // Correlated readings: the sandwich against the spread of 4000 least-squares fits of readings
  // drawn with covariance C (held parameters dropped, as the design drops them).
  const Eigen::MatrixXd Vc = poseSetCovariance(b.rows, b.names, b.C, subset, o);
  std::vector<Eigen::Index> idx, freec;
  for (int k : subset)
    for (Eigen::Index r = 0; r < 3; ++r) idx.push_back(3 * k + r);
  for (int i = 0; i < b.m.size(); ++i)
    if (!all.held[static_cast<size_t>(i)]) freec.push_back(i);
  const auto m = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd Cs(m, m), Jf(m, static_cast<Eigen::Index>(freec.size()));
  for (Eigen::Index r = 0; r < m; ++r) {
    for (Eigen::Index q = 0; q < m; ++q) Cs(r, q) = b.C(idx[static_cast<size_t>(r)], idx[static_cast<size_t>(q)]);
    for (size_t c = 0; c < freec.size(); ++c) Jf(r, static_cast<Eigen::Index>(c)) = Jall(idx[static_cast<size_t>(r)], freec[c]);
  }
  const Eigen::MatrixXd L = Cs.llt().matrixL();
  const auto qr = Jf.colPivHouseholderQr();
  Rng rng(7, 0);
  const int runs = 4000;
  Eigen::VectorXd sum2 = Eigen::VectorXd::Zero(Jf.cols());
  for (int run = 0; run < runs; ++run) {
    Eigen::VectorXd z(m);
    for (Eigen::Index r = 0; r < m; ++r) z[r] = rng.normal();
    const Eigen::VectorXd x = qr.solve(Eigen::VectorXd(L * z));
    sum2 += x.cwiseAbs2();
  }
  for (size_t c = 0; c < freec.size(); ++c) {
    const double predicted = Vc(freec[c], freec[c]);
    // The sample variance of 4000 normal draws: relative sd sqrt(2 / 4000) = 2.2 %; 5 of them.
    EXPECT_NEAR(sum2[static_cast<Eigen::Index>(c)] / runs, predicted, 0.112 * predicted) << b.names[static_cast<size_t>(freec[c])].name;
  }
}

TEST(PoseDesign, BudgetRefinementLowersTheCriterionAndNoSingleExchangeLowersItFurther) {
  const BudgetCase b;
  PoseDesignOptions d_opt;
  d_opt.poses = 8;
  std::vector<Eigen::MatrixXd> white;
  for (const auto& r : b.rows) white.push_back(r / umToMm(0.7));
  const PoseDesign d = designPoses(white, b.names, d_opt);
  PoseBudgetOptions o;
  // The tight one: A0A (the tilt axis's zero) weighed as a 0.3 mdeg reference, the rest 1 um / 1 mdeg.
  o.weight = Eigen::VectorXd::Zero(b.m.size());
  for (int i = 0; i < b.m.size(); ++i) {
    const bool len = b.names[static_cast<size_t>(i)].kind == ParamKind::Length;
    const double ref = b.names[static_cast<size_t>(i)].name == "A0A" ? mdegToRad(0.3) : (len ? umToMm(1.0) : mdegToRad(1.0));
    o.weight[i] = 1.0 / (ref * ref);
  }
  const double start = poseSetBudget(b.rows, b.names, b.C, d.chosen, o);
  const PoseDesign r = refinePosesForBudget(b.rows, b.names, b.C, d.chosen, o);
  ASSERT_EQ(r.chosen.size(), d.chosen.size());
  EXPECT_NEAR(r.budget, poseSetBudget(b.rows, b.names, b.C, r.chosen, o), 1e-9 * r.budget);
  EXPECT_LT(r.budget, start);
  for (size_t c = 0; c < r.chosen.size(); ++c)
    for (int k = 0; k < static_cast<int>(b.cand.size()); ++k) {
      if (std::find(r.chosen.begin(), r.chosen.end(), k) != r.chosen.end()) continue;
      std::vector<int> s = r.chosen;
      s[c] = k;
      EXPECT_GE(poseSetBudget(b.rows, b.names, b.C, s, o), r.budget * (1 - 1e-9));
    }
  std::printf("budget design (8 of %zu poses): criterion %.3f from the D-optimal %.3f\n", b.cand.size(), r.budget, start);
  // Bad input: a weight of the wrong size, none counted, a start pose twice.
  PoseBudgetOptions bad = o;
  bad.weight = Eigen::VectorXd::Ones(3);
  EXPECT_THROW(refinePosesForBudget(b.rows, b.names, b.C, d.chosen, bad), std::invalid_argument);
  bad.weight = Eigen::VectorXd::Zero(b.m.size());
  EXPECT_THROW(refinePosesForBudget(b.rows, b.names, b.C, d.chosen, bad), std::invalid_argument);
  std::vector<int> twice = d.chosen;
  twice[1] = twice[0];
  EXPECT_THROW(refinePosesForBudget(b.rows, b.names, b.C, twice, o), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
