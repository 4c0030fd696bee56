// The five-axis model with both rotary axes' location errors (issue 19), each configuration
// checked by a path that does not go through its chain code:
//  - 000 Eq. (1) and 002 Eq. (2)-(3) as rotacal has carried them since the first cycles
//    (core/error_model.cpp): where the two factor orders coincide the transforms agree exactly;
//  - the product of exponentials: every motion of the machine is a rotation about a located
//    line (Rodrigues' formula about the axis lines read at zero pose), so
//    T(theta) = rot(line_1, s_1 theta_1) rot(line_2, s_2 theta_2) T(0) for any errors;
//  - J_X_p against central differences;
//  - identifiability: the rank and the unseen directions each configuration has in closed form.
// Then noise-free readings of a sphere at a pose set are fitted by the shared engine and every
// identifiable combination is recovered to 1e-6 um / 1e-7 mdeg.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <random>

#include "core/error_model.hpp"
#include "core/identifiability.hpp"
#include "core/kinematic_model.hpp"
#include "core/least_squares.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

const Eigen::Vector3d kSphere(120.0, -80.0, 150.0);
constexpr double kPivotToBall = 250.0;

KinematicModel model(const std::string& name, char head = 'B') { return kinematicModel(name, kSphere, kPivotToBall, head); }

Eigen::VectorXd randomErrors(const KinematicModel& m, std::mt19937& rng, double len_mm, double ang_rad) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd p(m.size());
  for (int i = 0; i < m.size(); ++i) p[i] = u(rng) * (m.parameters[i].kind == ParamKind::Length ? len_mm : ang_rad);
  return p;
}

Pose randomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> tilt(-100, 100), turn(-360, 360);
  return {tilt(rng), tilt(rng), turn(rng)};
}

Eigen::VectorXd at(const KinematicModel& m, const std::vector<std::pair<const char*, double>>& values) {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(m.size());
  for (const auto& [name, v] : values) {
    const int i = m.parameterIndex(name);
    EXPECT_GE(i, 0) << name;
    if (i >= 0) p[i] = v;
  }
  return p;
}

// The papers' parameters whose factors have a counterpart here, and that counterpart.
struct PapersModel {
  std::string configuration;
  Kinematics kinematics;
  std::vector<std::pair<const char*, const char*>> same;  // paper name -> ISO 230-7 name here
};

class AgreesWithThePapersModel : public ::testing::TestWithParam<PapersModel> {};

TEST_P(AgreesWithThePapersModel, WhereTheFactorOrdersCoincide) {
  const PapersModel& c = GetParam();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const KinematicModel m = model(c.configuration);
  const auto& info = locationParameters(c.kinematics);
  for (int trial = 0; trial < 50; ++trial) {
    LocationErrors e;
    e.kinematics = c.kinematics;
    Eigen::VectorXd p = Eigen::VectorXd::Zero(m.size());
    for (const auto& [paper, here] : c.same) {
      const int i = parameterIndex(c.kinematics, paper);
      ASSERT_GE(i, 0) << paper;
      e.values[i] = (info[static_cast<size_t>(i)].kind == ParamKind::Length ? 0.2 : 2e-3) * u(rng);
      ASSERT_GE(m.parameterIndex(here), 0) << here;
      p[m.parameterIndex(here)] = e.values[i];
    }
    const Pose pose = randomPose(rng);
    EXPECT_LT((sphereCentreInAxes(m, p, pose) - T_m_w(e, pose) * kSphere).norm(), 1e-12) << "trial " << trial;
  }
}

