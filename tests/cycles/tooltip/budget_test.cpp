// What the tooltip cycle signs (issue 17, cycles/tooltip/budget.hpp): u_B of one contributor
// against its linear propagation through the fit's Jacobian (computed without the simulator, the
// draws or the Gauss-Newton), u_A measuring a known reading noise (and not the systematic residual
// the linear axes leave), the transverse-only case, none declared, the bundled 004 contributors.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>

#include "core/contributors.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/tooltip/analyze.hpp"
#include "cycles/tooltip/budget.hpp"
#include "cycles/tooltip/plan.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

MachineModel headMachine() { return loadMachine(test::sourcePath("examples/machines/head_ab.json")); }

ProbePlan plan004(const std::string& end = "90") {
  return makePlan("tooltip", headMachine(), {{"units", "inch"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", end}});
}

/// A head of 004's size: dR = 40 um, e = 3 + 5 A/90 - 2 sin A + 1.5 sin 2A mdeg (docs/tooltip.md).
TooltipHead head004(const ProbePlan& plan) {
  TooltipHead h;
  for (const auto& p : plan.points)
    if (h.angles_deg.empty() || std::abs(p.pose.A - h.angles_deg.back()) > 1e-9) h.angles_deg.push_back(p.pose.A);
  for (double a : h.angles_deg) {
    const double r = degToRad(a);
    h.e_mdeg.push_back(3.0 + 5.0 * a / 90.0 - 2.0 * std::sin(r) + 1.5 * std::sin(2 * r));
  }
  h.dR_um = 40.0;
  return h;
}

ContributorSet oneContributor(const std::string& id, double u_internal) {
  ContributorSet cs;
  cs.file = "test";
  Contributor c;
  c.info = findContributor(id);
  EXPECT_NE(c.info, nullptr) << id;
  c.u = Eigen::Vector3d(u_internal, 0, 0);
  cs.items.push_back(c);
  return cs;
}

int indexOf(const UncertaintyBudget& b, const std::string& name) {
  for (int i = 0; i < b.size(); ++i)
    if (b.names[static_cast<size_t>(i)] == name) return i;
  return -1;
}

/// (J^T J)^-1 J^T of the joint model at x, over all its columns (e per angle, dR): the fit's
/// linear map from reading changes (um) to parameter changes (rad, mm).
Eigen::MatrixXd linearMap(const ProbePlan& plan, const TooltipRun& run, const TooltipHead& h) {
  Eigen::VectorXd x(static_cast<int>(h.e_mdeg.size()) + 1);
  for (size_t j = 0; j < h.e_mdeg.size(); ++j) x[static_cast<int>(j)] = mdegToRad(h.e_mdeg[j]);
  x[x.size() - 1] = umToMm(h.dR_um);
  const Eigen::MatrixXd J = evaluateTooltipModel(plan, {run}, x).J_model_x;
  return (J.transpose() * J).ldlt().solve(J.transpose());
}

TEST(TooltipBudget, ScaleOfZAgainstItsLinearPropagation) {
  const ProbePlan plan = plan004();
  const TooltipHead h = head004(plan);
  const TooltipRun run = simulateTooltipHead(plan, h, TooltipDraw{}, true, 0.0, nullptr);
  const TooltipAnalysis a = analyzeTooltip(plan, {run});
  const double u_s = 20e-6;  // E_zz_lin 20 um/m
  const ContributorSet cs = oneContributor("E_zz_lin", u_s);
  TooltipBudgetOptions o;
  o.runs = 8000;
  o.alone_runs = 0;
  const UncertaintyBudget b = tooltipBudget(plan, {run}, a, 0.254, &cs, o);
  ASSERT_TRUE(b.type_b_evaluated);
  // A Z scale s moves the pivot by s Zp: reading k's dz changes by s (Zp_k - Zp_ref) (in um),
  // its transverse reading not at all; the fit maps that through (J^T J)^-1 J^T.
  const std::vector<int> refs = tooltipReferences(plan);
  Eigen::VectorXd dy = Eigen::VectorXd::Zero(2 * static_cast<int>(plan.points.size() - 1));
  int i = 0;
  for (size_t k = 0; k < plan.points.size(); ++k) {
    if (refs[k] == static_cast<int>(k)) continue;
    dy[2 * i + 1] = mmToUm(plan.points[k].trigger_m_mm.z() - plan.points[static_cast<size_t>(refs[k])].trigger_m_mm.z());
    ++i;
  }
  const Eigen::VectorXd dx = linearMap(plan, run, h) * dy;  // per unit s: rad, mm
  const Eigen::VectorXd ub = b.uB();
  const int iR = indexOf(b, "dR");
  ASSERT_GE(iR, 0);
  const double expect_dR = u_s * std::abs(mmToUm(dx[dx.size() - 1]));
  EXPECT_GT(expect_dR, 1.0);  // a test of something: the scale moves dR by um
  EXPECT_NEAR(ub[iR], expect_dR, 0.03 * expect_dR);
  for (size_t j = 0; j < h.angles_deg.size(); ++j) {
    const int ie = indexOf(b, fmt::format("e_A{:g}", h.angles_deg[j]));
    ASSERT_GE(ie, 0);
    const double expect = u_s * std::abs(radToMdeg(dx[static_cast<int>(j)]));
    EXPECT_NEAR(ub[ie], expect, 0.03 * expect + 1e-6) << h.angles_deg[j];
  }
}

TEST(TooltipBudget, TypeAMeasuresAKnownReadingNoise) {
  const ProbePlan plan = plan004();
  const TooltipHead h = head004(plan);
  const TooltipRun clean = simulateTooltipHead(plan, h, TooltipDraw{}, true, 0.0, nullptr);
  const Eigen::MatrixXd G = linearMap(plan, clean, h);
  const double noise = 2.0;
  // What 2 um per reading component gives dR through the fit: noise |G_dR| from each reading's
  // own, and from the laser's zero (one sweep: one zero per direction, read less by every value
  // of that direction, the transverse ones even and Z odd): noise |sum of G_dR over them|.
  const Eigen::VectorXd g = G.row(G.rows() - 1).transpose();
  double zero_t = 0.0, zero_z = 0.0;
  for (Eigen::Index i = 0; i < g.size(); ++i) (i % 2 == 0 ? zero_t : zero_z) += g[i];
  const double expect_dR = noise * mmToUm(std::sqrt(g.squaredNorm() + zero_t * zero_t + zero_z * zero_z));
  std::printf("u_A(dR) per um of reading noise: %.3f um from the readings, %.3f um with the zero\n", mmToUm(g.norm()),
              expect_dR / noise);
  // The linear axes' random errors (4 um nodes) are in the data and declared, as is the 2 um
  // reading noise: the residual carries the axes, u_A must not (they are u_B's).
  ContributorSet cs = oneContributor("E_zz_rand", umToMm(4.0));
  cs.items.push_back(oneContributor("E_yy_rand", umToMm(4.0)).items.front());
  TooltipBudgetOptions o;
  o.runs = 100;
  o.alone_runs = 0;
  double ua2 = 0, ua2_none = 0, raw2 = 0;
  const int datasets = 40;
  for (int m = 0; m < datasets; ++m) {
    TooltipDraw d;
    drawTooltip(plan, cs, 99, m, -1, &d);
    Rng rng(5, static_cast<std::uint64_t>(m));
    const TooltipRun run = simulateTooltipHead(plan, h, d, true, noise, &rng);
    const TooltipAnalysis a = analyzeTooltip(plan, {run});
    const UncertaintyBudget b = tooltipBudget(plan, {run}, a, noise, &cs, o);
    const double u = b.uA()[indexOf(b, "dR")];
    ua2 += u * u;
    raw2 += a.joint.u_dR_um * a.joint.u_dR_um;
    // Noise alone, none declared (the plan's 0.254 um laser figure, far below): the residual
    // shows the excess, and u_A is its own scatter.
    Rng rng2(6, static_cast<std::uint64_t>(m));
    const TooltipRun run2 = simulateTooltipHead(plan, h, TooltipDraw{}, true, noise, &rng2);
    const TooltipAnalysis a2 = analyzeTooltip(plan, {run2});
    const UncertaintyBudget b2 = tooltipBudget(plan, {run2}, a2, 0.254, nullptr, o);
    const double u2 = b2.uA()[indexOf(b2, "dR")];
    ua2_none += u2 * u2;
  }
  std::printf("u_A(dR) rms: %.3f um (noise alone), %.3f um (with the linear axes), the data's u %.3f um; expected %.3f um\n",
              std::sqrt(ua2_none / datasets), std::sqrt(ua2 / datasets), std::sqrt(raw2 / datasets), expect_dR);
  EXPECT_NEAR(std::sqrt(ua2_none / datasets), expect_dR, 0.1 * expect_dR);
  EXPECT_NEAR(std::sqrt(ua2 / datasets), expect_dR, 0.2 * expect_dR);
  // The data's own u (contract.md) carries the linear axes too: well above the reading noise's
  // (its own and its zero's, as the fit's map now counts them).
  EXPECT_GT(std::sqrt(raw2 / datasets), 1.4 * expect_dR);
}

TEST(TooltipBudget, RepeatsThatScatterRaiseTypeA) {
  const ProbePlan plan = plan004();
  TooltipHead h = head004(plan);
  std::vector<TooltipRun> runs;
  for (int r = 0; r < 3; ++r) {
    h.dR_um = 40.0 + 10.0 * r;  // the set-up moved between repeats: 10 um steps of dR
    Rng rng(11, static_cast<std::uint64_t>(r));
    runs.push_back(simulateTooltipHead(plan, h, TooltipDraw{}, true, 0.5, &rng));
  }
  const TooltipAnalysis a = analyzeTooltip(plan, runs);
  TooltipBudgetOptions o;
  o.runs = 100;
  const UncertaintyBudget b = tooltipBudget(plan, runs, a, 0.254, nullptr, o);
  // The standard error of the three repeats' mean: sd 10 um / sqrt(3) = 5.8 um (plus noise). The
  // pooled fit's residual already carries the moved set-up, which the rule reads as per-reading
  // scatter, and each reading carries its laser zero's as well (on this plan about twice the
  // reading's own for dR: TypeAMeasuresAKnownReadingNoise), so u_A lands above the repeats'
  // standard error (7.3 um), not below it: at least 3/4 of it, at most 1.5 x.
  EXPECT_GE(b.uA()[indexOf(b, "dR")], 0.75 * 10.0 / std::sqrt(3.0));
  EXPECT_LE(b.uA()[indexOf(b, "dR")], 1.5 * 10.0 / std::sqrt(3.0));
  EXPECT_GT(b.uA()[indexOf(b, "dR")], 10.0 * b.uA()[indexOf(b, "e_A30")] / 1000.0);  // a set-up far beyond the noise
}

TEST(TooltipBudget, TransverseOnlyBudgetsTheAngularErrorsAlone) {
  const ProbePlan plan = plan004("60");
  const TooltipHead h = head004(plan);
  TooltipRun run = simulateTooltipHead(plan, h, TooltipDraw{}, false, 0.0, nullptr);
  ASSERT_FALSE(std::isfinite(run[3].z_um));
  const TooltipAnalysis a = analyzeTooltip(plan, {run});
  ASSERT_TRUE(a.transverse_only);
  const ContributorSet cs = oneContributor("E_yy_lin", 20e-6);
  TooltipBudgetOptions o;
  o.runs = 4000;
  o.alone_runs = 0;
  const UncertaintyBudget b = tooltipBudget(plan, {run}, a, 0.254, &cs, o);
  EXPECT_EQ(indexOf(b, "dR"), -1);    // not identifiable: not budgeted
  EXPECT_EQ(indexOf(b, "e_A0"), -1);  // the reference, fixed at 0
  ASSERT_EQ(b.size(), 12);            // 5 .. 60 deg
  // A Y scale s moves the pivot by s Yp = -s R sin A: dy = -s R sin A, read by 004's model as
  // e = dy / (R cos A) = -s tan A (rad): u_B = u_s tan A.
  const Eigen::VectorXd ub = b.uB();
  for (double ang : {30.0, 60.0}) {
    const double expect = radToMdeg(20e-6 * std::tan(degToRad(ang)));
    EXPECT_NEAR(ub[indexOf(b, fmt::format("e_A{:g}", ang))], expect, 0.05 * expect) << ang;
  }
}

TEST(TooltipBudget, NoneDeclaredLeavesTypeBAtZeroAndSaysSo) {
  const ProbePlan plan = plan004();
  const TooltipHead h = head004(plan);
  Rng rng(3, 0);
  const TooltipRun run = simulateTooltipHead(plan, h, TooltipDraw{}, true, 1.0, &rng);
  const TooltipAnalysis a = analyzeTooltip(plan, {run});
  const UncertaintyBudget b = tooltipBudget(plan, {run}, a, 0.254, nullptr, TooltipBudgetOptions{});
  EXPECT_FALSE(b.type_b_evaluated);
  EXPECT_EQ(b.uB().norm(), 0.0);
  EXPECT_GT(b.uA().minCoeff(), 0.0);
  EXPECT_NE(b.type_b_source.find("not evaluated"), std::string::npos);
  EXPECT_NE(budgetText(b, tooltipBudgetValues(a, b)).find("not evaluated"), std::string::npos);
}

TEST(TooltipBudget, The004ContributorsPutMachinePositioningFirst) {
  const MachineModel m = headMachine();
  ASSERT_TRUE(m.contributors.has_value());
  // 004 Sec. VII's figures in internal units (mm): 0.000010, 0.000025, 0.000070 in; the machine
  // positioning's 0.000500 in as node values 12.7 / sqrt(2) um.
  EXPECT_DOUBLE_EQ(m.contributors->find("laser_resolution")->u[0], 0.254e-3);
  EXPECT_DOUBLE_EQ(m.contributors->find("laser_sphere_form")->u[0], 0.635e-3);
  EXPECT_DOUBLE_EQ(m.contributors->find("laser_lateral_coupling")->u[0], 1.778e-3);
  EXPECT_NEAR(m.contributors->find("E_zz_rand")->u[0] * std::sqrt(2.0), 12.7e-3, 0.05e-3);
  EXPECT_DOUBLE_EQ(m.contributors->find("laser_alignment")->u[0], 2e-3);  // 2 mrad
  const ProbePlan plan = plan004();
  const TooltipHead h = head004(plan);
  Rng rng(3, 1);
  const TooltipRun run = simulateTooltipHead(plan, h, TooltipDraw{}, true, 1.9, &rng);
  const TooltipAnalysis a = analyzeTooltip(plan, {run});
  TooltipBudgetOptions o;
  o.runs = 500;
  o.alone_runs = 200;
  const UncertaintyBudget b = tooltipBudget(plan, {run}, a, 0.254, &*m.contributors, o);
  const int iR = indexOf(b, "dR");
  ASSERT_GE(iR, 0);
  // 004 Sec. VII: "the largest error is the machine positioning error": dR's largest term is a
  // positioning error of a linear axis carrying the pivot, far above the data's u.
  std::string largest;
  double best = 0;
  for (const auto& t : b.terms)
    if (t.u[iR] > best) best = t.u[iR], largest = t.contributor;
  EXPECT_TRUE(largest == "E_zz_rand" || largest == "E_yy_rand") << largest;
  EXPECT_GT(b.uB()[iR], 3.0 * b.uA()[iR]);
  // The per-reading terms of 004 are Type A: not in the Monte Carlo.
  for (const auto& t : b.terms)
    EXPECT_TRUE(t.contributor != "laser_resolution" && t.contributor != "laser_sphere_form" &&
                t.contributor != "laser_lateral_coupling")
        << t.contributor;
}

}  // namespace
}  // namespace rotacal
