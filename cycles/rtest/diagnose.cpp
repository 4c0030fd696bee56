#include "cycles/rtest/diagnose.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/units.hpp"

namespace rotacal {

void RtestDiagnosisOptions::validate() const {
  if (!(alpha > 0 && alpha < 0.5)) throw std::invalid_argument("alpha must be in (0, 0.5)");
  if (!(min_holdout_gain >= 0 && min_holdout_gain < 1)) throw std::invalid_argument("min_holdout_gain must be in [0, 1)");
  if (!(sensor_sigma_um > 0)) throw std::invalid_argument("sensor_sigma_um must be > 0");
}

namespace {

/// 002 Eq. (6) over several cycles at once: readings = (J_j - J_ref) omega [+ J_j tau omega_dot],
/// tau = hours since the reset; dz and c at tilt 0 held at 0 (first-cycle convention).
struct JointModel {
  const ProbePlan* plan;
  std::vector<Eigen::Matrix<double, 3, kRtestParams>> J;
  std::vector<int> tilt_of;
  int ref = 0, ref_tilt = 0, nt = 0;
  double t_ref_s = 0.0;
  bool drift = false;
  std::vector<int> cols;

  int fullCols() const { return kRtestParams * nt * (drift ? 2 : 1); }
  void rows(const RtestCycle& c, Eigen::MatrixXd& A, Eigen::VectorXd& y, int at) const {
    const int nb = kRtestParams * nt;
    for (size_t j = 0; j < c.readings.size(); ++j) {
      const int r = at + 3 * static_cast<int>(j);
      const int ti = tilt_of[j];
      const double tau = (c.readings[j].t_s - t_ref_s) / 3600.0;
      A.block(r, kRtestParams * ti, 3, kRtestParams) += J[j];
      A.block(r, kRtestParams * ref_tilt, 3, kRtestParams) -= J[ref];
      if (drift) A.block(r, nb + kRtestParams * ti, 3, kRtestParams) += tau * J[j];
      y.segment<3>(r) = c.readings[j].dq_w_mm;
    }
  }
  /// Fit on the cycles except `skip` (-1: none); returns the full parameter vector.
  Eigen::VectorXd fit(const std::vector<RtestCycle>& cycles, int skip) const {
    const int per = 3 * static_cast<int>(plan->points.size());
    const int m = per * (static_cast<int>(cycles.size()) - (skip >= 0 ? 1 : 0));
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, fullCols());
    Eigen::VectorXd y(m);
    int at = 0;
    for (int k = 0; k < static_cast<int>(cycles.size()); ++k) {
      if (k == skip) continue;
      rows(cycles[k], A, y, at);
      at += per;
    }
    Eigen::MatrixXd Au(m, cols.size());
    Eigen::VectorXd scale(cols.size());
    for (size_t q = 0; q < cols.size(); ++q) {
      Au.col(q) = A.col(cols[q]);
      scale[q] = std::max(Au.col(q).norm(), 1e-300);
    }
    const Eigen::VectorXd xs = (Au * scale.cwiseInverse().asDiagonal()).colPivHouseholderQr().solve(y);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(fullCols());
    for (size_t q = 0; q < cols.size(); ++q) x[cols[q]] = xs[q] / scale[q];
    return x;
  }
  double rss(const RtestCycle& c, const Eigen::VectorXd& x) const {
    const int per = 3 * static_cast<int>(plan->points.size());
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(per, fullCols());
    Eigen::VectorXd y(per);
    rows(c, A, y, 0);
    return (y - A * x).squaredNorm();
  }
};

}  // namespace