// 000: Dx Dy Dz Da(a_AY) [Db Dc] Da(-A) Dy(dy_CA) Db(b_CA) Dc(-C). With b_AY = c_AY = 0 every
// other factor has its counterpart here: Dx(dx_AY) commutes with Da and is X0C.
// 002: [Da Db Dc](a_BY b_BY c_BY) Dx(dx_BY) Dy(dy_CB) Dz(dz_BY) Db(-B) Da(a_CB) Dx(dx_CB) Dc(-C).
// With the B axis's three angles zero: Dy(dy_CB) commutes with Db(-B) and is Y0C; Da(a_CB)
// Dx(dx_CB) = Dx Da is X0C then A0C.
// A/B: [Da Db Dc](a_BY b_BY c_BY) Dx(dx_BY) Dy(dy_AB) Dz(dz_BY) Db(-B) Dz(dz_AB) Dc(c_AB) Da(-A).
// With the B axis's three angles zero: Dy(dy_AB) commutes with Db(-B) and is Y0A; Dz(dz_AB)
// Dc(c_AB) is Z0A then C0A.
INSTANTIATE_TEST_SUITE_P(
    KinematicModel, AgreesWithThePapersModel,
    ::testing::Values(PapersModel{"table_ac", Kinematics::TableAC,
                                  {{"dx_AY", "X0C"}, {"dy_AY", "Y0A"}, {"dz_AY", "Z0A"}, {"a_AY", "A0A"},
                                   {"dy_CA", "Y0C"}, {"b_CA", "B0C"}}},
                      PapersModel{"table_bc", Kinematics::TableBC,
                                  {{"dx_BY", "X0B"}, {"dz_BY", "Z0B"}, {"dy_CB", "Y0C"}, {"dx_CB", "X0C"},
                                   {"a_CB", "A0C"}}},
                      PapersModel{"table_ab", Kinematics::TableAB,
                                  {{"dx_BY", "X0B"}, {"dz_BY", "Z0B"}, {"dy_AB", "Y0A"}, {"dz_AB", "Z0A"},
                                   {"c_AB", "C0A"}}}),
    [](const auto& info) { return info.param.configuration; });

// Rotation by angle about the line through q with direction w (Rodrigues), as a transform.
Eigen::Isometry3d aboutLine(const Eigen::Vector3d& q, const Eigen::Vector3d& w, double angle) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, w.normalized()).toRotationMatrix();
  T.translation() = q - T.linear() * q;
  return T;
}

// The axis lines at zero pose, read from the chain's frames just before each axis's motion.
struct Line {
  char axis;
  Eigen::Vector3d q, w;
  double sign;
};
std::vector<Line> linesAtZero(const std::vector<ModelFactor>& chain, const Eigen::VectorXd& p) {
  std::vector<Line> lines;
  Eigen::Isometry3d F = Eigen::Isometry3d::Identity();
  for (const auto& f : chain) {
    if (f.parameter < 0) {
      const Eigen::Vector3d e = f.motion == Motion::Rx ? Eigen::Vector3d::UnitX()
                                : f.motion == Motion::Ry ? Eigen::Vector3d::UnitY()
                                                         : Eigen::Vector3d::UnitZ();
      lines.push_back({f.axis, F.translation(), F.linear() * e, f.sign});
      continue;
    }
    F = F * elementary(f.motion, f.sign * p[f.parameter]);
  }
  return lines;
}

double angleOf(char axis, const Pose& pose) { return axis == 'A' ? pose.A : (axis == 'B' ? pose.B : pose.C); }

class EveryConfiguration : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryConfiguration, EveryMotionIsARotationAboutTheLocatedAxisLine) {
  std::mt19937 rng(13);
  const KinematicModel m = model(GetParam());
  for (int trial = 0; trial < 30; ++trial) {
    // Large errors (0.5 mm, 1 deg) so that a sign or order slip cannot hide below first order.
    const Eigen::VectorXd p = randomErrors(m, rng, 0.5, degToRad(1.0));
    const Pose pose = randomPose(rng);
    for (const auto* side : {&m.table_chain, &m.head_chain}) {
      Eigen::Isometry3d poe = Eigen::Isometry3d::Identity();
      for (const Line& l : linesAtZero(*side, p)) poe = poe * aboutLine(l.q, l.w, l.sign * degToRad(angleOf(l.axis, pose)));
      const Eigen::Isometry3d T0 = side == &m.table_chain ? T_m_w(m, p, Pose{}) : T_c_t(m, p, Pose{});
      const Eigen::Isometry3d T = side == &m.table_chain ? T_m_w(m, p, pose) : T_c_t(m, p, pose);
      EXPECT_LT(((poe * T0).matrix() - T.matrix()).norm(), 1e-11) << GetParam() << " trial " << trial;
    }
  }
}

