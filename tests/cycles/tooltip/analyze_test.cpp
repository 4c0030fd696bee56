// The fixed-tool-tip cycle (004): plan geometry against 004's closed form, the exact simulator
// against closed forms, identification of known errors (noise-free and with noise), 004's
// formula and its blind spots. The diagnosis: diagnose_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <fmt/format.h>

#include "cycles/cycle.hpp"
#include "core/errors.hpp"
#include "cycles/tooltip/plan.hpp"
#include "cycles/tooltip/analyze.hpp"
#include "core/units.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

MachineModel headMachine() { return loadMachine(test::sourcePath("examples/machines/head_ab.json")); }

ProbePlan plan004(CycleOptions extra = {}) {
  CycleOptions o{{"units", "inch"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}};
  for (const auto& [k, v] : extra) o[k] = v;
  return makePlan("tooltip", headMachine(), o);
}

TooltipTruth truthOf(double dR_um, double offset, double slope, double s1, double s2, double noise = 0) {
  TooltipTruth t;
  t.dR_um = dR_um;
  t.offset_mdeg = offset;
  t.slope_mdeg_per_90deg = slope;
  t.sin_mdeg = s1;
  t.sin2_mdeg = s2;
  t.noise_um = noise;
  return t;
}

TEST(TooltipPlan, PivotFollows004SecV) {
  const ProbePlan plan = plan004();
  ASSERT_EQ(plan.points.size(), 19u);  // A = 0, 5, ..., 90
  const double r = 381.0;
  for (const auto& p : plan.points) {
    const double a = degToRad(p.pose.A);
    // 004 Sec. V: Yp = -R sin A, Zp = -R (1 - cos A); X does not move. 1e-9 mm: round-off.
    EXPECT_NEAR(p.trigger_m_mm.x(), 0.0, 1e-9);
    EXPECT_NEAR(p.trigger_m_mm.y(), -r * std::sin(a), 1e-9);
    EXPECT_NEAR(p.trigger_m_mm.z(), -r * (1 - std::cos(a)), 1e-9);
    // and the tip stays at (0, 0, -R)
    const Eigen::Vector3d tip = p.trigger_m_mm + tipOffset_m(a, 0.0, r);
    EXPECT_LT((tip - Eigen::Vector3d(0, 0, -r)).norm(), 1e-9);
  }
}

TEST(TooltipPlan, RejectsBadOptionsAndTableMachines) {
  EXPECT_THROW(plan004({{"step_deg", "7"}}), std::invalid_argument);  // 90 / 7 is not whole
  EXPECT_THROW(plan004({{"axis", "C"}}), std::invalid_argument);
  EXPECT_THROW(plan004({{"colour", "red"}}), std::invalid_argument);
  EXPECT_THROW(makePlan("tooltip", test::acMachine(), {}), std::invalid_argument);
}

TEST(TooltipPlan, DynamicTestOf004SecVI) {
  const ProbePlan plan = plan004({{"sweeps", "5"}, {"other_deg", "0,30,60"}, {"step_deg", "15"}});
  // per sweep: the zero pose + 5 x (6 up, 12 down, 6 back) steps; three B angles
  EXPECT_EQ(plan.points.size(), 3u * (1 + 5 * 24));
  double max_a = 0, min_a = 0;
  for (const auto& p : plan.points) {
    max_a = std::max(max_a, p.pose.A);
    min_a = std::min(min_a, p.pose.A);
    const Eigen::Vector3d tip = p.trigger_m_mm + tipOffset_m(degToRad(p.pose.A), degToRad(p.pose.B), 381.0);
    EXPECT_LT((tip - p.contact_w_mm).norm(), 1e-9);
  }
  EXPECT_EQ(max_a, 90.0);
  EXPECT_EQ(min_a, -90.0);
}

TEST(TooltipSimulate, PivotLengthErrorIsRadialClosedForm) {
  // With dR only, the tip moves along the tool: d(A) = dR (sin A, -cos A) - dR (0, -1) (zeroed at 0).
  const ProbePlan plan = plan004();
  const TooltipRun run = simulateTooltip(plan, truthOf(40.0, 0, 0, 0, 0), 1);
  for (const auto& r : run) {
    const double a = degToRad(r.angle_deg);
    EXPECT_NEAR(r.t_um, 40.0 * std::sin(a), 1e-6);  // um; 1e-6: double round-off of mm values
    EXPECT_NEAR(r.z_um, 40.0 * (1 - std::cos(a)), 1e-6);
  }
}

