#include "core/diagnosis.hpp"
#include "core/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

#include "core/causes.hpp"
#include "core/report_envelope.hpp"
#include "core/units.hpp"

namespace rotacal {

bool DiagnosisOptions::validate(std::string* why) const {
  auto fail = [&](const char* w) {
    if (why) *why = w;
    return false;
  };
  if (!(alpha > 0 && alpha < 0.5)) return fail("alpha must be in (0, 0.5)");
  if (!(min_holdout_gain >= 0 && min_holdout_gain < 1)) return fail("min_holdout_gain must be in [0, 1)");
  if (!(holdout_sigmas >= 0)) return fail("holdout_sigmas must be >= 0");
  if (max_causes < 1) return fail("max_causes must be >= 1");
  if (!(prior_sigma_um > 0)) return fail("prior_sigma_um must be > 0");
  return true;
}

namespace {

struct Model {
  std::vector<ExtensionPtr> ext;
  IdentificationResult full;
  double holdout_rms_um = 0.0;
  int holdout_n = 0;
  bool ok = false;
};

IdentificationOptions lsqOptions(const DiagnosisOptions& o, const std::vector<ExtensionPtr>& ext) {
  IdentificationOptions io;
  io.method = Method::LeastSquaresPerPoint;
  io.prior_sigma_um = o.prior_sigma_um;
  io.extensions = ext;
  return io;
}

std::vector<std::string> holdoutPoses(const ProbePlan& plan) {
  std::vector<std::string> f;
  for (size_t i = 1; i < plan.poses.size(); ++i) f.push_back(plan.poses[i].name);
  return f;
}

/// Leave-one-pose-out: fit without the pose, predict it; pooled over the folds.
void holdout(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const DiagnosisOptions& o, Model* m,
             const std::set<std::string>& skip_folds) {
  double ss = 0.0;
  int n = 0;
  for (const auto& pose : holdoutPoses(plan)) {
    if (skip_folds.count(pose)) continue;
    IdentificationOptions io = lsqOptions(o, m->ext);
    io.hold_out = [pose](int, const ProbePoint& p) { return p.pose_name == pose; };
    const auto r = identify(plan, runs, io);
    if (r.summary.termination != Termination::Converged) continue;
    ss += r.holdout_rms_um * r.holdout_rms_um * r.holdout_points;
    n += r.holdout_points;
  }
  m->holdout_n = n;
  m->holdout_rms_um = n ? std::sqrt(ss / n) : 0.0;
}

/// Folds in which the baseline itself cannot be fitted are skipped for every model.
std::set<std::string> badFolds(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const DiagnosisOptions& o) {
  std::set<std::string> bad;
  for (const auto& pose : holdoutPoses(plan)) {
    IdentificationOptions io = lsqOptions(o, {});
    io.hold_out = [pose](int, const ProbePoint& p) { return p.pose_name == pose; };
    if (identify(plan, runs, io).summary.termination != Termination::Converged) bad.insert(pose);
  }
  return bad;
}

std::string directionName(const Eigen::Vector3d& u) {
  int axis = 0;
  u.cwiseAbs().maxCoeff(&axis);
  return fmt::format("{}{}", u[axis] > 0 ? '+' : '-', "XYZ"[axis]);
}

std::vector<FactorStatistic> residualAnalysis(const ProbePlan& plan, const IdentificationResult& base, double sigma_um,
                                              int runs, double alpha) {
  std::vector<FactorStatistic> out;
  std::vector<const PointResidual*> res;
  for (const auto& r : base.residuals)
    if (!r.held_out) res.push_back(&r);
  if (res.empty()) return out;
  const double m = static_cast<double>(res.size());
  // Residuals of a fit have variance sigma^2 dof / m on average.
  const double s_eff = sigma_um * std::sqrt(std::max(1, base.summary.dof) / m);
  auto categorical = [&](const std::string& name, auto key_of) {
    std::map<std::string, std::pair<double, int>> g;
    for (const auto* r : res) {
      auto& e = g[key_of(*r)];
      e.first += r->residual_um;
      ++e.second;
    }
    if (g.size() < 2) return;
    FactorStatistic f;
    f.factor = name;
    double worst = 0;
    for (const auto& [k, v] : g) {
      const double mean = v.first / v.second;
      f.chi2 += v.second * mean * mean / (s_eff * s_eff);
      if (std::abs(mean) >= std::abs(worst)) {
        worst = mean;
        f.detail = fmt::format("largest group mean {:+.3f} um at {} = {} ({} points)", mean, name, k, v.second);
      }
    }
    f.dof = static_cast<int>(g.size()) - 1;
    out.push_back(f);
  };
  auto continuous = [&](const std::string& name, const std::string& unit, double scale, auto x_of) {
    double mx = 0, my = 0;
    for (const auto* r : res) { mx += x_of(*r); my += r->residual_um; }
    mx /= m;
    my /= m;
    double sxx = 0, sxy = 0;
    for (const auto* r : res) {
      sxx += (x_of(*r) - mx) * (x_of(*r) - mx);
      sxy += (x_of(*r) - mx) * (r->residual_um - my);
    }
    if (sxx <= 1e-12) return;
    FactorStatistic f;
    f.factor = name;
    const double b = sxy / sxx, se = s_eff / std::sqrt(sxx);
    f.chi2 = (b / se) * (b / se);
    f.dof = 1;
    f.detail = fmt::format("slope {:+.4f} um per {} (standard error {:.4f})", b * scale, unit, se * scale);
    out.push_back(f);
  };
  auto point = [&](const PointResidual& r) { return plan.findPoint(r.point_id); };
  continuous("time", "h", 1.0, [](const PointResidual& r) { return r.t_h; });
  if (runs > 1) categorical("repeat", [](const PointResidual& r) { return std::to_string(r.run + 1); });
  categorical("pose", [&](const PointResidual& r) { return point(r)->pose_name; });
  categorical("approach", [&](const PointResidual& r) { return directionName(point(r)->approach_m); });
  categorical("face", [&](const PointResidual& r) { return std::string(faceName(point(r)->face)); });
  for (int ax = 0; ax < 3; ++ax)
    continuous(std::string(1, "XYZ"[ax]), "100 mm", 100.0,
               [&, ax](const PointResidual& r) { return point(r)->trigger_m_mm[ax]; });
  const double thr = alpha / static_cast<double>(out.size());
  for (auto& f : out) {
    f.p_value = chiSquareSurvival(f.chi2, f.dof);
    f.structured = f.p_value < thr;
  }
  return out;
}

std::string paramsSentence(const Finding& f) {
  std::string s;
  for (const auto& p : f.parameters)
    s += (s.empty() ? "" : ", ") + fmt::format("{} = {:.3g} +- {:.2g} {}", p.name, p.value, p.u, p.unit);
  return s;
}

}  // namespace

Diagnosis diagnose(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const DiagnosisOptions& options) {
  Diagnosis d;
  d.holdout_scheme = "leave one pose out (poses after the reference pose), pooled over the folds";
  const auto cands = options.candidates.empty() ? catalogFor(plan, static_cast<int>(runs.size())) : options.candidates;

  Model base;
  base.full = identify(plan, runs, lsqOptions(options, {}));
  d.baseline = base.full;
  if (base.full.summary.termination != Termination::Converged) return d;
  const auto skip = badFolds(plan, runs, options);
  holdout(plan, runs, options, &base, skip);
  d.baseline_holdout_rms_um = base.holdout_rms_um;
  d.sigma_um = std::max(options.prior_sigma_um, base.full.summary.sigma_um);

  // Mean time of each repeat.
  {
    std::map<int, std::pair<double, int>> t;
    for (const auto& r : base.full.residuals) {
      t[r.run].first += r.t_h;
      ++t[r.run].second;
    }
    for (const auto& [run, v] : t) d.repeat_times_h.push_back(v.first / v.second);
  }
  d.residual_analysis = residualAnalysis(plan, base.full, d.sigma_um, static_cast<int>(runs.size()), options.alpha);

  Model current = base;
  std::set<std::string> used_causes;
  const double m = base.full.summary.observations;
  for (int step = 0; step < options.max_causes; ++step) {
    std::vector<Model> trials;
    std::vector<size_t> trial_cand;
    for (size_t c = 0; c < cands.size(); ++c) {
      if (options.progress)
        options.progress(step * static_cast<int>(cands.size()) + static_cast<int>(c),
                         options.max_causes * static_cast<int>(cands.size()));
      if (used_causes.count(cands[c]->cause())) continue;
      Model t;
      t.ext = current.ext;
      t.ext.push_back(cands[c]);
      t.full = identify(plan, runs, lsqOptions(options, t.ext));
      CandidateScore sc;
      sc.cause = cands[c]->cause();
      sc.variant = cands[c]->variant();
      sc.parameters = static_cast<int>(cands[c]->parameters().size());
      if (t.full.summary.termination == Termination::RankDeficient) {
        std::vector<std::string> with;
        for (const auto& n : t.full.unidentifiable) {
          bool own = false;
          for (const auto& p : cands[c]->parameters()) own = own || p.name == n;
          if (!own) with.push_back(n);
        }
        sc.verdict = "not identifiable with this plan (confounded with " +
                     (with.empty() ? std::string("itself") : fmt::format("{}", fmt::join(with, ", "))) + ")";
        if (step == 0) {
          Confounded cf;
          cf.causes = {sc.cause};
          for (const auto& w : with) cf.causes.push_back(w);
          cf.why = "the plan moves every trigger alike for " + sc.cause + " and " + fmt::format("{}", fmt::join(with, ", ")) +
                   " (their Jacobian columns are parallel: the fit is rank deficient)";
          cf.separate_with = separationHint(sc.cause, with);
          d.confounded.push_back(cf);
        }
        if (step == 0) d.candidates.push_back(sc);
        continue;
      }
      if (step == 0 && t.full.summary.termination == Termination::Converged && t.full.extension_correlation.size()) {
        // Nearly parallel columns: the plan can hardly tell this cause from a location error.
        const long off = t.full.extension_correlation.rows() - static_cast<long>(cands[c]->parameters().size());
        std::set<std::string> with;
        double worst = 0.0;
        for (long a = off; a < t.full.extension_correlation.rows(); ++a)
          for (int b = 0; b < kNumLocationErrors; ++b) {
            const double r = std::abs(t.full.extension_correlation(a, b));
            worst = std::max(worst, r);
            if (r > options.max_correlation) with.insert(std::string(locationParameters(plan.machine.kinematics)[b].name));
          }
        if (!with.empty()) {
          std::vector<std::string> w(with.begin(), with.end());
          Confounded cf;
          cf.causes = {sc.cause};
          for (const auto& n : w) cf.causes.push_back(n);
          cf.why = fmt::format("with this plan {} is nearly indistinguishable from {} (correlation up to {:.3f}: the "
                               "Jacobian columns are {:.1f} deg apart); an effect of this cause would be read as "
                               "location errors",
                               sc.cause, fmt::join(w, ", "), worst, radToDeg(std::acos(std::min(1.0, worst))));
          cf.separate_with = separationHint(sc.cause, w);
          d.confounded.push_back(cf);
        }
      }
      if (t.full.summary.termination != Termination::Converged) {
        sc.verdict = "fit failed: " + t.full.summary.message;
        if (step == 0) d.candidates.push_back(sc);
        continue;
      }
      const double rss_cur = 2.0 * current.full.summary.cost * kUmPerMm * kUmPerMm;  // um^2
      const double rss_new = 2.0 * t.full.summary.cost * kUmPerMm * kUmPerMm;
      const double sigma = std::max(options.prior_sigma_um, t.full.summary.sigma_um);
      sc.residual_rms_um = t.full.summary.residual_rms_um;
      sc.chi2 = (rss_cur - rss_new) / (sigma * sigma);
      sc.p_value = chiSquareSurvival(sc.chi2, sc.parameters);
      sc.bic = m * std::log(rss_new / m) + t.full.summary.parameters * std::log(m);
      holdout(plan, runs, options, &t, skip);
      sc.holdout_rms_um = t.holdout_rms_um;
      const double needed = std::max(options.min_holdout_gain,
                                     options.holdout_sigmas / std::sqrt(2.0 * std::max(1, t.holdout_n)));
      const double gain = current.holdout_rms_um > 0 ? 1.0 - t.holdout_rms_um / current.holdout_rms_um : 0.0;
      const double p_thr = options.alpha / static_cast<double>(cands.size());
      if (sc.p_value >= p_thr)
        sc.verdict = fmt::format("residual drop within noise (chi2 {:.1f} on {} dof, p {:.2g} >= {:.2g})", sc.chi2,
                                 sc.parameters, sc.p_value, p_thr);
      else if (gain < needed)
        sc.verdict = fmt::format("held-out gain {:.1f} % below the {:.1f} % the noise allows", 100 * gain, 100 * needed);
      else {
        sc.verdict = "accepted";
        t.ok = true;
      }
      if (step == 0 || t.ok) d.candidates.push_back(sc);
      trials.push_back(t);
      trial_cand.push_back(c);
    }
    int best = -1;
    for (size_t i = 0; i < trials.size(); ++i)
      if (trials[i].ok && (best < 0 || trials[i].holdout_rms_um < trials[static_cast<size_t>(best)].holdout_rms_um))
        best = static_cast<int>(i);
    if (best < 0) break;
    Model& w = trials[static_cast<size_t>(best)];
    const ExtensionPtr& x = cands[trial_cand[static_cast<size_t>(best)]];
    for (auto& sc : d.candidates)
      if (sc.verdict == "accepted" && !(sc.cause == x->cause() && sc.variant == x->variant()))
        sc.verdict = "significant, but another variant or cause predicts held-out data better";
    Finding f;
    f.cause = x->cause();
    f.variant = x->variant();
    f.fit = w.full;
    f.residual_rms_um = w.full.summary.residual_rms_um;
    f.holdout_rms_um = w.holdout_rms_um;
    f.gain_pct = base.holdout_rms_um > 0 ? 100.0 * (1.0 - w.holdout_rms_um / base.holdout_rms_um) : 0.0;
    const auto params = x->parameters();
    const long off = w.full.extension_values.size() - static_cast<long>(params.size());
    Eigen::VectorXd pv = w.full.extension_values.segment(off, static_cast<long>(params.size()));
    for (size_t i = 0; i < params.size(); ++i)
      f.parameters.push_back({params[i].name, params[i].unit, pv[static_cast<long>(i)] * params[i].to_report,
                              w.full.extension_u[off + static_cast<long>(i)] * params[i].to_report});
    if (f.cause == "thermal_drift") {
      for (size_t r = 0; r < d.repeat_times_h.size(); ++r) {
        ObservationContext ctx{nullptr, static_cast<int>(r), d.repeat_times_h[r]};
        f.per_repeat.emplace_back(d.repeat_times_h[r], x->errorsAt(pv, ctx, w.full.estimate));
      }
    }
    f.summary = fmt::format("{} ({}): {}; held-out residual {:.3f} -> {:.3f} um ({:+.0f} %)", x->describe(), x->variant(),
                            paramsSentence(f), base.holdout_rms_um, w.holdout_rms_um, -f.gain_pct);
    d.findings.push_back(f);
    used_causes.insert(x->cause());
    current = w;
  }
  return d;
}

Json diagnosisToJson(const Diagnosis& d) {
  Json j;
  j["format"] = "rotacal-diagnosis/1";
  j["baseline"] = {{"model", "location errors + one surface offset per target point (lsq_per_point)"},
                   {"residual_rms_um", d.baseline.summary.residual_rms_um},
                   {"holdout_rms_um", d.baseline_holdout_rms_um},
                   {"location_errors", locationErrorsJson(d.baseline.estimate, d.baseline.u)}};
  j["holdout"] = d.holdout_scheme;
  j["sigma_um"] = d.sigma_um;
  j["verdict"] = d.effectFound() ? "effect_found" : "no_significant_effect";
  Json ra = Json::array();
  for (const auto& f : d.residual_analysis)
    ra.push_back({{"factor", f.factor}, {"detail", f.detail}, {"chi2", f.chi2}, {"dof", f.dof}, {"p", f.p_value},
                  {"structured", f.structured}});
  j["residual_analysis"] = ra;
  Json findings = Json::array();
  for (const auto& f : d.findings) {
    Json p = Json::object();
    for (const auto& q : f.parameters) p[q.name] = {{"value", q.value}, {"unit", q.unit}, {"u", q.u}};
    Json fj = {{"cause", f.cause},
               {"variant", f.variant},
               {"summary", f.summary},
               {"parameters", p},
               {"location_errors", locationErrorsJson(f.fit.estimate, f.fit.u)},
               {"residual_rms_um", f.residual_rms_um},
               {"holdout_rms_um", f.holdout_rms_um},
               {"gain_pct", f.gain_pct}};
    if (!f.per_repeat.empty()) {
      Json pr = Json::array();
      for (size_t r = 0; r < f.per_repeat.size(); ++r)
        pr.push_back({{"repeat", r + 1}, {"t_h", f.per_repeat[r].first},
                      {"location_errors", locationErrorsJson(f.per_repeat[r].second, f.fit.u)}});
      fj["per_repeat"] = pr;
    }
    findings.push_back(fj);
  }
  j["findings"] = findings;
  Json conf = Json::array();
  for (const auto& c : d.confounded) conf.push_back({{"causes", c.causes}, {"why", c.why}, {"separate_with", c.separate_with}});
  j["confounded"] = conf;
  Json cands = Json::array();
  for (const auto& c : d.candidates)
    cands.push_back({{"cause", c.cause}, {"variant", c.variant}, {"parameters", c.parameters},
                     {"residual_rms_um", c.residual_rms_um}, {"holdout_rms_um", c.holdout_rms_um}, {"chi2", c.chi2},
                     {"p", c.p_value}, {"bic", c.bic}, {"verdict", c.verdict}});
  j["candidates"] = cands;
  return j;
}

std::string diagnosisText(const Diagnosis& d) {
  std::string s;
  s += fmt::format("baseline (location errors + per-point offsets): residual rms {:.3f} um, held-out rms {:.3f} um\n",
                   d.baseline.summary.residual_rms_um, d.baseline_holdout_rms_um);
  s += fmt::format("noise used by the tests: {:.3f} um (probe repeatability or the fit's own, the larger)\n\n", d.sigma_um);
  s += "where the model disagrees with the data:\n";
  for (const auto& f : d.residual_analysis)
    s += fmt::format("  {:<9} chi2 {:>9.1f} on {:>2} dof  p {:<9.2g} {}  {}\n", f.factor, f.chi2, f.dof, f.p_value,
                     f.structured ? "STRUCTURE" : "noise    ", f.detail);
  s += "\ncandidate causes:\n";
  for (const auto& c : d.candidates)
    s += fmt::format("  {:<24} {:<14} held-out {:>7.3f} um  {}\n", c.cause, c.variant, c.holdout_rms_um, c.verdict);
  s += "\n";
  if (d.findings.empty()) s += "verdict: no significant effect: the model explains the data to within the probe's noise\n";
  for (const auto& f : d.findings) {
    s += "FOUND " + f.cause + ": " + f.summary + "\n";
    const auto& params = locationParameters(f.fit.estimate.kinematics);
    s += fmt::format("  {:<8} {:>10} {:>10}\n", "error", "baseline", "extended");
    for (int i = 0; i < kNumLocationErrors; ++i)
      s += fmt::format("  {:<8} {:>10.3f} {:>10.3f} {}\n", params[i].name, d.baseline.estimate.reportValue(i),
                       f.fit.estimate.reportValue(i), reportUnit(params[i].kind));
  }
  for (const auto& c : d.confounded) s += "confounded: " + c.why + "; " + c.separate_with + "\n";
  return s;
}

}  // namespace rotacal