TEST_P(EveryConfiguration, AnalyticJacobianMatchesCentralDifferences) {
  std::mt19937 rng(14);
  const KinematicModel m = model(GetParam());
  constexpr double h = 1e-6;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::VectorXd p = trial == 0 ? Eigen::VectorXd::Zero(m.size()) : randomErrors(m, rng, 0.05, 1e-3);
    const Pose pose = randomPose(rng);
    const auto J = J_X_p(m, p, pose);
    for (int i = 0; i < m.size(); ++i) {
      Eigen::VectorXd hi = p, lo = p;
      hi[i] += h;
      lo[i] -= h;
      const Eigen::Vector3d fd = (sphereCentreInAxes(m, hi, pose) - sphereCentreInAxes(m, lo, pose)) / (2 * h);
      // truncation ~h^2 |X| ~ 3e-10 mm; rounding ~1e-16 x 400 mm / 1e-6 ~ 4e-8 mm
      EXPECT_LT((J.col(i) - fd).norm(), 1e-6) << GetParam() << " " << m.parameters[i].name;
    }
  }
}

// A pose set exercising every rotary axis alone and combined.
std::vector<Pose> poseSet(const KinematicModel& m) {
  std::vector<Pose> poses;
  const std::vector<double> tilts = {-90, -45, 0, 30, 60};
  const std::vector<double> turns = {0, 60, 120, 180, 240, 300};
  const bool two_tilts = m.name == "head_ab";
  for (double t : tilts)
    for (double c : (two_tilts ? tilts : turns)) {
      Pose p;
      if (m.name == "table_ac") p = {t, 0, c};
      else if (m.name == "table_bc") p = {0, t, c};
      else if (m.name == "table_ab") p = {c, t, 0};  // the A table turns, the B axis tilts
      else if (m.name == "head_table") p = m.head_axes[0] == 'A' ? Pose{t, 0, c} : Pose{0, t, c};
      else if (m.name == "head_cb") p = {0, t, c};  // the B head tilts, the C head turns
      else p = {t, c, 0};
      poses.push_back(p);
    }
  return poses;
}

Eigen::MatrixXd stackedJacobian(const KinematicModel& m, const Eigen::VectorXd& p, const std::vector<Pose>& poses) {
  Eigen::MatrixXd J(3 * static_cast<Eigen::Index>(poses.size()), m.size());
  for (size_t k = 0; k < poses.size(); ++k) J.middleRows(3 * static_cast<Eigen::Index>(k), 3) = J_X_p(m, p, poses[k]);
  return J;
}

std::vector<IdentifiabilityParameter> names(const KinematicModel& m) {
  std::vector<IdentifiabilityParameter> out;
  for (const auto& q : m.parameters) out.push_back({q.name, q.kind});
  return out;
}

// The unseen directions in closed form (see each case), at nominal: J v = 0 to rounding, and the
// rank is the parameter count less their number.
struct Unseen {
  std::string configuration;
  char head;
  int count;  // independent unseen directions
  std::vector<std::vector<std::pair<const char*, double>>> directions;
};

class ClosedFormUnseen : public ::testing::TestWithParam<Unseen> {};

