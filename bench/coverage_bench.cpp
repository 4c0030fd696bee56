// rotacal_coverage_bench: the honest test of an uncertainty. Machines are drawn from
// the declared contributors (true location errors, probe repeatability, pre-travel, linear-axis
// errors, set-up, form, roughness), each measured on the exact simulator and analyzed as
// `analyze` does (estimate + touch154Budget); the bench counts how often the truth lies within
// +-U (k read off each analysis' Monte Carlo) of the estimate, per parameter. Claimed: about 95 %; accepted: 93-97 %
// (docs/uncertainty.md). Printed, not asserted. Each machine's analysis draws its own Monte Carlo
// runs (a seed per machine): the coverage of the method, its Monte Carlo's sampling included, not
// of one fixed set of draws shared by every machine.
// Run: build/bench/rotacal_coverage_bench [machines] [method: lsq_per_point|closed_form|lsq_rigid_setup] [CONTRIB.json]
//      build/bench/rotacal_coverage_bench rtest [machines]   (the R-test cycle: bc_trunnion with
//      its declared contributors, examples/contributors/rtest_002.json; analyze's rtestBudget)
//      build/bench/rotacal_coverage_bench tooltip [machines]  (the tool-tip cycle of 004: head_ab
//      with examples/contributors/tooltip_004.json; analyze's tooltipBudget)
//      build/bench/rotacal_coverage_bench spheres3 [machines] [CONTRIB.json]   (the three-sphere
//      cycle on ac_trunnion, default examples/contributors/spheres3_001.json; spheres3Budget)
//      build/bench/rotacal_coverage_bench one_sphere_head [machines] [CONTRIB.json] ["OPTIONS"]   (the
//        one-sphere cycle on examples/machines/bc_head_table.json, a B head over a C table)
//      build/bench/rotacal_coverage_bench one_sphere_head_ab [machines] [CONTRIB.json] ["OPTIONS"]   (the
//        same on examples/machines/ab_head.json, an A head carrying a B head)
//      build/bench/rotacal_coverage_bench one_sphere [machines] [CONTRIB.json] ["OPTIONS"]   (the
//        one-sphere cycle on ac_trunnion, default examples/contributors/table5.json; sphereBudget)
//      OPTIONS: the plan's options as `plan --set` takes them, e.g. "poses=14 design=A"
//      build/bench/rotacal_coverage_bench spaceframe [machines] [frame_u_um]   (the space frame
//      on ac_trunnion, phi -90 -45 0, with its declared contributors, 000 Table 5, and a frame
//      calibrated to frame_u_um per coordinate, default 1; spaceframeBudget)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/machine.hpp"
#include "core/rng.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "cycles/cycle.hpp"
#include "cycles/touch154/budget.hpp"
#include "cycles/touch154/closed_form.hpp"
#include "cycles/touch154/uncertainty.hpp"
#include "cycles/rtest/analyze.hpp"
#include "cycles/rtest/budget.hpp"
#include "cycles/tooltip/analyze.hpp"
#include "cycles/tooltip/budget.hpp"
#include "cycles/spheres3/analyze.hpp"
#include "cycles/spheres3/budget.hpp"
#include "cycles/one_sphere/analyze.hpp"
#include "cycles/one_sphere/budget.hpp"
#include "cycles/one_sphere/plan.hpp"
#include "core/contributor_draw.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/spaceframe/budget.hpp"

using namespace rotacal;

namespace {

// The mean coverage factor per parameter (U = k u_c; k read off each analysis' own Monte Carlo
// distribution, core/uncertainty_budget.hpp), printed under each table.
struct MeanCoverageFactor {
  std::vector<std::string> names;
  Eigen::VectorXd sum;
  int n = 0;
  void add(const UncertaintyBudget& b) {
    if (n == 0) {
      names = b.names;
      sum = Eigen::VectorXd::Zero(b.size());
    }
    if (b.size() != sum.size()) return;
    sum += b.coverageFactors();
    ++n;
  }
  void print() const {
    std::string line = "mean k:";
    for (size_t i = 0; i < names.size(); ++i)
      line += fmt::format("{} {} {:.2f}", i ? "," : "", names[i], sum[static_cast<Eigen::Index>(i)] / std::max(1, n));
    std::printf("%s\n", line.c_str());
  }
};

// The coverage test's tally (docs/uncertainty.md), the one rule every cycle's section below
// applies: per parameter, how often the error lies within U and within u_c over the machines
// drawn, and the rms of the error, of u_c and of u_A (each in the parameter's unit). A row pools
// the parameters lo..hi-1; a parameter given without u_A leaves "within u" and "rms u_A" blank.
class Coverage {
 public:
  explicit Coverage(size_t parameters = 0) { resize(parameters); }
  void resize(size_t parameters) {
    for (auto* v : {&in_U_, &in_u_, &e2_, &uc2_, &ua2_, &n_}) v->assign(parameters, 0.0);
  }
  size_t size() const { return n_.size(); }
  double count(size_t i) const { return n_[i]; }
  void add(size_t i, double err, double U, double uc, double ua = 0.0) {
    in_U_[i] += err <= U;
    in_u_[i] += err <= uc;
    e2_[i] += err * err;
    uc2_[i] += uc * uc;
    ua2_[i] += ua * ua;
    ++n_[i];
  }
  std::string columns(size_t lo, size_t hi, bool with_u = true) const {
    double in_U = 0, in_u = 0, e2 = 0, uc2 = 0, ua2 = 0, n = 0;
    for (size_t i = lo; i < hi; ++i) {
      in_U += in_U_[i], in_u += in_u_[i], e2 += e2_[i], uc2 += uc2_[i], ua2 += ua2_[i];
      n += n_[i];
    }
    n = std::max(n, 1.0);
    if (!with_u)
      return fmt::format("{:11.1f}% {:>12} {:10.3f} {:10.3f} {:>10}", 100.0 * in_U / n, "", std::sqrt(e2 / n),
                         std::sqrt(uc2 / n), "");
    return fmt::format("{:11.1f}% {:11.1f}% {:10.3f} {:10.3f} {:10.3f}", 100.0 * in_U / n, 100.0 * in_u / n,
                       std::sqrt(e2 / n), std::sqrt(uc2 / n), std::sqrt(ua2 / n));
  }
  std::string columns(size_t i, bool with_u = true) const { return columns(i, i + 1, with_u); }
  /// One row: the name in `width` characters, the columns, then `tail`.
  std::string row(const std::string& name, size_t i, const std::string& tail, int width = 8) const {
    return fmt::format("{:<{}} {}{}", name, width, columns(i), tail);
  }

