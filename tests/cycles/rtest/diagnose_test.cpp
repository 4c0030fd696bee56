// thermal_drift on R-test series (issue 6): hidden drifts found, clean series and the real
// spindle curve's quantisation chatter not reported, the real heating curve measured.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "cycles/cycle.hpp"
#include "core/machine.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/rtest/diagnose.hpp"
#include "core/units.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

ProbePlan thermalPlan() {
  return makePlan("rtest", loadMachine(test::sourcePath("examples/machines/bc_trunnion.json")), {{"thermal", "1"}});
}

/// 002-like position-dependent errors (um / mdeg at B = -60..60), scaled.
Truth baseTruth(double scale, int shape) {
  Truth t;
  t.errors.kinematics = Kinematics::TableBC;
  t.pose_dependent = [scale, shape](const Pose& p) {
    const double s = p.B / 60.0;
    ErrorVector d = ErrorVector::Zero();
    d[0] = umToMm(scale * (3.0 + 2.0 * s));
    d[1] = umToMm(scale * (-4.0 + (shape % 2 ? 1.5 : -1.0) * s * s));
    d[2] = umToMm(scale * 5.0 * s);
    d[3] = mdegToRad(scale * (2.0 - s));
    d[4] = mdegToRad(scale * (-1.5 + 2.5 * s));
    d[5] = mdegToRad(scale * (shape % 3) * 0.5 * s * s);
    return d;
  };
  return t;
}

RtestDiagnosis run(const ProbePlan& plan, const Truth& truth, const RtestTruthExtras& x, std::uint64_t seed, double noise) {
  RtestSimOptions o;
  o.seed = seed;
  o.noise_um = noise;
  RtestDiagnosisOptions d;
  d.sensor_sigma_um = noise;
  return diagnoseRtest(plan, simulateRtest(plan, truth, x, o).cycles, d);
}

TEST(RtestDiagnosis, HiddenDriftOf002IsFoundAndMeasured) {
  // 002 Sec. 4.4: about -2 um X, -6 um Y, -2 um Z over 3 h; sizes and seeds varied.
  const ProbePlan plan = thermalPlan();
  for (double size : {0.5, 1.0, 1.5})
    for (std::uint64_t seed : {3u, 11u}) {
      Truth t = baseTruth(1.0, static_cast<int>(seed));
      const double ry = -2.0 * size, rx = -0.667 * size;  // um/h
      t.drift = [rx, ry](double s) {
        ErrorVector d = ErrorVector::Zero();
        d[0] = umToMm(rx * s / 3600.0);
        d[1] = umToMm(ry * s / 3600.0);
        return d;
      };
      const RtestDiagnosis d = run(plan, t, {}, seed, 0.2);
      ASSERT_TRUE(d.drift_found) << "size " << size << " seed " << seed << ": " << d.reason;
      EXPECT_GT(d.gain_pct, 10.0);
      for (int i = 0; i < 5; ++i) {  // dy_CB's rate at every B, within its uncertainty
        EXPECT_NEAR(mmToUm(d.analysis.rate(1, i)) * 3600, ry, 4.0 * mmToUm(d.analysis.rate_u(1, i)) * 3600);
        EXPECT_NEAR(mmToUm(d.analysis.rate(0, i)) * 3600, rx, 4.0 * mmToUm(d.analysis.rate_u(0, i)) * 3600);
      }
    }
}

TEST(RtestDiagnosis, NoFalseAlarmOnTwentyCleanSeeds) {
  const ProbePlan plan = thermalPlan();
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const double noise = 0.1 + 0.05 * static_cast<double>(seed % 5);  // 0.1 .. 0.3 um
    const RtestDiagnosis d = run(plan, baseTruth(0.5 + 0.1 * static_cast<double>(seed % 7), static_cast<int>(seed)), {},
                                 seed, noise);
    EXPECT_FALSE(d.drift_found) << "seed " << seed;
  }
}

std::vector<double> sjtuDriftUm() {
  std::vector<double> v;
  for (const char* rel : {"../shared/data", "../../shared/data"}) {
    std::ifstream in(test::sourcePath(std::string(rel) + "/sjtu-spindle-thermal/thermal_expansion_error_original.csv"));
    if (!in) continue;
    std::string line;
    std::getline(in, line);  // header (with a byte-order mark)
    while (std::getline(in, line)) v.push_back(std::stod(line.substr(0, line.find(','))));
    break;
  }
  return v;
}

