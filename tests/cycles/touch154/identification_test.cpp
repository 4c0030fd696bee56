// Identification by recovery: simulate the exact machine with known errors, identify them back.
#include <gtest/gtest.h>

#include <cmath>

#include "cycles/touch154/identification.hpp"
#include "cycles/touch154/closed_form.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

IdentificationResult run(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, Method m) {
  IdentificationOptions o;
  o.method = m;
  return identifyTouch154(plan, runs, o);
}

void expectRecovered(const IdentificationResult& r, const LocationErrors& truth, double tol_um, double tol_mdeg,
                     const std::string& what) {
  ASSERT_EQ(r.summary.termination, Termination::Converged) << what << ": " << r.summary.message;
  const auto& params = locationParameters(truth.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double tol = params[i].kind == ParamKind::Length ? tol_um : tol_mdeg;
    EXPECT_NEAR(r.estimate.reportValue(i), truth.reportValue(i), tol) << what << ": " << params[i].name;
  }
}

Truth roughPiece() {
  // Issue 2: 0.5 mm / 2 mrad setup error and a non-square piece (sides 20 um out of square over
  // 100 mm, top tilted 2 mrad).
  Truth t = test::truthWith(test::table4Mean());
  t.artefact.setup.translation_mm = Eigen::Vector3d(0.5, -0.5, 0.2);
  t.artefact.setup.rotation_rad = Eigen::Vector3d(0.0, 0.0, 0.002);
  t.artefact.form[static_cast<size_t>(Face::PosX)].tilt_v_rad = 0.0;
  t.artefact.form[static_cast<size_t>(Face::PosY)].tilt_v_rad = 0.0;
  // Out of square: +X face turned 0.2 mrad about the vertical, -Y face -0.2 mrad.
  t.artefact.form[static_cast<size_t>(Face::PosX)] = FaceForm{0.0, 0.0, 0.0002};
  t.artefact.form[static_cast<size_t>(Face::NegY)] = FaceForm{0.0, 0.0, -0.0002};
  t.artefact.form[static_cast<size_t>(Face::Top)] = FaceForm{0.0, 0.002, 0.0};
  return t;
}

TEST(LeastSquares, RecoversTable4ExactlyWithoutNoise) {
  const ProbePlan plan = test::touch154Plan();
  const LocationErrors truth = test::table4Mean();
  const auto data = simulate(plan, test::truthWith(truth), {});
  // The model is the exact simulator: Gauss-Newton converges to rounding (1e-6 um, 1e-7 mdeg).
  expectRecovered(run(plan, {data}, Method::LeastSquaresRigidSetup), truth, 1e-6, 1e-7, "rigid setup");
  expectRecovered(run(plan, {data}, Method::LeastSquaresPerPoint), truth, 1e-6, 1e-7, "per point");
}

TEST(LeastSquares, FormImmuneVariantIgnoresSetupAndFormErrors) {
  const ProbePlan plan = test::touch154Plan();
  const Truth t = roughPiece();
  const auto data = simulate(plan, t, {});
  expectRecovered(run(plan, {data}, Method::LeastSquaresPerPoint), t.errors, 0.1, 0.01, "per point");
}

TEST(LeastSquares, RigidSetupModelIsExactForARigidlyMisplacedSquarePiece) {
  const ProbePlan plan = test::touch154Plan();
  Truth t = test::truthWith(test::table4Mean());
  t.artefact.setup.translation_mm = Eigen::Vector3d(0.5, -0.5, 0.2);
  t.artefact.setup.rotation_rad = Eigen::Vector3d(0.002, -0.001, 0.002);
  expectRecovered(run(plan, {simulate(plan, t, {})}, Method::LeastSquaresRigidSetup), t.errors, 1e-6, 1e-7, "rigid");
}

TEST(ClosedForm, SecondOrderBiasWithARoughPieceIsSmallAndMeasured) {
  // The closed form is first order: the relative displacements of Eq. (21) cancel the piece's
  // setup and form only to first order. What remains is (face tilt) x (in-plane motion caused by
  // the location errors), e.g. 2 mrad x 30 um = 0.06 um, and, for the angles, that divided by
  // Pattern 4's short lever arm. Measured here and documented in docs/identification.md.
  const ProbePlan plan = test::touch154Plan();
  const Truth t = roughPiece();
  const auto r = run(plan, {simulate(plan, t, {})}, Method::ClosedForm);
  ASSERT_EQ(r.summary.termination, Termination::Converged);
  double worst_um = 0, worst_mdeg = 0;
  const auto& params = locationParameters(Kinematics::TableAC);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double d = std::abs(r.estimate.reportValue(i) - t.errors.reportValue(i));
    (params[i].kind == ParamKind::Length ? worst_um : worst_mdeg) = std::max(
        params[i].kind == ParamKind::Length ? worst_um : worst_mdeg, d);
  }
  std::printf("closed-form bias with the rough piece: %.4f um, %.5f mdeg\n", worst_um, worst_mdeg);
  RecordProperty("closed_form_bias_um", std::to_string(worst_um));
  RecordProperty("closed_form_bias_mdeg", std::to_string(worst_mdeg));
  // The bias is second order: far below the first-order effects (tens of um) and the noise (0.7 um).
  EXPECT_LT(worst_um, 0.5);
  EXPECT_LT(worst_mdeg, 0.05);
  // ... and it vanishes with the piece's errors: the same bound with a perfect piece is 0.05/0.005.
  const auto clean = run(plan, {simulate(plan, test::truthWith(t.errors), {})}, Method::ClosedForm);
  for (int i = 0; i < kNumLocationErrors; ++i)
    EXPECT_NEAR(clean.estimate.reportValue(i), t.errors.reportValue(i), params[i].kind == ParamKind::Length ? 0.05 : 0.005);
}