 private:
  std::vector<double> in_U_, in_u_, e2_, uc2_, ua2_, n_;
};

/// The spread every machine's true location errors are drawn from, of 000 Table 4's size: per
/// length (um), per angle (mdeg). Every cycle's coverage is measured over the same population.
constexpr double kTruthSdUm = 20.0, kTruthSdMdeg = 2.0;

/// A machine's true location errors, drawn with kTruthSdUm and kTruthSdMdeg.
LocationErrors drawLocationErrors(Kinematics kinematics, Rng& rng) {
  LocationErrors e;
  e.kinematics = kinematics;
  const auto& params = locationParameters(kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i)
    e.setReportValue(i, (params[static_cast<size_t>(i)].kind == ParamKind::Length ? kTruthSdUm : kTruthSdMdeg) * rng.normal());
  return e;
}

/// One more machine analyzed; every 50th is counted on stderr (runs of thousands take minutes).
void countMachine(int& done) {
  ++done;
  if (done % 50 == 0) std::fprintf(stderr, "%d machines\n", done);
}

std::string coverageHeader(int width) {
  return fmt::format("{:<{}} {:>12} {:>12} {:>10} {:>10} {:>10}", "param", width, "within U", "within u", "rms e", "rms u_c",
                     "rms u_A");
}

void printClaimed() {
  std::printf("claimed: 95.4 %% within U (k from the Monte Carlo, JCGM 101), 68.3 %% within u (if normal); accepted 93-97 %% "
              "(docs/uncertainty.md)\n");
}

// The R-test: every machine draws its location errors and every declared contributor (the Type
// B ones through drawRtest, on the exact simulator; sensor noise and sphere form per reading),
// and is analyzed as `analyze` does (analyzeRtest + rtestBudget, 1000 Monte Carlo runs).
int rtestCoverage(int machines) {
  const MachineModel machine = loadMachine(ROTACAL_SOURCE_DIR "/examples/machines/bc_trunnion.json");
  const ProbePlan plan = makePlan("rtest", machine, {});
  const ContributorSet& cs = *machine.contributors;
  const double sensor_um = 0.2;  // the plan's sensor_noise_um (002 Table 1)
  const double form_um = cs.find("rtest_sphere_form") ? mmToUm(cs.find("rtest_sphere_form")->u[0]) : 0.0;
  const auto& params = locationParameters(machine.kinematics);
  Coverage cov(kNumLocationErrors), tilt_cov(kRtestParams);
  MeanCoverageFactor mean_k;
  int done = 0;
  for (int m = 0; m < machines; ++m) {
    Rng rng(778, static_cast<std::uint64_t>(m));
    Truth t;
    t.errors = drawLocationErrors(machine.kinematics, rng);
    RtestDraw d;
    drawRtest(plan, cs, 4343, m, -1, &d);
    RtestTruthExtras x;
    applyRtestDraw(plan, d, &t, &x);
    RtestSimOptions so;
    so.seed = static_cast<std::uint64_t>(m) + 1;
    so.noise_um = std::hypot(sensor_um, form_um);
    so.cycles = 1;
    const RtestSeries s = simulateRtest(plan, t, x, so);
    RtestFitOptions fo;
    fo.sensor_sigma_um = sensor_um;
    const RtestAnalysis a = analyzeRtest(plan, s.cycles, fo);
    if (!a.location.identifiable) continue;
    RtestBudgetOptions bo;
    bo.runs = 1000;
    bo.alone_runs = 0;
    bo.seed = 0x4d43000000ULL + static_cast<std::uint64_t>(m);  // each machine its own Monte Carlo draws
    const UncertaintyBudget b = rtestBudget(plan, s.cycles.front(), a.location, sensor_um, &cs, bo);
    const Eigen::VectorXd uc = b.uC(), ua = b.uA(), U = b.expanded();
    mean_k.add(b);
    LocationErrors est;
    est.kinematics = machine.kinematics;
    est.values = a.location.value;
    for (int i = 0; i < kNumLocationErrors; ++i) {
      cov.add(i, std::abs(est.reportValue(i) - t.errors.reportValue(i)), U[i], uc[i], ua[i]);
    }
    // The per-tilt errors: their truth is the per-tilt fit of the machine's own readings without
    // noise or contributors (the six errors per tilt that the location errors make, as the fit
    // refers them to the reset).
    {
      RtestBudgetOptions tbo;
      tbo.runs = 1000;
      tbo.alone_runs = 0;
      tbo.seed = 0x4d43000000ULL + static_cast<std::uint64_t>(m);
      const RtestTiltBudget tb = rtestTiltBudget(plan, s.cycles.front(), a, fo, &cs, tbo);
      Truth clean;
      clean.errors = t.errors;
      RtestSimOptions cso;
      cso.cycles = 1;
      const Eigen::MatrixXd truth_tilt = analyzeRtest(plan, simulateRtest(plan, clean, {}, cso).cycles, fo).cycles.front().value;
      const Eigen::MatrixXd uc_t = tb.uC(), U_t = tb.expanded();
      for (int i = 0; i < tb.tilts; ++i)
        for (int p = 0; p < kRtestParams; ++p) {
          if (uc_t(p, i) == 0.0) continue;  // fixed by the reset
          const double f = rtestParameterIsLength(p) ? kUmPerMm : kMdegPerRad;
          const double err = f * std::abs(a.cycles.front().value(p, i) - truth_tilt(p, i));
          tilt_cov.add(p, err, U_t(p, i), uc_t(p, i));
        }
    }
    countMachine(done);
  }
  std::printf("rtest: %d machines drawn from %s (true errors sd %.0f um / %.0f mdeg, sensor noise %.2f um, form %.2f um)\n",
              done, cs.file.c_str(), kTruthSdUm, kTruthSdMdeg, sensor_um, form_um);
  std::printf("%s\n", coverageHeader(8).c_str());
  for (int i = 0; i < kNumLocationErrors; ++i)
    std::printf("%s\n", cov.row(std::string(params[i].name), i, "  " + std::string(reportUnit(params[i].kind))).c_str());
  std::printf("per-tilt errors of the first cycle (pooled over the tilts; dz and c at the reset's tilt are fixed):\n");
  for (int p = 0; p < kRtestParams; ++p)
    std::printf("%-8s %s  %s\n", rtestParameterName(machine.kinematics, p).c_str(), tilt_cov.columns(p, false).c_str(),
                rtestParameterIsLength(p) ? "um" : "mdeg");
  mean_k.print();
  printClaimed();
  return 0;
}

// The tool-tip test of 004: every machine draws its head (dR and an angular error per commanded
// angle, the size of docs/tooltip.md's example) and every declared contributor (the Type B ones
// through drawTooltip on the exact head geometry; the per-reading ones, 004's laser, sphere and
// lateral coupling, as noise per reading component), and is analyzed as `analyze` does
// (analyzeTooltip + tooltipBudget, 400 Monte Carlo runs).
int tooltipCoverage(int machines) {
  const MachineModel machine = loadMachine(ROTACAL_SOURCE_DIR "/examples/machines/head_ab.json");
  const ProbePlan plan =
      makePlan("tooltip", machine, {{"units", "inch"}, {"radius_mm", "381"}, {"step_deg", "5"}, {"end_deg", "90"}});
  const ContributorSet& cs = *machine.contributors;
  double noise2 = 0;
  for (const auto& c : cs.items)
    if (tooltipTypeA(*c.info)) noise2 += mmToUm(c.u[0]) * mmToUm(c.u[0]);
  const double noise_um = std::sqrt(noise2);
  const double sd_dR_um = 40.0, sd_e_mdeg = 3.0, sd_e_angle_mdeg = 1.0;
  TooltipHead head;
  for (const auto& p : plan.points)
    if (head.angles_deg.empty() || std::abs(p.pose.A - head.angles_deg.back()) > 1e-9) head.angles_deg.push_back(p.pose.A);
  const int J = static_cast<int>(head.angles_deg.size());
  Coverage cov(static_cast<size_t>(J) + 1);
  MeanCoverageFactor mean_k;
  int done = 0;
  for (int m = 0; m < machines; ++m) {
    Rng rng(779, static_cast<std::uint64_t>(m));
    head.dR_um = sd_dR_um * rng.normal();
    const double c0 = sd_e_mdeg * rng.normal(), c1 = sd_e_mdeg * rng.normal(), c2 = sd_e_mdeg * rng.normal(),
                 c3 = sd_e_mdeg * rng.normal();
    head.e_mdeg.clear();
    for (double a : head.angles_deg) {
      const double r = degToRad(a);
      head.e_mdeg.push_back(c0 + c1 * a / 90.0 + c2 * std::sin(r) + c3 * std::sin(2 * r) + sd_e_angle_mdeg * rng.normal());
    }
    TooltipDraw d;
    drawTooltip(plan, cs, 5151, m, -1, &d);
    Rng noise(780, static_cast<std::uint64_t>(m));
    const TooltipRun run = simulateTooltipHead(plan, head, d, true, noise_um, &noise);
    const TooltipAnalysis a = analyzeTooltip(plan, {run});
    TooltipBudgetOptions bo;
    bo.runs = kMinRunsForCoverageFactor;  // the fewest from which k is read off (analyze: 2000)
    bo.alone_runs = 0;
    bo.seed = 0x4d43000000ULL + static_cast<std::uint64_t>(m);  // each machine its own Monte Carlo draws
    const UncertaintyBudget b = tooltipBudget(plan, {run}, a, 0.254, &cs, bo);
    if (b.size() != J + 1) continue;
    const Eigen::VectorXd uc = b.uC(), ua = b.uA(), U = b.expanded();
    mean_k.add(b);
    for (int i = 0; i <= J; ++i) {  // e_k in angle order, then dR (the budget's order)
      const double est = i < J ? a.joint.e_mdeg[static_cast<size_t>(i)] : a.joint.dR_um;
      const double tru = i < J ? head.e_mdeg[static_cast<size_t>(i)] : head.dR_um;
      cov.add(static_cast<size_t>(i), std::abs(est - tru), U[i], uc[i], ua[i]);
    }
    countMachine(done);
  }
  std::printf("tooltip: %d machines drawn from %s (true dR sd %.0f um, e sd %.0f mdeg per shape term + %.0f mdeg per "
              "angle, per-reading noise %.3f um)\n",
              done, cs.file.c_str(), sd_dR_um, sd_e_mdeg, sd_e_angle_mdeg, noise_um);
  std::printf("%s\n", coverageHeader(8).c_str());
  auto row = [&](const std::string& name, int lo, int hi, const char* unit) {
    std::printf("%-8s %s  %s\n", name.c_str(), cov.columns(static_cast<size_t>(lo), static_cast<size_t>(hi)).c_str(), unit);
  };
  row("e (all)", 0, J, "mdeg (pooled over the angles)");
  for (int i = 0; i < J; ++i) row(fmt::format("e_A{:g}", head.angles_deg[static_cast<size_t>(i)]), i, i + 1, "mdeg");
  row("dR", J, J + 1, "um");
  mean_k.print();
  printClaimed();
  return 0;
}

// The three spheres (001): every machine draws its C location errors, component errors (the
// identifiable harmonics up to 3C), the spheres' places on the table and every declared
// contributor (Type B through drawSpheres3 on the exact simulator; repeatability and roughness
// per touch), and is analyzed as `analyze` does (identifySpheres3 + spheres3Budget, 1000 Monte
// Carlo runs). Coverage per location error, and per component error over the 12 sampled angles.
// The per-touch variance (mm^2) of the contributors a cycle takes as acting at every touch.
double perTouchVariance_mm2(const ContributorSet& cs, bool (*per_touch)(const ContributorInfo&)) {
  double v = 0.0;
  for (const auto& c : cs.items)
    if (per_touch(*c.info)) v += c.u[0] * c.u[0];
  return v;
}

int spheres3Coverage(int machines, const std::string& contributors_file) {
  const MachineModel machine = loadMachine(ROTACAL_SOURCE_DIR "/examples/machines/ac_trunnion.json");
  const ProbePlan plan = makePlan("spheres3", machine, {});
  const ContributorSet cs = loadContributors(contributors_file);
  const double touch_mm2 = perTouchVariance_mm2(cs, spheres3TypeA);
  const int n_angles = static_cast<int>(plan.poses.size());
  const std::vector<ComponentTerm> terms = componentTerms(ComponentModel::Full, n_angles);
  // 001: location errors of a few um and arcsec, volumetric error up to 12 um before
  // compensation; drawn larger for the location errors (000 Table 4's size, as the other cycles).
  const double comp_um = 1.0, comp_mdeg = 0.5, sphere_um = 50.0;
  const char* names[4] = {"Oxc", "Oyc", "Sxc", "Syc"};
  Coverage cov(4), c_cov(kNumComponentErrors);
  MeanCoverageFactor mean_k;
  int done = 0;
  for (int m = 0; m < machines; ++m) {
    Rng rng(779, static_cast<std::uint64_t>(m));
    const Eigen::Vector4d L(umToMm(kTruthSdUm * rng.normal()), umToMm(kTruthSdUm * rng.normal()),
                            mdegToRad(kTruthSdMdeg * rng.normal()), mdegToRad(kTruthSdMdeg * rng.normal()));
    Eigen::VectorXd h = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(terms.size()));
    for (size_t k = 0; k < terms.size(); ++k)
      if (terms[k].k <= 3)
        h[static_cast<Eigen::Index>(k)] = terms[k].component >= 3 ? mdegToRad(comp_mdeg * rng.normal()) : umToMm(comp_um * rng.normal());
    auto componentAt = [&terms, h](double c_rad) {
      ComponentVector v = ComponentVector::Zero();
      for (size_t k = 0; k < terms.size(); ++k) v += h[static_cast<Eigen::Index>(k)] * terms[k].value(c_rad);
      return v;
    };
    Truth t;
    t.errors.kinematics = machine.kinematics;
    t.table_transform = [L, componentAt](const Pose& pose, double) {
      return spheres3Table_m_w(L, componentAt(degToRad(pose.C)), degToRad(pose.C));
    };
    for (int i = 1; i <= 3; ++i)
      t.sphere_center_error_w_mm[i] = Eigen::Vector3d(umToMm(sphere_um * rng.normal()), umToMm(sphere_um * rng.normal()),
                                                      umToMm(sphere_um * rng.normal()));
    Spheres3Draw d;
    drawSpheres3(plan, cs, 4545, m, -1, &d);
    applySpheres3Draw(d, &t);
    t.noise_um = mmToUm(std::sqrt(touch_mm2));
    const MeasurementRun run = simulate(plan, t, {static_cast<std::uint64_t>(m) + 1});
    Spheres3Options o;
    o.prior_sigma_um = machine.probe.repeatability_um;
    Spheres3Result r;
    try {
      r = identifySpheres3(plan, {run}, o);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "machine %d: %s\n", m, e.what());
      continue;
    }
    Spheres3BudgetOptions bo;
    bo.runs = 1000;
    bo.alone_runs = 0;
    bo.seed = 0x4d43000000ULL + static_cast<std::uint64_t>(m);  // each machine its own Monte Carlo draws
    const Spheres3Budget b = spheres3Budget(plan, r, {}, &cs, bo);
    const Eigen::VectorXd uc = b.location.uC(), ua = b.location.uA(), U = b.location.expanded();
    mean_k.add(b.location);
    for (int i = 0; i < 4; ++i) {
      const double f = i < 2 ? kUmPerMm : kMdegPerRad;
      cov.add(i, f * std::abs(r.location[i] - L[i]), U[i], uc[i], ua[i]);
    }
    for (int a = 0; a < n_angles; ++a) {
      const ComponentVector truth = componentAt(degToRad(r.c_deg[static_cast<size_t>(a)]));
      for (int k = 0; k < kNumComponentErrors; ++k) {
        const double f = k >= 3 ? kMdegPerRad : kUmPerMm;
        const double err = f * std::abs(r.values(a, k) - truth[k]);
        const double u = b.component_u_c(a, k);
        c_cov.add(k, err, b.component_k(a, k) * u, u);
      }
    }
    countMachine(done);
  }
  std::printf("spheres3: %d machines drawn from %s (location errors sd %.0f um / %.0f mdeg, component terms up to 3C sd "
              "%.1f um / %.1f mdeg, spheres %.0f um, per-touch scatter %.3f um)\n",
              done, cs.file.c_str(), kTruthSdUm, kTruthSdMdeg, comp_um, comp_mdeg, sphere_um, mmToUm(std::sqrt(touch_mm2)));
  std::printf("%s\n", coverageHeader(8).c_str());
  for (int i = 0; i < 4; ++i) std::printf("%s\n", cov.row(names[i], i, i < 2 ? "  um" : "  mdeg").c_str());
  std::printf("component errors at the %d sampled angles:\n", n_angles);
  for (int k = 0; k < kNumComponentErrors; ++k)
    std::printf("%-8s %s  %s\n", componentNames()[static_cast<size_t>(k)], c_cov.columns(k, false).c_str(),
                k >= 3 ? "mdeg" : "um");
  mean_k.print();
  printClaimed();
  return 0;
}