TEST(TooltipSimulate, AngularErrorIsTangentialClosedForm) {
  // e = 10 mdeg constant except that the zero reading carries it too: d = R (Rx(A+e) - Rx(A)) - same at 0.
  const ProbePlan plan = plan004();
  const TooltipRun run = simulateTooltip(plan, truthOf(0, 10.0, 0, 0, 0), 1);
  const double r = 381.0, e = mdegToRad(10.0);
  for (const auto& rd : run) {
    const double a = degToRad(rd.angle_deg);
    const double y = r * (std::sin(a + e) - std::sin(a)) - r * std::sin(e);
    const double z = -r * (std::cos(a + e) - std::cos(a)) + r * (std::cos(e) - 1);
    EXPECT_NEAR(rd.t_um, mmToUm(y), 1e-6);
    EXPECT_NEAR(rd.z_um, mmToUm(z), 1e-6);
  }
}

TEST(TooltipFit, JacobianMatchesFiniteDifferences) {
  for (const char* axis : {"A", "B"}) {
    const ProbePlan plan = plan004({{"axis", axis}, {"other_deg", "0,30"}});
    const std::vector<TooltipRun> runs = {simulateTooltip(plan, truthOf(20, 1, 2, 3, 4), 1)};
    Eigen::VectorXd x = Eigen::VectorXd::Zero(20);
    for (int j = 0; j < 19; ++j) x[j] = mdegToRad(5.0 * std::sin(j));
    x[19] = 0.03;  // mm
    const TooltipModelEval e = evaluateTooltipModel(plan, runs, x);
    ASSERT_EQ(e.angles, 19);
    for (int c = 0; c < 20; ++c) {
      const double h = c < 19 ? 1e-7 : 1e-5;  // rad, mm: central differences, truncation ~h^2
      Eigen::VectorXd xp = x, xm = x;
      xp[c] += h;
      xm[c] -= h;
      const Eigen::VectorXd fd =
          (evaluateTooltipModel(plan, runs, xp).model_um - evaluateTooltipModel(plan, runs, xm).model_um) / (2 * h);
      // um per rad ~ 4e5, um per mm ~ 1e3: relative 1e-6 of the column's size
      EXPECT_LT((fd - e.J_model_x.col(c)).cwiseAbs().maxCoeff(), 1e-6 * (1.0 + e.J_model_x.col(c).cwiseAbs().maxCoeff()))
          << axis << " column " << c;
    }
  }
}

TEST(TooltipFit, NoiseFreeRecoversPivotAndAngularErrorTo1e3) {
  for (char axis : {'A', 'B'}) {
    const ProbePlan plan = plan004({{"axis", std::string(1, axis)}});
    const TooltipTruth t = truthOf(-35.0, 4.0, 6.0, -3.0, 2.0);
    const TooltipRun run = simulateTooltip(plan, t, 1);
    const TooltipFit f = fitTooltip(plan, {run}, {});
    ASSERT_TRUE(f.converged);
    EXPECT_NEAR(f.dR_um, t.dR_um, 1e-3 * 35.0) << axis;
    for (size_t k = 0; k < f.angles_deg.size(); ++k)
      EXPECT_NEAR(f.e_mdeg[k], t.angularErrorMdeg(f.angles_deg[k]), 1e-3 * 10.0) << axis << " " << f.angles_deg[k];
    EXPECT_LT(f.residual_rms_um, 1e-6);  // exact model: the residual is round-off only
  }
}

TEST(TooltipFit, DynamicSweepsAtSeveralOtherAnglesRecoverTheErrors) {
  // 004 Sec. VI: A back and forth twice at B = 0 and 30 deg; every reading enters the fit.
  const ProbePlan plan = plan004({{"sweeps", "2"}, {"other_deg", "0,30"}, {"step_deg", "15"}});
  const TooltipTruth t = truthOf(45.0, -2.0, 4.0, 3.0, -1.0);
  const TooltipFit f = fitTooltip(plan, {simulateTooltip(plan, t, 1)}, {});
  ASSERT_TRUE(f.converged);
  EXPECT_EQ(f.angles_deg.front(), -90.0);
  EXPECT_NEAR(f.dR_um, 45.0, 1e-3 * 45.0);
  for (size_t k = 0; k < f.angles_deg.size(); ++k)
    EXPECT_NEAR(f.e_mdeg[k], t.angularErrorMdeg(f.angles_deg[k]), 1e-3 * 10.0) << f.angles_deg[k];
}

