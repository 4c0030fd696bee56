#include "cycles/spheres3/diagnose.hpp"

#include <cmath>

#include <fmt/format.h>

#include "core/units.hpp"

namespace rotacal {

namespace {

// Held-out rms over every C angle left out in turn (um, per coordinate), and the coordinates.
std::pair<double, int> leaveOneAngleOut(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                        Spheres3Options o) {
  double ss = 0.0;
  int n = 0;
  for (int a = 0; a < static_cast<int>(plan.poses.size()); ++a) {
    o.hold_out_angle = a;
    const Spheres3Result r = identifySpheres3(plan, runs, o);
    for (const auto& ob : r.observations)
      if (ob.held_out) {
        ss += std::pow(mmToUm(1.0), 2) * ob.residual_mm.squaredNorm();
        n += 3;
      }
  }
  return {n ? std::sqrt(ss / n) : 0.0, n};
}

Json locationJson(const Spheres3Result& r) {
  Json le = Json::object();
  for (int i = 0; i < 4; ++i) {
    const bool angle = i >= 2;
    le[spheres3LocationNames()[static_cast<size_t>(i)]] = {
        {"value", angle ? radToMdeg(r.location[i]) : mmToUm(r.location[i])},
        {"unit", angle ? "mdeg" : "um"},
        {"u", angle ? radToMdeg(r.location_u[i]) : mmToUm(r.location_u[i])},
        {"iso", spheres3LocationIso()[static_cast<size_t>(i)]}};
  }
  return le;
}

}  // namespace

Spheres3Diagnosis diagnoseSpheres3(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                   const DiagnosisOptions& options) {
  std::string why;
  if (!options.validate(&why)) throw std::invalid_argument("diagnosis options: " + why);
  Spheres3Diagnosis d;
  Spheres3Options base;
  base.model = ComponentModel::None;
  base.prior_sigma_um = options.prior_sigma_um;
  d.baseline = identifySpheres3(plan, runs, base);
  // The sphere fits' touch noise does not depend on the C model: one sigma for both fits.
  d.sigma_um = d.baseline.sigma_used_um;
  const auto [hb, nb] = leaveOneAngleOut(plan, runs, base);
  d.baseline_holdout_rms_um = hb;
  d.holdout_coordinates = nb;

  Spheres3Options ext = base;
  ext.model = ComponentModel::SecondOrderRadial;
  const Spheres3Result cand = identifySpheres3(plan, runs, ext);
  const auto [hc, nc] = leaveOneAngleOut(plan, runs, ext);
  CandidateScore sc;
  sc.cause = "rotary_error_motion";
  sc.variant = "second_order_radial";
  sc.parameters = static_cast<int>(cand.terms.size());
  sc.residual_rms_um = cand.residual_rms_um;
  sc.holdout_rms_um = hc;
  // chi2 values of both fits use the same sigma: their difference is the drop in units of it.
  sc.chi2 = d.baseline.chi2 - cand.chi2;
  sc.p_value = chiSquareSurvival(sc.chi2, sc.parameters);
  const double m = 3.0 * static_cast<double>(cand.observations.size());
  const double rss = cand.chi2 * d.sigma_um * d.sigma_um;
  sc.bic = m * std::log(std::max(rss, 1e-300) / m) + cand.parameters * std::log(m);
  const int n_candidates = 1;
  const double p_thr = options.alpha / n_candidates;
  const double needed = std::max(options.min_holdout_gain, options.holdout_sigmas / std::sqrt(2.0 * std::max(1, nc)));
  const double gain = hb > 0 ? 1.0 - hc / hb : 0.0;
  if (sc.p_value >= p_thr)
    sc.verdict = fmt::format("residual drop within noise (chi2 {:.1f} on {} dof, p {:.2g} >= {:.2g})", sc.chi2,
                             sc.parameters, sc.p_value, p_thr);
  else if (gain < needed)
    sc.verdict = fmt::format("held-out gain {:.1f} % below the {:.1f} % the noise allows", 100 * gain, 100 * needed);
  else
    sc.verdict = "accepted";
  d.candidates.push_back(sc);
  if (sc.verdict == "accepted") {
    d.found = true;
    d.extended = cand;
    d.extended_holdout_rms_um = hc;
    d.gain_pct = 100.0 * gain;
  }
  return d;
}

Json spheres3DiagnosisJson(const Spheres3Diagnosis& d) {
  Json j;
  j["format"] = "rotacal-diagnosis/1";
  j["cycle"] = "spheres3";
  j["baseline"] = {{"model", "C-axis location errors Oxc Oyc Sxc Syc and the sphere positions (no error motion)"},
                   {"residual_rms_um", d.baseline.residual_rms_um},
                   {"holdout_rms_um", d.baseline_holdout_rms_um},
                   {"location_errors", locationJson(d.baseline)}};
  j["holdout_scheme"] = "leave one C angle out";
  j["sigma_um"] = d.sigma_um;
  j["verdict"] = d.found ? "effect_found" : "no_significant_effect";
  Json cands = Json::array();
  for (const auto& c : d.candidates)
    cands.push_back({{"cause", c.cause},
                     {"variant", c.variant},
                     {"parameters", c.parameters},
                     {"residual_rms_um", c.residual_rms_um},
                     {"holdout_rms_um", c.holdout_rms_um},
                     {"chi2", c.chi2},
                     {"p_value", c.p_value},
                     {"bic", c.bic},
                     {"verdict", c.verdict}});
  j["candidates"] = cands;
  Json findings = Json::array();
  if (d.found) {
    const Spheres3Result& e = d.extended;
    Json params = Json::object();
    for (size_t t = 0; t < e.terms.size(); ++t)
      params[e.terms[t].name()] = {{"value", mmToUm(e.h[static_cast<Eigen::Index>(t)])},
                                   {"unit", "um"},
                                   {"u", mmToUm(e.h_u[static_cast<Eigen::Index>(t)])}};
    const double ax = std::hypot(e.h[0], e.h[1]), ay = std::hypot(e.h[2], e.h[3]);
    findings.push_back(
        {{"cause", "rotary_error_motion"},
         {"variant", "second_order_radial"},
         {"summary", fmt::format("the C axis's centre moves twice per turn (second-order radial error motion, an oval "
                                 "bearing or a table clamped out of round): amplitude {:.2f} um in X, {:.2f} um in Y",
                                 mmToUm(ax), mmToUm(ay))},
         {"parameters", params},
         {"location_errors", locationJson(e)},
         {"residual_rms_um", e.residual_rms_um},
         {"holdout_rms_um", d.extended_holdout_rms_um},
         {"gain_pct", d.gain_pct}});
  }
  j["findings"] = findings;
  j["confounded"] = Json::array();
  return j;
}

std::string spheres3DiagnosisText(const Spheres3Diagnosis& d) {
  std::string s = fmt::format(
      "spheres3 diagnosis: baseline (location errors only) residual {:.3f} um rms, held-out {:.3f} um rms "
      "(leave one C angle out), touch noise {:.3f} um\n",
      d.baseline.residual_rms_um, d.baseline_holdout_rms_um, d.sigma_um);
  for (const auto& c : d.candidates)
    s += fmt::format("  {}/{}: residual {:.3f} um, held-out {:.3f} um, chi2 {:.1f} (p {:.2g}): {}\n", c.cause, c.variant,
                     c.residual_rms_um, c.holdout_rms_um, c.chi2, c.p_value, c.verdict);
  s += d.found ? fmt::format("verdict: effect found (rotary_error_motion), held-out gain {:.0f} %\n", d.gain_pct)
               : "verdict: no significant effect\n";
  return s;
}

}  // namespace rotacal