TEST_P(ClosedFormUnseen, RankAndUnseenDirectionsAreTheClosedForm) {
  const Unseen& c = GetParam();
  const KinematicModel m = model(c.configuration, c.head);
  const Eigen::MatrixXd J = stackedJacobian(m, Eigen::VectorXd::Zero(m.size()), poseSet(m));
  const Identifiability id = identifiability(J, names(m));
  EXPECT_EQ(id.rank, m.size() - c.count) << c.configuration;
  EXPECT_EQ(static_cast<int>(id.combinations.size()), c.count);
  for (const auto& d : c.directions) {
    const Eigen::VectorXd v = at(m, d);
    EXPECT_LT((J * v).norm(), 1e-12 * v.norm() * J.norm()) << c.configuration << " " << d.front().first;
  }
  for (const auto& comb : id.combinations) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(m.size());
    for (const auto& [j, r] : comb.terms)
      v[j] = m.parameters[j].kind == ParamKind::Length ? umToMm(r) : mdegToRad(r);
    EXPECT_LT((J * v).norm(), 1e-9 * v.norm() * J.norm()) << comb.text;
  }
}

// C0C turns the set-up about the C axis: the sphere moves by C0C ez x p_S, undone by
// d_S = C0C (p_y, -p_x, 0). A head's zero turns the ball about the head axis: undone by the ball's
// offsets. A constant translation of the whole table side and the whole head side reads nothing.
// The zero of an inner axis commutes with its motion: the outer axis's tilt about the same
// direction (A0C, B0C, A0B) does the same.
const double px = kSphere.x(), py = kSphere.y(), pz = kSphere.z();
INSTANTIATE_TEST_SUITE_P(
    KinematicModel, ClosedFormUnseen,
    ::testing::Values(
        // A0A commutes with the A motion: at nominal it is a tilt of the C axis about X (A0C).
        Unseen{"table_ac", 'B', 2, {{{"C0C", 1.0}, {"dX_S", py}, {"dY_S", -px}}, {{"A0A", 1.0}, {"A0C", -1.0}}}},
        // B0B likewise: a tilt of the C axis about Y (B0C).
        Unseen{"table_bc", 'B', 2, {{{"C0C", 1.0}, {"dX_S", py}, {"dY_S", -px}}, {{"B0B", 1.0}, {"B0C", -1.0}}}},
        // A0A turns the set-up about the A table's axis X: the sphere moves by A0A ex x p_S, undone
        // by d_S = A0A (0, p_z, -p_y); B0A, at nominal right after B's motion, is B0B.
        Unseen{"table_ab", 'B', 2, {{{"A0A", 1.0}, {"dY_S", pz}, {"dZ_S", -py}}, {{"B0B", 1.0}, {"B0A", -1.0}}}},
        // B0B turns the ball about B: dX_T = -L B0B undoes it (the ball at -L moves by B0B x).
        Unseen{"head_table", 'B', 5,
               {{{"C0C", 1.0}, {"dX_S", py}, {"dY_S", -px}},
                {{"X0C", 1.0}, {"X0B", 1.0}},
                {{"Y0C", 1.0}, {"dY_T", 1.0}},
                {{"dZ_S", 1.0}, {"Z0B", 1.0}},
                {{"B0B", 1.0}, {"dX_T", kPivotToBall}}}},
        Unseen{"head_table", 'A', 5,
               {{{"C0C", 1.0}, {"dX_S", py}, {"dY_S", -px}},
                {{"X0C", 1.0}, {"dX_T", 1.0}},
                {{"Y0C", 1.0}, {"Y0A", 1.0}},
                {{"dZ_S", 1.0}, {"Z0A", 1.0}},
                {{"A0A", 1.0}, {"dY_T", -kPivotToBall}}}},
        Unseen{"head_ab", 'B', 5,
               {{{"dX_S", 1.0}, {"X0B", 1.0}},
                {{"dY_S", 1.0}, {"Y0A", 1.0}},
                {{"dZ_S", 1.0}, {"Z0A", 1.0}},
                {{"B0B", 1.0}, {"dX_T", kPivotToBall}},
                {{"A0A", 1.0}, {"A0B", -1.0}}}},
        // The C head carrying the B head: the head's place reads as the sphere's (X0C Y0C, and Z0B
        // along the C axis); C0C commutes with the C motion and, at nominal (X0B = 0), is the B
        // axis's tilt about Z (C0B).
        Unseen{"head_cb", 'B', 5,
               {{{"dX_S", 1.0}, {"X0C", 1.0}},
                {{"dY_S", 1.0}, {"Y0C", 1.0}},
                {{"dZ_S", 1.0}, {"Z0B", 1.0}},
                {{"B0B", 1.0}, {"dX_T", kPivotToBall}},
                {{"C0C", 1.0}, {"C0B", -1.0}}}}),
    [](const auto& info) { return info.param.configuration + "_" + std::string(1, info.param.head); });