// The space frame (003): every machine draws its location errors (000 Table 4's size), the
// frame's set-up on the table, the frame's true spheres about its calibration (FRAME.json's u)
// and every declared contributor (Type B through drawProbeAxes on the exact simulator: the drawn
// linear scale is the truth of the fitted one; repeatability and roughness per touch), and is
// analyzed as `analyze` does (analyzeSpaceframe + spaceframeBudget, 500 Monte Carlo runs).
int spaceframeCoverage(int machines, double frame_u_um) {
  const MachineModel machine = loadMachine(ROTACAL_SOURCE_DIR "/examples/machines/ac_trunnion.json");
  const ProbePlan plan = makePlan("spaceframe", machine, {{"phi_list", "-90,-45,0"}, {"frame_u_um", fmt::format("{:g}", frame_u_um)}});
  const ContributorSet& cs = *machine.contributors;
  double touch_mm2 = 0.0;
  for (const auto& c : cs.items)
    if (spaceframeTypeA(*c.info)) touch_mm2 += c.u[0] * c.u[0];
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  const double setup_um = 50.0, setup_mdeg = 5.0;
  std::vector<std::string> names;
  Coverage cov;
  MeanCoverageFactor mean_k;
  int done = 0;
  for (int m = 0; m < machines; ++m) {
    Rng rng(991, static_cast<std::uint64_t>(m));
    FrameModel truth_model;
    truth_model.errors = drawLocationErrors(machine.kinematics, rng);
    for (int i = 0; i < 3; ++i) {
      truth_model.setup_translation_mm[i] = umToMm(setup_um * rng.normal());
      truth_model.setup_rotation_rad[i] = mdegToRad(setup_mdeg * rng.normal());
    }
    Truth t;
    t.errors = truth_model.errors;
    for (const auto& p : plan.points)
      if (!t.sphere_center_error_w_mm.count(p.sphere->id)) {
        Eigen::Vector3d frame_error(rng.normal(), rng.normal(), rng.normal());
        t.sphere_center_error_w_mm[p.sphere->id] =
            truth_model.placedCentre_w(p.sphere->center_w_mm, p.sphere->id, layout.origin_w_mm) - p.sphere->center_w_mm +
            umToMm(frame_u_um) * frame_error;
      }
    ProbeAxesDraw d;
    drawProbeAxes(plan, cs, spaceframeTypeB, 5151, m, -1, &d);
    applyProbeAxesDraw(d, &t);
    truth_model.scale = d.linear_errors.scale;
    t.noise_um = mmToUm(std::sqrt(touch_mm2));
    const MeasurementRun run = simulate(plan, t, {static_cast<std::uint64_t>(m) + 1});
    SpaceframeAnalysis a;
    try {
      a = analyzeSpaceframe(plan, {run});
    } catch (const std::exception& e) {
      std::fprintf(stderr, "machine %d: %s\n", m, e.what());
      continue;
    }
    SpaceframeBudgetOptions bo;
    bo.runs = kMinRunsForCoverageFactor;  // the fewest from which k is read off (analyze: 2000)
    bo.alone_runs = 0;
    bo.seed = 0x4d43000000ULL + static_cast<std::uint64_t>(m);  // each machine its own Monte Carlo draws
    const UncertaintyBudget b = spaceframeBudget(plan, a, {}, &cs, bo);
    SpaceframeAnalysis truth_as_analysis;
    truth_as_analysis.model = truth_model;
    const Eigen::VectorXd est = spaceframeBudgetValues(plan, a), tru = spaceframeBudgetValues(plan, truth_as_analysis);
    const Eigen::VectorXd uc = b.uC(), ua = b.uA(), U = b.expanded();
    mean_k.add(b);
    if (names.empty()) {
      names = b.names;
      cov.resize(names.size());
    }
    for (int i = 0; i < b.size(); ++i) cov.add(static_cast<size_t>(i), std::abs(est[i] - tru[i]), U[i], uc[i], ua[i]);
    countMachine(done);
  }
  std::printf("spaceframe: %d machines, contributors %s, frame calibrated to %g um per coordinate (location errors sd "
              "%.0f um / %.0f mdeg, set-up %.0f um / %.0f mdeg, per-touch scatter %.3f um)\n",
              done, cs.file.c_str(), frame_u_um, kTruthSdUm, kTruthSdMdeg, setup_um, setup_mdeg, mmToUm(std::sqrt(touch_mm2)));
  std::printf("%s\n", coverageHeader(14).c_str());
  for (size_t i = 0; i < names.size(); ++i) std::printf("%s\n", cov.row(names[i], i, "", 14).c_str());
  mean_k.print();
  printClaimed();
  return 0;
}

}  // namespace

