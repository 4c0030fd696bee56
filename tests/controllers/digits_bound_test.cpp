// Issue 3's criterion, per dialect and per unit: generate -> simulate in the dialect's own
// results format -> parse -> identify gives the csv path's location errors within the bound
// that the dialect's printed digits allow, computed here, not assumed.
//
// The bound. Identification sees each trigger only through s_i = u_i . (p_i - p_nominal,i)
// (alongApproach, u_i = approach). A dialect prints each coordinate rounded to `decimals` in its
// unit, so every coordinate moves by at most h = 0.5 * 10^-decimals * unit_mm and s_i by at most
// e_i = h * |u_i|_1. To first order the estimate moves by G * ds, G = d(theta)/d(s) (8 x 154),
// so |d theta_k| <= sum_i |G_ki| e_i. G is computed by finite differences of the whole
// identification (an independent path from the estimate itself); the linearisation error is
// shown negligible by predicting the actual difference as G * ds_actual.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <string>

#include "controllers/dialect.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "dialect_battery.hpp"

namespace rotacal {
namespace {

struct Printed {
  const char* dialect;
  int decimals;       // of every printed coordinate, mm machine
  int inch_decimals;  // on an inch machine
  bool mm_only;       // prints mm on an inch machine too
};
// From the writers: LinuxCNC LOG %.6f; DPRNT [44] / inch [35]; SPRINT %10.4F / inch %10.5F;
// Heidenhain format file 4 decimals, always MM; Okuma PUT VCn,4 / inch VCn,5.
const Printed kPrinted[] = {{"linuxcnc", 6, 6, false}, {"fanuc", 4, 5, false},     {"haas", 4, 5, false},
                            {"siemens", 4, 5, false},  {"heidenhain", 4, 4, true}, {"okuma", 4, 5, false}};

struct BoundSetup {
  ProbePlan plan;
  MeasurementRun sim;         // exact triggers (no noise)
  IdentificationResult csv;   // through the csv dialect (17 significant digits)
  Eigen::MatrixXd G;          // d theta / d s_i: mm/mm and rad/mm
};

const BoundSetup& setupFor(LengthUnit unit) {
  static std::map<LengthUnit, BoundSetup> cache;
  auto it = cache.find(unit);
  if (it != cache.end()) return it->second;
  BoundSetup s;
  s.plan = test::acPlan(unit);
  Truth truth;
  truth.errors = test::table4();
  truth.artefact.setup.translation_mm = Eigen::Vector3d(0.5, -0.3, 0.2);
  truth.start_time_s = 7.5e8;
  s.sim = simulate(s.plan, truth, {1});
  const Dialect& csv = dialectByName("csv");
  const IdentificationOptions opt;
  s.csv = identify(s.plan, {csv.parseResults(csv.writeResults(s.plan, s.sim), "sim.csv", s.plan)}, opt);
  // Finite differences: 1 um steps, six decades above the solver's step tolerance (1e-10
  // relative) and small enough that the second-order terms (face re-estimation) vanish.
  const double h = 1e-3;
  const size_t n = s.sim.points.size();
  s.G.resize(kNumLocationErrors, static_cast<long>(n));
  for (size_t i = 0; i < n; ++i) {
    MeasurementRun pert = s.sim;
    pert.points[i].position_m_mm += h * s.plan.findPoint(pert.points[i].point_id)->approach_m;
    const IdentificationResult r = identify(s.plan, {pert}, opt);
    s.G.col(static_cast<long>(i)) = (r.estimate.values - s.csv.estimate.values) / h;
  }
  return cache.emplace(unit, std::move(s)).first->second;
}

double toReport(int k, double v) {
  return locationParameters(Kinematics::TableAC)[static_cast<size_t>(k)].kind == ParamKind::Length ? mmToUm(v)
                                                                                                    : radToMdeg(v);
}

class DigitsBound : public ::testing::TestWithParam<std::tuple<Printed, LengthUnit>> {};

TEST_P(DigitsBound, DialectPathEqualsCsvPathWithinThePrintedDigitsBound) {
  const auto [printed, unit] = GetParam();
  const BoundSetup& s = setupFor(unit);
  ASSERT_EQ(s.csv.summary.termination, Termination::Converged) << s.csv.summary.message;
  const Dialect& d = dialectByName(printed.dialect);
  const bool inch = unit == LengthUnit::Inch && !printed.mm_only;
  const int decimals = unit == LengthUnit::Inch ? printed.inch_decimals : printed.decimals;
  const double half_unit_mm = 0.5 * std::pow(10.0, -decimals) * (inch ? kMmPerInch : 1.0);

  const MeasurementRun run = d.parseResults(d.writeResults(s.plan, s.sim), "sim.txt", s.plan);
  ASSERT_EQ(run.points.size(), s.sim.points.size());
  const IdentificationResult r = identify(s.plan, {run}, IdentificationOptions{});
  ASSERT_EQ(r.summary.termination, Termination::Converged) << r.summary.message;

  Eigen::VectorXd e(run.points.size()), ds(run.points.size());
  for (size_t i = 0; i < run.points.size(); ++i) {
    ASSERT_EQ(run.points[i].point_id, s.sim.points[i].point_id);
    const Eigen::Vector3d& u = s.plan.findPoint(run.points[i].point_id)->approach_m;
    const Eigen::Vector3d dp = run.points[i].position_m_mm - s.sim.points[i].position_m_mm;
    // The printed digits are what the dialect claims: every coordinate within half a unit
    // (+1e-12 mm for the inch conversion's double arithmetic).
    EXPECT_LE(dp.cwiseAbs().maxCoeff(), half_unit_mm + 1e-12) << "point " << run.points[i].point_id;
    e[static_cast<long>(i)] = half_unit_mm * u.cwiseAbs().sum();
    ds[static_cast<long>(i)] = u.dot(dp);
  }
  const ErrorVector bound = s.G.cwiseAbs() * e;
  const ErrorVector diff = r.estimate.values - s.csv.estimate.values;
  const ErrorVector predicted = s.G * ds;
  const auto& params = locationParameters(Kinematics::TableAC);
  std::string table;
  for (int k = 0; k < kNumLocationErrors; ++k) {
    const auto& p = params[static_cast<size_t>(k)];
    // 1e-9 mm / 1e-9 rad: the solver's convergence floor (step tolerance 1e-10 relative).
    EXPECT_LE(std::abs(diff[k]), bound[k] + 1e-9) << printed.dialect << " " << p.name;
    // Linearisation: the actual change is G * ds up to second-order terms, here < 1 % of the
    // bound (or the 1e-9 floor).
    EXPECT_NEAR(diff[k], predicted[k], 0.01 * bound[k] + 1e-9) << printed.dialect << " " << p.name;
    table += fmt::format(" {}={:.4f}/{:.4f}{}", p.name, std::abs(toReport(k, diff[k])), toReport(k, bound[k]),
                         reportUnit(p.kind));
  }
  // |dialect - csv| / bound per parameter, for the report (docs/dialects.md).
  std::printf("[bound] %s %s, %d decimals:%s\n", printed.dialect, inch ? "inch" : "mm", decimals, table.c_str());
  // The rounding was exercised: the dialect's run differs from the exact one.
  EXPECT_GT(ds.cwiseAbs().maxCoeff(), 0.1 * half_unit_mm);
}

INSTANTIATE_TEST_SUITE_P(AllDialects, DigitsBound,
                         ::testing::Combine(::testing::ValuesIn(kPrinted),
                                            ::testing::Values(LengthUnit::Millimetre, LengthUnit::Inch)),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param).dialect) +
                                  (std::get<1>(info.param) == LengthUnit::Inch ? "_inch" : "_mm");
                         });

}  // namespace
}  // namespace rotacal