RtestDiagnosis diagnoseRtest(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestDiagnosisOptions& o) {
  o.validate();
  RtestDiagnosis d;
  RtestFitOptions fo;
  fo.sensor_sigma_um = o.sensor_sigma_um;
  d.analysis = analyzeRtest(plan, cycles, fo);
  d.cycles = static_cast<int>(cycles.size());
  const Kinematics k = plan.machine.kinematics;
  const int nt = static_cast<int>(d.analysis.tilt_deg.size());

  JointModel base;
  base.plan = &plan;
  for (const auto& p : plan.points) {
    base.J.push_back(J_wq_omega(k, p.pose, rtestNest_w(plan)));
    const double t = tiltOf(k, p.pose);
    base.tilt_of.push_back(static_cast<int>(std::find(d.analysis.tilt_deg.begin(), d.analysis.tilt_deg.end(), t) -
                                            d.analysis.tilt_deg.begin()));
  }
  base.ref = rtestReferencePoint(plan) - 1;
  base.ref_tilt = base.tilt_of[base.ref];
  base.nt = nt;
  base.t_ref_s = cycles.front().readings[base.ref].t_s;
  JointModel drift = base;
  drift.drift = true;
  const int fixed_dz = kRtestParams * base.ref_tilt + 2, fixed_c = kRtestParams * base.ref_tilt + 5;
  for (int q = 0; q < base.fullCols(); ++q)
    if (q != fixed_dz && q != fixed_c) base.cols.push_back(q);
  for (int q = 0; q < drift.fullCols(); ++q)
    if (q != fixed_dz && q != fixed_c) drift.cols.push_back(q);

  const double n_read = 3.0 * static_cast<double>(plan.points.size()) * d.cycles;
  auto rmsAll = [&](const JointModel& jm) {
    const Eigen::VectorXd x = jm.fit(cycles, -1);
    double s = 0;
    for (const auto& c : cycles) s += jm.rss(c, x);
    return mmToUm(std::sqrt(s / n_read));
  };
  auto holdout = [&](const JointModel& jm) {
    double s = 0;
    for (int kk = 0; kk < d.cycles; ++kk) s += jm.rss(cycles[kk], jm.fit(cycles, kk));
    return mmToUm(std::sqrt(s / n_read));
  };
  d.baseline_rms_um = rmsAll(base);
  if (d.cycles < 4) {
    d.reason = fmt::format("{} cycle(s): a drift needs at least 4 to be told from scatter", d.cycles);
    d.baseline_holdout_rms_um = d.cycles > 1 ? holdout(base) : 0.0;
    return d;
  }
  d.baseline_holdout_rms_um = holdout(base);
  d.drift_rms_um = rmsAll(drift);
  d.drift_holdout_rms_um = holdout(drift);
  d.gain_pct = 100.0 * (1.0 - d.drift_holdout_rms_um / d.baseline_holdout_rms_um);

  // Slope tests: the per-cycle estimates' trend (rate_u already widened by the scatter).
  const double nu = static_cast<double>(d.cycles) - 2.0;
  const int n_tests = kRtestParams * nt;
  int significant = 0;
  for (int i = 0; i < nt; ++i)
    for (int p = 0; p < kRtestParams; ++p) {
      RtestDriftTest t;
      t.param = p;
      t.tilt = i;
      t.rate = d.analysis.rate(p, i);
      t.u = d.analysis.rate_u(p, i);
      if (!(t.u > 0)) continue;
      t.t = t.rate / t.u;
      t.p_value = studentTwoSided(t.t, nu);
      t.significant = t.p_value < o.alpha / n_tests;
      significant += t.significant;
      d.tests.push_back(t);
    }
  const bool gain = d.gain_pct >= 100.0 * o.min_holdout_gain;
  d.drift_found = significant > 0 && gain;
  if (!d.drift_found)
    d.reason = significant == 0 ? fmt::format("no slope passes the t test at alpha = {:g} (Bonferroni over {})", o.alpha,
                                              n_tests)
                                : fmt::format("slopes pass the t test but the held-out gain is {:.1f} %", d.gain_pct);
  return d;
}

namespace {
double rep(int p, double v) { return p < 3 ? mmToUm(v) : radToMdeg(v); }
std::string unit(int p) { return p < 3 ? "um" : "mdeg"; }
}  // namespace