// One drawn one-sphere machine as `analyze` sees it: its declared contributors drawn into the
// truth (draw_seed, machine m), the per-touch scatter as noise, the fit, the budget (1000 Monte
// Carlo runs, each machine its own seed). Empty when the fit refuses the data.
std::optional<UncertaintyBudget> drawnSphereMachine(const ProbePlan& plan, const ContributorSet& cs, Truth t, int m,
                                                    std::uint64_t draw_seed, std::uint64_t mc_seed_base,
                                                    SphereCycleResult* r, ProbeAxesDraw* drawn = nullptr) {
  ProbeAxesDraw d;
  drawProbeAxes(plan, cs, isProbeAxesContributor, draw_seed, m, -1, &d);
  applyProbeAxesDraw(d, &t);
  if (drawn) *drawn = d;
  t.noise_um = mmToUm(std::sqrt(perTouchVariance_mm2(cs, isPerTouchContributor)));
  try {
    *r = identifySphereCycle(plan, {simulate(plan, t, {static_cast<std::uint64_t>(m) + 1})});
  } catch (const std::exception& e) {
    std::fprintf(stderr, "machine %d: %s\n", m, e.what());
    return std::nullopt;
  }
  BudgetOptions bo;
  bo.runs = 1000;
  bo.alone_runs = 0;
  bo.seed = mc_seed_base + static_cast<std::uint64_t>(m);
  return sphereBudget(plan, *r, &cs, bo);
}