// Noise-free readings at the pose set, fitted from nominal by the shared engine: the fitted model
// reads every pose (fitted or not) as the truth does to 1e-6 um, and the estimate differs from
// the truth only along the unseen directions: each separable parameter to 1e-6 um / 1e-7 mdeg.
TEST_P(EveryConfiguration, NoiseFreeReadingsRecoverEveryIdentifiableCombination) {
  std::mt19937 rng(15);
  const KinematicModel m = model(GetParam());
  const std::vector<Pose> poses = poseSet(m);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd truth = randomErrors(m, rng, 0.05, degToRad(0.05));
    Eigen::VectorXd y(3 * static_cast<Eigen::Index>(poses.size()));
    for (size_t k = 0; k < poses.size(); ++k)
      y.segment<3>(3 * static_cast<Eigen::Index>(k)) = sphereCentreInAxes(m, truth, poses[k]);
    const auto f = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
      r.resize(y.size());
      for (size_t k = 0; k < poses.size(); ++k)
        r.segment<3>(3 * static_cast<Eigen::Index>(k)) = sphereCentreInAxes(m, p, poses[k]) - y.segment<3>(3 * static_cast<Eigen::Index>(k));
      if (J) *J = stackedJacobian(m, p, poses);
    };
    const LeastSquaresResult fit = solveLeastSquares(f, Eigen::VectorXd::Zero(m.size()));
    ASSERT_TRUE(fit.summary.usable()) << fit.summary.briefReport();
    std::mt19937 held_out(100 + trial);
    for (int k = 0; k < 20; ++k) {
      const Pose pose = randomPose(held_out);
      EXPECT_LT(mmToUm((sphereCentreInAxes(m, fit.x, pose) - sphereCentreInAxes(m, truth, pose)).norm()), 1e-6)
          << GetParam();
    }
    const Identifiability id = identifiability(stackedJacobian(m, fit.x, poses), names(m));
    for (int i = 0; i < m.size(); ++i) {
      if (!id.separable[i]) continue;
      const bool len = m.parameters[i].kind == ParamKind::Length;
      const double err = len ? mmToUm(fit.x[i] - truth[i]) : radToMdeg(fit.x[i] - truth[i]);
      EXPECT_LT(std::abs(err), len ? 1e-6 : 1e-7) << GetParam() << " " << m.parameters[i].name;
    }
  }
}