TEST(TooltipFit, WithNoiseWithinUncertainty) {
  int dR_outside = 0, e_outside = 0, e_total = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ProbePlan plan = plan004();
    const TooltipTruth t = truthOf(30.0, 2.0, -4.0, 3.0, 1.0, 2.0);
    const TooltipFit f = fitTooltip(plan, {simulateTooltip(plan, t, seed)}, {});
    // 3 u: 0.27 % of cases outside for a normal estimate; a loose bound on 20 seeds.
    if (std::abs(f.dR_um - t.dR_um) > 3 * f.u_dR_um) ++dR_outside;
    EXPECT_GT(f.u_dR_um, 0.0);
    for (size_t k = 0; k < f.angles_deg.size(); ++k, ++e_total)
      if (std::abs(f.e_mdeg[k] - t.angularErrorMdeg(f.angles_deg[k])) > 3 * f.u_e_mdeg[k]) ++e_outside;
  }
  EXPECT_LE(dR_outside, 1);
  EXPECT_LE(e_outside, e_total / 50);
}

TEST(TooltipFit, Formula004ReadsPivotLengthAsAngularErrorAndFailsAt90) {
  const ProbePlan plan = plan004();
  const TooltipRun run = simulateTooltip(plan, truthOf(40.0, 0, 0, 0, 0), 1);
  const auto da = angularError004Mdeg(plan, run);
  for (size_t k = 0; k < run.size(); ++k) {
    const double a = degToRad(run[k].angle_deg);
    if (run[k].angle_deg == 90.0) {
      EXPECT_TRUE(std::isnan(da[k]));
      continue;
    }
    // 004: dA = dy / (R cos A) = dR tan A / R although the axis has no angular error.
    EXPECT_NEAR(da[k], radToMdeg(umToMm(40.0) * std::tan(a) / 381.0), 1e-6);
  }
  const TooltipFit joint = fitTooltip(plan, {run}, {});
  for (double e : joint.e_mdeg) EXPECT_NEAR(e, 0.0, 1e-6);
}

TEST(TooltipFit, FSurvivalMatchesClosedForms) {
  // F(1, d2) is t^2: for d2 = 1 (Cauchy) P(|t| > x) = 1 - 2 atan(x) / pi.
  EXPECT_NEAR(fSurvival(4.0, 1, 1), 1 - 2 * std::atan(2.0) / kPi, 1e-10);
  // F(2, d2): survival = (1 + 2 f / d2)^(-d2/2).
  EXPECT_NEAR(fSurvival(3.0, 2, 10), std::pow(1 + 2 * 3.0 / 10, -5.0), 1e-10);
}

TEST(TooltipResults, RoundTripAndErrors) {
  const ProbePlan plan = plan004();
  const TooltipRun run = simulateTooltip(plan, truthOf(10, 1, 0, 0, 0, 0.5), 3);
  const std::string text = tooltipResultsText(plan, run);
  const std::vector<TooltipRun> back = parseTooltipResults(text, "r.csv", plan);
  ASSERT_EQ(back.size(), 1u);
  ASSERT_EQ(back[0].size(), run.size());
  for (size_t k = 0; k < run.size(); ++k) EXPECT_NEAR(back[0][k].t_um, run[k].t_um, 0.5e-4);
  try {
    parseTooltipResults("angle_deg,dy_um,dz_um\n0,0,0\n5,x,0\n", "bad.csv", plan);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3);
  }
  EXPECT_THROW(parseTooltipResults("angle_deg,dy_um,dz_um\n0,0,0\n", "short.csv", plan), InputError);
  EXPECT_THROW(parseTooltipResults("a,b\n", "hdr.csv", plan), InputError);
}