/// The one-sphere plan of `machine` with `plan_options` ("key=value key=value", as `plan --set`
/// takes them), its size printed.
ProbePlan oneSpherePlan(const MachineModel& machine, const std::string& plan_options) {
  CycleOptions options;
  for (size_t at = 0; at < plan_options.size();) {
    const size_t end = std::min(plan_options.find(' ', at), plan_options.size());
    const std::string kv = plan_options.substr(at, end - at);
    if (const size_t eq = kv.find('='); eq != std::string::npos) options[kv.substr(0, eq)] = kv.substr(eq + 1);
    at = end + 1;
  }
  const ProbePlan plan = makePlan("one_sphere", machine, options);
  std::printf("plan: %zu poses, %zu touches, %.0f s of machine time (options: %s)\n", plan.poses.size(), plan.points.size(),
              plan.points.back().t_s, plan_options.empty() ? "none" : plan_options.c_str());
  return plan;
}

// The one sphere: every machine draws the 8 location errors of its A/C table (000 Table
// 4's size), the sphere's place on the table (50 um) and every declared contributor that acts on
// one sphere (the probe's pretravel by direction and the linear axes through drawProbeAxes, on
// the exact simulator; repeatability and roughness per touch), and is analyzed as `analyze` does
// (identifySphereCycle + sphereBudget, 1000 Monte Carlo runs, each machine its own seed).
int oneSphereCoverage(int machines, const std::string& contributors_file, const std::string& plan_options) {
  const MachineModel machine = loadMachine(ROTACAL_SOURCE_DIR "/examples/machines/ac_trunnion.json");
  const ProbePlan plan = oneSpherePlan(machine, plan_options);
  const ContributorSet cs = loadContributors(contributors_file);
  const double touch_mm2 = perTouchVariance_mm2(cs, isPerTouchContributor);
  const auto& params = locationParameters(machine.kinematics);
  const double sphere_um = 50.0;
  Coverage cov(kNumLocationErrors);
  double k_sum[kNumLocationErrors] = {};
  // The linear axes' squareness, where the plan fits it: its truth is the drawn one.
  const char* sq_names[3] = {"S_xy", "S_xz", "S_yz"};
  Coverage sq_cov(3);
  int done = 0;
  for (int m = 0; m < machines; ++m) {
    Rng rng(780, static_cast<std::uint64_t>(m));
    Truth t;
    t.errors = drawLocationErrors(machine.kinematics, rng);
    t.sphere_center_error_w_mm[1] = Eigen::Vector3d(umToMm(sphere_um * rng.normal()), umToMm(sphere_um * rng.normal()),
                                                    umToMm(sphere_um * rng.normal()));
    SphereCycleResult r;
    ProbeAxesDraw d;
    const auto b_or = drawnSphereMachine(plan, cs, t, m, 4646, 0x4d43000000ULL, &r, &d);
    if (!b_or) continue;
    const UncertaintyBudget& b = *b_or;
    const Eigen::VectorXd uc = b.uC(), ua = b.uA(), U = b.expanded(), kf = b.coverageFactors();
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const std::string& iso = r.names[static_cast<size_t>(r.location_index_in_x[static_cast<size_t>(i)])].name;
      int q = 0;
      for (int k = 0; k < b.size(); ++k)
        if (b.names[static_cast<size_t>(k)] == iso) q = k;
      cov.add(i, std::abs(r.location.reportValue(i) - t.errors.reportValue(i)), U[q], uc[q], ua[q]);
      k_sum[i] += kf[q];
    }
    if (d.linear) {
      const double drawn[3] = {d.linear_errors.S_xy, d.linear_errors.S_xz, d.linear_errors.S_yz};
      for (int s = 0; s < 3; ++s)
        for (int k = 0; k < b.size(); ++k)
          if (b.names[static_cast<size_t>(k)] == sq_names[s]) {
            size_t xi = 0;
            for (size_t i = 0; i < r.names.size(); ++i)
              if (r.names[i].name == sq_names[s]) xi = i;
            const double err = std::abs(radToMdeg(r.x[static_cast<Eigen::Index>(xi)] - drawn[s]));
            sq_cov.add(s, err, U[k], uc[k]);
          }
    }
    countMachine(done);
  }
  std::printf("one_sphere: %d machines drawn from %s (location errors sd %.0f um / %.0f mdeg, sphere %.0f um, per-touch "
              "scatter %.3f um)\n",
              done, cs.file.c_str(), kTruthSdUm, kTruthSdMdeg, sphere_um, mmToUm(std::sqrt(touch_mm2)));
  std::printf("%s %8s\n", coverageHeader(8).c_str(), "mean k");
  for (int i = 0; i < kNumLocationErrors; ++i)
    std::printf("%s\n", cov.row(std::string(params[static_cast<size_t>(i)].name), i,
                                fmt::format(" {:8.2f}  {}", k_sum[i] / done,
                                            params[static_cast<size_t>(i)].kind == ParamKind::Length ? "um" : "mdeg"))
                            .c_str());
  for (int s = 0; s < 3 && sq_cov.count(s) > 0; ++s)
    std::printf("%-8s %s %8s  mdeg (the linear axes' squareness, fitted)\n", sq_names[s], sq_cov.columns(s, false).c_str(),
                "");
  printClaimed();
  return 0;
}