TEST(LeastSquares, ReportedUncertaintyMatchesTheSpreadOver200Seeds) {
  const ProbePlan plan = test::touch154Plan();
  Truth t = test::truthWith(test::table4Mean());
  t.noise_um = 0.7;
  constexpr int kSeeds = 200;
  for (Method m : {Method::LeastSquaresPerPoint, Method::ClosedForm}) {
    ErrorVector sum = ErrorVector::Zero(), sum2 = ErrorVector::Zero(), usum = ErrorVector::Zero();
    for (int s = 0; s < kSeeds; ++s) {
      const auto r = run(plan, {simulate(plan, t, {static_cast<std::uint64_t>(1000 + s)})}, m);
      ASSERT_EQ(r.summary.termination, Termination::Converged);
      const ErrorVector d = r.estimate.values - t.errors.values;
      sum += d;
      sum2 += d.cwiseAbs2();
      usum += r.u;
    }
    const ErrorVector mean = sum / kSeeds;
    const ErrorVector sd = (sum2 / kSeeds - mean.cwiseAbs2()).cwiseSqrt() * std::sqrt(kSeeds / (kSeeds - 1.0));
    const ErrorVector u = usum / kSeeds;
    for (int i = 0; i < kNumLocationErrors; ++i) {
      // Issue 2: within 20 %. The sample sd of 200 normal draws itself scatters by 5 % (k = 1).
      EXPECT_NEAR(sd[i] / u[i], 1.0, 0.20) << methodName(m) << " " << locationParameters(Kinematics::TableAC)[i].name
                                            << ": spread " << sd[i] << " vs reported " << u[i];
      // Unbiased: the mean error is within 4 standard errors of zero.
      EXPECT_LT(std::abs(mean[i]), 4 * u[i] / std::sqrt(kSeeds)) << locationParameters(Kinematics::TableAC)[i].name;
    }
  }
}

TEST(LeastSquares, RefusesParametersThePlanCannotIdentify) {
  ProbePlan plan = test::touch154Plan();
  std::vector<ProbePoint> a0;
  for (const auto& p : plan.points)
    if (p.pose.A == 0.0) a0.push_back(p);
  for (size_t i = 0; i < a0.size(); ++i) a0[i].id = static_cast<int>(i + 1);
  plan.points = a0;
  const auto data = simulate(plan, test::truthWith(test::table4Mean()), {});
  const auto r = run(plan, {data}, Method::LeastSquaresPerPoint);
  EXPECT_EQ(r.summary.termination, Termination::RankDeficient);
  // With A fixed at 0 the A-axis height dz_AY and the split dy_AY / dy_CA are invisible.
  const auto has = [&](const char* n) { return std::find(r.unidentifiable.begin(), r.unidentifiable.end(), n) != r.unidentifiable.end(); };
  EXPECT_TRUE(has("dz_AY")) << r.summary.message;
  EXPECT_TRUE(has("dy_AY")) << r.summary.message;
  EXPECT_TRUE(has("dy_CA")) << r.summary.message;
  EXPECT_NE(r.summary.message.find("dz_AY"), std::string::npos);
}

TEST(LeastSquares, RepeatsShareTheTestPiece) {
  const ProbePlan plan = test::touch154Plan();
  Truth t = roughPiece();
  t.noise_um = 0.7;
  std::vector<MeasurementRun> runs;
  for (int s = 0; s < 4; ++s) runs.push_back(simulate(plan, t, {static_cast<std::uint64_t>(s + 1)}));
  const auto one = run(plan, {runs[0]}, Method::LeastSquaresPerPoint);
  const auto four = run(plan, runs, Method::LeastSquaresPerPoint);
  ASSERT_EQ(four.summary.termination, Termination::Converged);
  EXPECT_EQ(four.summary.observations, 4 * 154);
  // Four repeats: the uncertainty drops by about 2 (sqrt 4); allow 1.6 .. 2.5 for dof effects.
  for (int i = 0; i < kNumLocationErrors; ++i) {
    EXPECT_GT(one.u[i] / four.u[i], 1.6);
    EXPECT_LT(one.u[i] / four.u[i], 2.5);
  }
}

}  // namespace
}  // namespace rotacal