// The program repeats the plan (option repeats, 3 on a new static plan) and the laser's file holds
// the runs one after the other: read back run by run, each with its own draws and the same head;
// a part-run, a run too many and an angle out of place are refused at their line.
TEST(TooltipResults, ThePlansRunsAreReadFromOneFile) {
  const ProbePlan plan = makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")),
                                  {{"units", "mm"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}});
  ASSERT_EQ(plan.options.at("repeats"), "3");
  const TooltipTruth truth = truthOf(10, 1, 0, 0, 0, 0.5);
  const std::vector<TooltipRun> runs = simulateTooltipRepeats(plan, truth, 3, TooltipMachine{});
  ASSERT_EQ(runs.size(), 3u);
  // Run 0 is the single run of the same seed; the others differ by their draws alone.
  const TooltipRun one = simulateTooltip(plan, truth, 3);
  const TooltipRun clean = simulateTooltip(plan, truthOf(10, 1, 0, 0, 0, 0.0), 3);
  for (size_t k = 0; k < one.size(); ++k) EXPECT_EQ(runs[0][k].t_um, one[k].t_um);
  double diff = 0.0;
  for (size_t r = 1; r < 3; ++r)
    for (size_t k = 1; k < one.size(); ++k) diff = std::max(diff, std::abs(runs[r][k].t_um - runs[0][k].t_um));
  EXPECT_GT(diff, 0.1);
  // Without scatter every run reads the same head.
  const std::vector<TooltipRun> still = simulateTooltipRepeats(plan, truthOf(10, 1, 0, 0, 0, 0.0), 3, TooltipMachine{});
  for (size_t r = 0; r < 3; ++r)
    for (size_t k = 0; k < one.size(); ++k) EXPECT_EQ(still[r][k].z_um, clean[k].z_um);
  const std::string text = tooltipResultsText(plan, runs);
  const std::vector<TooltipRun> back = parseTooltipResults(text, "r.csv", plan);
  ASSERT_EQ(back.size(), 3u);
  for (size_t r = 0; r < 3; ++r)
    for (size_t k = 0; k < one.size(); ++k) EXPECT_NEAR(back[r][k].z_um, runs[r][k].z_um, 0.5e-4);
  // Fewer runs than planned are read as they are; a part of a run or a fourth one is refused.
  const std::vector<TooltipRun> two = parseTooltipResults(tooltipResultsText(plan, {runs[0], runs[1]}), "r.csv", plan);
  EXPECT_EQ(two.size(), 2u);
  const size_t n = one.size();
  auto lineOfError = [&](const std::string& t) {
    try {
      (void)parseTooltipResults(t, "r.csv", plan);
    } catch (const InputError& e) {
      return e.line();
    }
    return -1;
  };
  std::string part = tooltipResultsText(plan, {runs[0], runs[1]});
  part = part.substr(0, part.rfind("90.0000,"));  // run 2 without its last reading
  EXPECT_GT(lineOfError(part), 0);
  const std::string four = tooltipResultsText(plan, {runs[0], runs[1], runs[2], runs[0]});
  // Header, n rows, then "# run k" and n rows per run: the fourth run's first row.
  EXPECT_EQ(lineOfError(four), static_cast<int>(1 + n + 2 * (n + 1) + 2));
  std::string shifted = tooltipResultsText(plan, {runs[0], runs[1]});
  const size_t second = shifted.find("# run 2\n") + 8;
  shifted.erase(second, shifted.find('\n', second) + 1 - second);  // run 2 starts at 5 deg
  EXPECT_EQ(lineOfError(shifted), static_cast<int>(1 + n + 2));
}