/// The real axial growth (1-min samples) from row `start` as a spindle (sphere) Z drift.
RtestTruthExtras spindleGrowth(const std::vector<double>& dl, size_t start) {
  RtestTruthExtras x;
  x.sphere_drift_m_mm = [dl, start](double t_s) {
    const double m = t_s / 60.0;
    const size_t i = std::min(dl.size() - 2, start + static_cast<size_t>(m));
    const double w = std::min(1.0, m - std::floor(m));
    return Eigen::Vector3d(0, 0, umToMm((1 - w) * dl[i] + w * dl[i + 1] - dl[start]));
  };
  return x;
}

TEST(RtestDiagnosis, RealSpindleHeatingFoundAsUniformZDrift) {
  const std::vector<double> dl = sjtuDriftUm();
  if (dl.size() < 1000) GTEST_SKIP() << "shared/data/sjtu-spindle-thermal not found beside the project";
  const ProbePlan plan = thermalPlan();
  const RtestTruthExtras x = spindleGrowth(dl, 0);  // the first 3 h: 0 -> 3.9 um
  const RtestDiagnosis d = run(plan, baseTruth(1.0, 1), x, 5, 0.2);
  ASSERT_TRUE(d.drift_found) << d.reason;
  // Independent path: the least-squares slope of the injected curve at the cycles' times. The
  // sphere rising by L reads as the table sinking: dz_BY drifts by -L at every B.
  double st = 0, sy = 0, stt = 0, sty = 0;
  const double n = static_cast<double>(d.analysis.cycles.size());
  for (const auto& c : d.analysis.cycles) {
    const double t = c.t_s / 3600.0, y = -mmToUm(x.sphere_drift_m_mm(c.t_s).z());
    st += t, sy += y, stt += t * t, sty += t * y;
  }
  const double slope = (n * sty - st * sy) / (n * stt - st * st);
  std::printf("SJTU rows 0-180 as spindle growth: injected slope %.3f um/h; dz_BY rates", slope);
  for (int i = 0; i < 5; ++i)
    std::printf(" %.3f+-%.3f", mmToUm(d.analysis.rate(2, i)) * 3600, mmToUm(d.analysis.rate_u(2, i)) * 3600);
  std::printf(" um/h; held-out gain %.1f %%\n", d.gain_pct);
  for (int i = 0; i < 5; ++i) {
    if (!(d.analysis.rate_u(2, i) > 0)) continue;
    // the curve bends (its scatter about a line is in rate_u); 0.05 um/h for the tilts' minute offsets
    EXPECT_NEAR(mmToUm(d.analysis.rate(2, i)) * 3600, slope, 4.0 * mmToUm(d.analysis.rate_u(2, i)) * 3600 + 0.05) << i;
  }
}

TEST(RtestDiagnosis, RealQuantisationChatterIsNotAnEffect) {
  const std::vector<double> dl = sjtuDriftUm();
  if (dl.size() < 1000) GTEST_SKIP() << "shared/data/sjtu-spindle-thermal not found beside the project";
  const ProbePlan plan = thermalPlan();
  // Every 3-h window of the real curve's plateau (after row 1200) in which it only chatters:
  // max - min within two quantisation steps (0.53 um).
  int windows = 0;
  for (size_t start = 1200; start + 200 < dl.size(); start += 120) {
    const auto [lo, hi] = std::minmax_element(dl.begin() + static_cast<long>(start), dl.begin() + static_cast<long>(start) + 190);
    if (*hi - *lo > 0.53) continue;
    ++windows;
    const RtestDiagnosis d = run(plan, baseTruth(1.0, static_cast<int>(start)), spindleGrowth(dl, start), start, 0.2);
    EXPECT_FALSE(d.drift_found) << "window from row " << start << ": chatter reported as drift";
    double tmax = 0;
    for (const auto& t : d.tests) tmax = std::max(tmax, std::abs(t.t));
    std::printf("chatter window from row %zu: max |t| %.2f, held-out gain %.1f %%\n", start, tmax, d.gain_pct);
  }
  EXPECT_GE(windows, 5);
}

TEST(RtestDiagnosis, StudentTail) {
  // Closed forms: nu = 1 is Cauchy, P(|T| > 1) = 0.5; nu = 2: P(|T| > t) = 1 - t / sqrt(2 + t^2).
  EXPECT_NEAR(studentTwoSided(1.0, 1.0), 0.5, 1e-9);
  EXPECT_NEAR(studentTwoSided(3.0, 2.0), 1.0 - 3.0 / std::sqrt(11.0), 1e-9);
  EXPECT_NEAR(studentTwoSided(0.0, 11.0), 1.0, 1e-12);
}

}  // namespace
}  // namespace rotacal