// The one sphere under a spindle head: a B head over a C table
// (examples/machines/bc_head_table.json) or an A head carrying a B head (ab_head.json). Every
// machine draws the separable location errors of its axes and the pivot-to-ball length's deviation
// (`drawn`: 20 um / 2 mdeg), the sphere's set-up (50 um; the 5 held directions' own parameters stay
// 0, so that the truth is what the fit reports), and every declared contributor that acts on one
// sphere (drawProbeAxes on the exact simulator, whose head carries the model's true chain), and is
// analyzed as `analyze` does (identifySphereCycle + sphereBudget, 1000 Monte Carlo runs).
int headCoverage(const std::string& machine_file, const std::vector<std::string>& drawn, int machines,
                 const std::string& contributors_file, const std::string& plan_options) {
  MachineModel machine = loadMachine(machine_file);
  const ContributorSet cs = loadContributors(contributors_file);
  // The head machines declare no contributors: the ones the machines are drawn from are what a
  // design for them (design=A) weighs.
  if (!machine.contributors) machine.contributors = cs;
  const ProbePlan plan = oneSpherePlan(machine, plan_options);
  const double touch_mm2 = perTouchVariance_mm2(cs, isPerTouchContributor);
  const SphereLayout layout = sphereLayoutOf(plan);
  const KinematicModel model = sphereModel(machine, Eigen::Vector3d::Zero());
  const double sphere_um = 50.0;
  Coverage cov(drawn.size());
  int done = 0;
  for (int m = 0; m < machines; ++m) {
    Rng rng(1919, static_cast<std::uint64_t>(m));
    Eigen::VectorXd p = Eigen::VectorXd::Zero(model.size());
    std::vector<double> truth_report(drawn.size());
    for (size_t i = 0; i < drawn.size(); ++i) {
      const int k = model.parameterIndex(drawn[i]);
      const bool length = model.parameters[static_cast<size_t>(k)].kind == ParamKind::Length;
      const double sd = drawn[i].back() == 'S' ? sphere_um : (length ? kTruthSdUm : kTruthSdMdeg);
      truth_report[i] = sd * rng.normal();
      p[k] = length ? umToMm(truth_report[i]) : mdegToRad(truth_report[i]);
    }
    Truth t = truthOfModel(model, p);
    t.errors.kinematics = machine.kinematics;
    SphereCycleResult r;
    const auto b_or = drawnSphereMachine(plan, cs, t, m, 1919, 0x4854000000ULL, &r);
    if (!b_or) continue;
    const UncertaintyBudget& b = *b_or;
    const Eigen::VectorXd uc = b.uC(), ua = b.uA(), U = b.expanded();
    for (size_t i = 0; i < drawn.size(); ++i) {
      int q = -1;
      for (int k = 0; k < b.size(); ++k)
        if (b.names[static_cast<size_t>(k)] == drawn[i]) q = k;
      const int x = r.model.parameterIndex(drawn[i]);
      if (q < 0 || x < 0) continue;
      const double v = r.x[x];
      const double est = r.model.parameters[static_cast<size_t>(x)].kind == ParamKind::Length ? mmToUm(v) : radToMdeg(v);
      cov.add(i, std::abs(est - truth_report[i]), U[q], uc[q], ua[q]);
    }
    countMachine(done);
  }
  std::printf("one_sphere on %s (L %.0f mm, sphere at %.0f, %.0f, %.0f mm): %d machines drawn from %s (location "
              "errors sd %.0f um / %.0f mdeg, sphere %.0f um, per-touch scatter %.3f um)\n",
              machine.name.c_str(), machine.head->pivot_to_ball_mm, layout.center_w_mm.x(), layout.center_w_mm.y(), layout.center_w_mm.z(), done,
              cs.file.c_str(), kTruthSdUm, kTruthSdMdeg, sphere_um, mmToUm(std::sqrt(touch_mm2)));
  std::printf("%s\n", coverageHeader(8).c_str());
  for (size_t i = 0; i < drawn.size(); ++i) {
    const bool length = model.parameters[static_cast<size_t>(model.parameterIndex(drawn[i]))].kind == ParamKind::Length;
    std::printf("%s\n", cov.row(drawn[i], i, length ? "  um" : "  mdeg").c_str());
  }
  printClaimed();
  return 0;
}