// 004's laser reads one direction (issue 17): a results file of the transverse column alone is
// analyzed, and what it cannot identify is said, not guessed.
TEST(TooltipResults, TheTransverseReadingAloneGivesTheAngularErrorsAndSaysDRIsNotIdentified) {
  const ProbePlan plan = makePlan("tooltip", loadMachine(test::sourcePath("examples/machines/head_ab.json")),
                                  {{"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "60"}});
  TooltipTruth t;
  t.sin_mdeg = 2.0;  // e(A) = 2 mdeg sin A: no pivot-length error
  const TooltipRun full = simulateTooltip(plan, t, 1);
  std::string text = "angle_deg,dy_um\n";
  for (const auto& r : full) text += fmt::format("{:.4f},{:.4f}\n", r.angle_deg, r.t_um);
  const TooltipRun dy = parseTooltipResults(text, "dy.csv", plan).front();
  ASSERT_EQ(dy.size(), full.size());
  EXPECT_FALSE(std::isfinite(dy[3].z_um));
  const TooltipAnalysis a = analyzeTooltip(plan, {dy});
  EXPECT_TRUE(a.transverse_only);
  // The angular error at every angle, against the truth (closed form: 2 sin A mdeg, zeroed at 0).
  for (size_t k = 0; k < a.joint.angles_deg.size(); ++k)
    if (std::isfinite(a.joint.e_mdeg[k]) && std::abs(a.joint.angles_deg[k]) > 1e-9) {
      EXPECT_NEAR(a.joint.e_mdeg[k] - a.joint.e_mdeg[0], 2.0 * std::sin(degToRad(a.joint.angles_deg[k])), 1e-3)
          << a.joint.angles_deg[k];
    }
  const Json j = tooltipReportJson(plan, {dy}, a);
  EXPECT_TRUE(j["location_errors"].empty());
  EXPECT_NE(j["not_identified"]["dR"].get<std::string>().find("not identifiable"), std::string::npos);
  EXPECT_NE(tooltipReportText(plan, a).find("not identifiable"), std::string::npos);
  // A row with a third column under the one-direction header is refused at its line.
  EXPECT_THROW(parseTooltipResults("angle_deg,dy_um\n0,0,0\n", "bad.csv", plan), InputError);
}

// diagnose's causes differ only in how they split between the two directions: a file of one
// direction among several is refused naming that file (the runs of every file read in turn).
TEST(TooltipResults, DiagnoseRefusesAFileOfOneDirectionNamingIt) {
  const ProbePlan plan = plan004();
  const TooltipRun full = simulateTooltip(plan, truthOf(10, 1, 0, 0, 0, 0.5), 1);
  std::string dy = "angle_deg,dy_um\n";
  for (const auto& r : full) dy += fmt::format("{:.4f},{:.4f}\n", r.angle_deg, r.t_um);
  DiagnoseRequest r;
  r.plan = &plan;
  r.results = {{"both.csv", tooltipResultsText(plan, {full, full})}, {"dy.csv", dy}};
  try {
    (void)cycleByName("tooltip").diagnose(r);
    FAIL() << "a file of one direction was diagnosed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "dy.csv");
    EXPECT_NE(std::string(e.what()).find("both directions"), std::string::npos) << e.what();
  }
}

// At A = +-90 deg the tip moves along the beam: the transverse reading does not see the angle to
// first order (d(dy)/de = R cos A). The fit said -1.4e17 mdeg there; it must say "not
// identifiable" (NaN, null in REPORT.json) and keep the other angles right.
TEST(TooltipResults, TheTransverseReadingAloneCannotSeeTheAngleAt90Degrees) {
  const ProbePlan plan = plan004();  // 0 .. 90 deg in 5 deg steps, both ways
  TooltipTruth t;
  t.sin_mdeg = 2.0;
  const TooltipRun full = simulateTooltip(plan, t, 1);
  std::string text = "angle_deg,dy_um\n";
  for (const auto& r : full) text += fmt::format("{:.6f},{:.6f}\n", r.angle_deg, r.t_um);
  const TooltipAnalysis a = analyzeTooltip(plan, parseTooltipResults(text, "dy.csv", plan));
  int at90 = 0;
  for (size_t k = 0; k < a.joint.angles_deg.size(); ++k) {
    const double A = a.joint.angles_deg[k];
    if (std::abs(std::abs(A) - 90.0) < 1e-9) {
      EXPECT_FALSE(std::isfinite(a.joint.e_mdeg[k])) << a.joint.e_mdeg[k];
      EXPECT_FALSE(std::isfinite(a.joint.u_e_mdeg[k]));
      ++at90;
    } else if (std::abs(A) > 1e-9) {
      ASSERT_TRUE(std::isfinite(a.joint.e_mdeg[k])) << A;
      EXPECT_NEAR(a.joint.e_mdeg[k] - a.joint.e_mdeg[0], 2.0 * std::sin(degToRad(A)), 2e-3) << A;
    }
  }
  EXPECT_GE(at90, 1);
  const Json j = tooltipReportJson(plan, parseTooltipResults(text, "dy.csv", plan), a);
  EXPECT_NO_THROW((void)j.dump());
}

}  // namespace
}  // namespace rotacal