Json rtestDiagnosisJson(const ProbePlan& plan, const RtestDiagnosis& d) {
  const Kinematics k = plan.machine.kinematics;
  const char ax = tiltAxis(k);
  Json j;
  j["format"] = "rotacal-diagnosis/1";
  j["cycle"] = "rtest";
  j["cycles"] = d.cycles;
  j["baseline"] = {{"model", "002 Table 2 errors at each tilt, constant over the series (Eq. (6) over all cycles)"},
                   {"residual_rms_um", d.baseline_rms_um},
                   {"holdout_rms_um", d.baseline_holdout_rms_um}};
  j["holdout_scheme"] = "leave one cycle out";
  j["verdict"] = d.drift_found ? "effect_found" : "no_significant_effect";
  if (!d.drift_found) j["reason"] = d.reason;
  Json tests = Json::array();
  for (const auto& t : d.tests)
    tests.push_back({{"parameter", fmt::format("{}({}={:g})", rtestParameterName(k, t.param), ax, d.analysis.tilt_deg[t.tilt])},
                     {"rate", rep(t.param, t.rate) * 3600.0},
                     {"u", rep(t.param, t.u) * 3600.0},
                     {"unit", unit(t.param) + "/h"},
                     {"t", t.t},
                     {"p_value", t.p_value},
                     {"significant", t.significant}});
  j["drift_tests"] = tests;
  Json findings = Json::array();
  if (d.drift_found) {
    Json params = Json::object();
    const RtestDriftTest* top = nullptr;
    for (const auto& t : d.tests) {
      if (!t.significant) continue;
      params[fmt::format("{}({}={:g})/h", rtestParameterName(k, t.param), ax, d.analysis.tilt_deg[t.tilt])] = {
          {"value", rep(t.param, t.rate) * 3600.0}, {"unit", unit(t.param) + "/h"}, {"u", rep(t.param, t.u) * 3600.0}};
      if (!top || std::abs(t.t) > std::abs(top->t)) top = &t;
    }
    // The errors re-estimated at each cycle's time are the per-cycle estimates of analyze.
    Json le = Json::object();
    const auto& last = d.analysis.cycles.back();
    for (int p = 0; p < kRtestParams; ++p) {
      std::vector<double> v, u;
      for (size_t i = 0; i < d.analysis.tilt_deg.size(); ++i) {
        v.push_back(rep(p, last.value(p, static_cast<int>(i))));
        u.push_back(rep(p, last.u(p, static_cast<int>(i))));
      }
      le[rtestParameterName(k, p)] = {{"unit", unit(p)}, {"values", v}, {"u", u},
                                      {"note", fmt::format("at the last cycle, t = {:.2f} h, per {} angle", last.t_s / 3600.0, ax)}};
    }
    findings.push_back(
        {{"cause", "thermal_drift"},
         {"variant", "linear"},
         {"summary", fmt::format("the rotary table's errors change with time: {} at {} = {:g} deg moves {:.2f} {}/h "
                                 "(t = {:.1f}); over the series {:.2f} {}",
                                 rtestParameterName(k, top->param), ax, d.analysis.tilt_deg[top->tilt],
                                 rep(top->param, top->rate) * 3600.0, unit(top->param), top->t,
                                 rep(top->param, d.analysis.change(top->param, top->tilt)), unit(top->param))},
         {"parameters", params},
         {"location_errors", le},
         {"residual_rms_um", d.drift_rms_um},
         {"holdout_rms_um", d.drift_holdout_rms_um},
         {"gain_pct", d.gain_pct}});
  }
  j["findings"] = findings;
  j["confounded"] = Json::array(
      {{{"causes", {"thermal_drift", "spindle_thermal_growth"}},
        {"why", fmt::format("the R-test sees the sphere against the nest only (002 Sec. 4.3): an axial growth of the "
                            "spindle moves the sphere like a uniform -{} drift of the table at every tilt",
                            rtestParameterName(k, 2))},
        {"separate_with", "a second R-test series with a longer or shorter sphere holder, or a spindle-growth sensor: "
                          "a spindle growth scales with neither"}}});
  if (d.cycles >= 4) {
    Json figs = Json::array();
    for (int p = 0; p < kRtestParams; ++p) {
      Json s = Json::array();
      std::vector<double> x, y, u;
      for (size_t i = 0; i < d.analysis.tilt_deg.size(); ++i) {
        x.push_back(d.analysis.tilt_deg[i]);
        y.push_back(rep(p, d.analysis.rate(p, static_cast<int>(i))) * 3600.0);
        u.push_back(rep(p, d.analysis.rate_u(p, static_cast<int>(i))) * 3600.0);
      }
      s.push_back({{"name", rtestParameterName(k, p) + "/h"}, {"style", "points"}, {"x", x}, {"y", y}, {"u", u}});
      std::string id = "rtest_drift_rate_" + rtestParameterName(k, p);
      for (auto& ch : id) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      figs.push_back({{"id", id},
                      {"title", fmt::format("Drift rate of {} at each {} angle", rtestParameterName(k, p), ax)},
                      {"x", {{"label", std::string(1, ax)}, {"unit", "deg"}}},
                      {"y", {{"label", "rate"}, {"unit", unit(p) + "/h"}}},
                      {"series", s},
                      {"note", "zero within the error bars: no drift of this error"}});
    }
    j["figures"] = figs;
  }
  return j;
}

std::string rtestDiagnosisText(const ProbePlan& plan, const RtestDiagnosis& d) {
  const Kinematics k = plan.machine.kinematics;
  std::string s = fmt::format("rotacal diagnose rtest: {} cycles\n", d.cycles);
  s += fmt::format("baseline (constant errors): residual {:.3f} um rms, held-out {:.3f} um rms\n", d.baseline_rms_um,
                   d.baseline_holdout_rms_um);
  if (d.cycles >= 4)
    s += fmt::format("with linear drift: residual {:.3f} um rms, held-out {:.3f} um rms, gain {:.1f} %\n", d.drift_rms_um,
                     d.drift_holdout_rms_um, d.gain_pct);
  if (!d.drift_found) return s + "verdict: no significant effect (" + d.reason + ")\n";
  s += "verdict: thermal_drift\n";
  for (const auto& t : d.tests)
    if (t.significant)
      s += fmt::format("  {}({}={:g}): {:.3f} +- {:.3f} {}/h (t = {:.1f})\n", rtestParameterName(k, t.param), tiltAxis(k),
                       d.analysis.tilt_deg[t.tilt], rep(t.param, t.rate) * 3600.0, rep(t.param, t.u) * 3600.0,
                       unit(t.param), t.t);
  return s;
}

}  // namespace rotacal