int main(int argc, char** argv) {
  // The one-sphere cycle's head machines and the parameters each machine draws.
  const struct {
    const char* bench;
    const char* machine;
    std::vector<std::string> drawn;
  } heads[] = {{"one_sphere_head", "/examples/machines/bc_head_table.json",
                {"X0C", "Y0C", "A0C", "B0C", "A0B", "C0B", "B0B", "dL", "dX_S", "dY_S", "dZ_S"}},
               {"one_sphere_head_ab", "/examples/machines/ab_head.json",
                {"B0A", "C0A", "A0A", "Z0B", "C0B", "B0B", "dY_T", "dL", "dX_S", "dY_S", "dZ_S"}}};
  for (const auto& h : heads)
    if (argc > 1 && std::string(argv[1]) == h.bench)
      return headCoverage(std::string(ROTACAL_SOURCE_DIR) + h.machine, h.drawn, argc > 2 ? std::atoi(argv[2]) : 500,
                          argc > 3 ? argv[3] : ROTACAL_SOURCE_DIR "/examples/contributors/table5.json",
                          argc > 4 ? argv[4] : "");
  if (argc > 1 && std::string(argv[1]) == "one_sphere")
    return oneSphereCoverage(argc > 2 ? std::atoi(argv[2]) : 500,
                             argc > 3 ? argv[3] : ROTACAL_SOURCE_DIR "/examples/contributors/table5.json",
                             argc > 4 ? argv[4] : "");
  if (argc > 1 && std::string(argv[1]) == "spheres3")
    return spheres3Coverage(argc > 2 ? std::atoi(argv[2]) : 500,
                            argc > 3 ? argv[3] : ROTACAL_SOURCE_DIR "/examples/contributors/spheres3_001.json");
  if (argc > 1 && std::string(argv[1]) == "spaceframe")
    return spaceframeCoverage(argc > 2 ? std::atoi(argv[2]) : 500, argc > 3 ? std::atof(argv[3]) : 1.0);
  if (argc > 1 && std::string(argv[1]) == "rtest") return rtestCoverage(argc > 2 ? std::atoi(argv[2]) : 500);
  if (argc > 1 && std::string(argv[1]) == "tooltip") return tooltipCoverage(argc > 2 ? std::atoi(argv[2]) : 500);
  const int machines = argc > 1 ? std::atoi(argv[1]) : 500;
  const std::string method_name = argc > 2 ? argv[2] : "lsq_per_point";
  const Method method = methodFromName(method_name);
  const MachineModel machine = loadMachine(ROTACAL_SOURCE_DIR "/examples/machines/ac_trunnion.json");
  const ProbePlan plan = makePlan("touch154", machine, {});
  // A third argument replaces the machine's contributors (lsq_rigid_setup presumes a piece of
  // perfect form: docs/uncertainty.md runs it with Table 5 less form_error).
  const ContributorSet contributors = argc > 3 ? loadContributors(argv[3]) : *machine.contributors;
  const DrawModel all = drawModel(contributors);
  const LinearChain chain0 = lineariseChain(plan, LocationErrors{});  // the draw's node span only
  const auto& params = locationParameters(machine.kinematics);
  // True location errors: 000 Table 4's size (tens of um, a fraction of a mdeg) drawn anew for
  // every machine, so the chain is never linearised at the truth.

  Coverage cov(kNumLocationErrors);
  MeanCoverageFactor mean_k;
  double ratio_sum[kNumLocationErrors] = {};
  int done = 0;
  for (int m = 0; m < machines; ++m) {
    Rng rng(777, static_cast<std::uint64_t>(m));
    const LocationErrors truth = drawLocationErrors(machine.kinematics, rng);
    RunDraw d;
    drawRun(all, chain0, 4242, m, &d);
    MeasurementRun run = simulate(plan, truthOfDraw(truth, d), {1});
    for (size_t p = 0; p < plan.points.size(); ++p)
      run.points[p].position_m_mm += (d.repeat_mm[static_cast<long>(p)] - d.rough_mm[static_cast<long>(p)]) * plan.points[p].approach_m;
    IdentificationOptions o;
    o.method = method;
    o.prior_sigma_um = machine.probe.repeatability_um;
    const IdentificationResult r = identifyTouch154(plan, {run}, o);
    if (r.summary.termination != Termination::Converged) continue;
    Touch154BudgetOptions bo;
    bo.alone_runs = 0;
    bo.seed = 0x4d43000000ULL + static_cast<std::uint64_t>(m);  // each machine its own Monte Carlo draws
    const UncertaintyBudget b = touch154Budget(plan, r, {}, &contributors, bo);
    const Eigen::VectorXd uc = b.uC(), U = b.expanded();
    mean_k.add(b);
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const double err = std::abs(r.estimate.reportValue(i) - truth.reportValue(i));
      cov.add(i, err, U[i], uc[i], b.uA()[i]);
      ratio_sum[i] += err / uc[i];
    }
    countMachine(done);
  }
  std::printf("touch154 %s: %d machines drawn from %s (true errors sd %.0f um / %.0f mdeg)\n", method_name.c_str(), done,
              contributors.file.c_str(), kTruthSdUm, kTruthSdMdeg);
  std::printf("%s %14s\n", coverageHeader(8).c_str(), "mean |e|/u_c");
  for (int i = 0; i < kNumLocationErrors; ++i)
    std::printf("%s %14.2f  %s\n", cov.row(std::string(params[i].name), i, "").c_str(), ratio_sum[i] / done,
                std::string(reportUnit(params[i].kind)).c_str());
  mean_k.print();
  printClaimed();
  return 0;
}