// The identifiability's u (the pose design's figure in um and mdeg for the declared noise)
// against a Monte Carlo of the fit it describes: sphere centres read with sd 0.5 um in X and Y
// (two opposite touches each) and 0.7 um in Z (the top touch), 400 noisy sets fitted by the
// engine with the held parameters fixed, as the u describes (fitting them too would chase
// directions the model sees only at second order, through the noise). Each separable
// parameter's scatter matches u within 15 % (the sd of a 400-sample sd is 3.5 %).
TEST_P(EveryConfiguration, IdentifiabilityUMatchesAMonteCarloOfTheFit) {
  const KinematicModel m = model(GetParam());
  const std::vector<Pose> poses = poseSet(m);
  const Eigen::Vector3d sd_mm(umToMm(0.5), umToMm(0.5), umToMm(0.7));
  const Eigen::Index n_obs = 3 * static_cast<Eigen::Index>(poses.size());
  Eigen::VectorXd w(n_obs);  // whitening: 1 / sd per reading
  for (Eigen::Index k = 0; k < n_obs; ++k) w[k] = 1.0 / sd_mm[k % 3];
  const Eigen::VectorXd truth = Eigen::VectorXd::Zero(m.size());
  const Identifiability id = identifiability(w.asDiagonal() * stackedJacobian(m, truth, poses), names(m));
  std::vector<Eigen::Index> free;
  for (int i = 0; i < m.size(); ++i)
    if (!id.held[static_cast<size_t>(i)]) free.push_back(i);
  const auto nf = static_cast<Eigen::Index>(free.size());
  const auto expand = [&](const Eigen::VectorXd& z) -> Eigen::VectorXd {
    Eigen::VectorXd p = truth;
    for (Eigen::Index k = 0; k < nf; ++k) p[free[static_cast<size_t>(k)]] = z[k];
    return p;
  };
  std::mt19937 rng(21);
  std::normal_distribution<double> g(0.0, 1.0);
  constexpr int kTrials = 400;
  Eigen::MatrixXd est(m.size(), kTrials);
  for (int t = 0; t < kTrials; ++t) {
    Eigen::VectorXd y(n_obs);
    for (size_t k = 0; k < poses.size(); ++k)
      y.segment<3>(3 * static_cast<Eigen::Index>(k)) = sphereCentreInAxes(m, truth, poses[k]);
    for (Eigen::Index k = 0; k < n_obs; ++k) y[k] += g(rng) / w[k];
    const auto f = [&](const Eigen::VectorXd& z, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
      const Eigen::VectorXd p = expand(z);
      r.resize(n_obs);
      for (size_t k = 0; k < poses.size(); ++k)
        r.segment<3>(3 * static_cast<Eigen::Index>(k)) = sphereCentreInAxes(m, p, poses[k]);
      r = w.asDiagonal() * (r - y);
      if (J) {
        const Eigen::MatrixXd Jfull = w.asDiagonal() * stackedJacobian(m, p, poses);
        J->resize(n_obs, nf);
        for (Eigen::Index k = 0; k < nf; ++k) J->col(k) = Jfull.col(free[static_cast<size_t>(k)]);
      }
    };
    const LeastSquaresResult fit = solveLeastSquares(f, Eigen::VectorXd::Zero(nf));
    ASSERT_TRUE(fit.summary.usable()) << fit.summary.briefReport();
    est.col(t) = expand(fit.x);
  }
  int checked = 0;
  for (int i = 0; i < m.size(); ++i) {
    if (!id.separable[i]) continue;
    const double f = m.parameters[i].kind == ParamKind::Length ? mmToUm(1.0) : radToMdeg(1.0);
    const double sd = f * std::sqrt((est.row(i).array() - est.row(i).mean()).square().sum() / (kTrials - 1));
    EXPECT_NEAR(sd / id.u_report[i], 1.0, 0.15) << GetParam() << " " << m.parameters[i].name << ": Monte Carlo " << sd
                                                << ", u " << id.u_report[i];
    std::printf("%s %s: Monte Carlo sd / u = %.3f\n", GetParam().c_str(), m.parameters[i].name.c_str(), sd / id.u_report[i]);
    ++checked;
  }
  EXPECT_GE(checked, 4) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(KinematicModel, EveryConfiguration, ::testing::ValuesIn(kinematicConfigurations()));

TEST(KinematicModel, UnknownConfigurationsAndHeadsAreRefusedByName) {
  EXPECT_THROW(kinematicModel("table_xy", kSphere), std::invalid_argument);
  EXPECT_THROW(kinematicModel("head_table", kSphere, kPivotToBall, 'C'), std::invalid_argument);
  EXPECT_THROW(kinematicModel("head_ab", kSphere, 0.0), std::invalid_argument);
  EXPECT_THROW(kinematicModel("head_cb", kSphere, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace rotacal
