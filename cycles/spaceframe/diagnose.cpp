#include "cycles/spaceframe/diagnose.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/report_envelope.hpp"
#include "core/units.hpp"

namespace rotacal {

namespace {

using ModelVector = Eigen::Matrix<double, FrameModel::kSize, 1>;


bool isScale(int index) { return index >= kNumLocationErrors && index < kNumLocationErrors + 3; }

// The measured centres with their whitening: W_i = L_i^-1, L_i L_i^T = C_i / runs (the sphere
// fit's centre covariance per unit touch noise), so W r is unit-variance per touch sigma.
struct Problem {
  const ProbePlan* plan = nullptr;
  Kinematics kin{};
  Eigen::Vector3d origin_w_mm = Eigen::Vector3d::Zero();
  std::vector<FramePoint> points;
  std::vector<Eigen::Vector3d> measured_m_mm;
  std::vector<Eigen::Matrix3d> W;
  ModelVector unit;

  int n() const { return static_cast<int>(points.size()); }
  // Whitened residual (um per unit touch sigma), and the plain one (um), of every centre.
  void residuals(const ModelVector& x, Eigen::VectorXd* w, Eigen::VectorXd* plain) const {
    const FrameModel fm = FrameModel::fromVector(kin, x);
    w->resize(3 * n());
    if (plain) plain->resize(3 * n());
    for (int i = 0; i < n(); ++i) {
      const Eigen::Vector3d r = mmToUm(1.0) * (measured_m_mm[i] - fm.fittedCentre_m(*plan, points[i], origin_w_mm));
      w->segment<3>(3 * i) = W[i] * r;
      if (plain) plain->segment<3>(3 * i) = r;
    }
  }
  // d(model, whitened um) / d(parameter, report unit): central differences of 1e-3 report units
  // (the fits converge to 1e-13 mm, far below the 1e-6 um these steps resolve).
  Eigen::MatrixXd jacobian(const ModelVector& x, const std::vector<int>& active) const {
    const double step = 1e-3;
    Eigen::MatrixXd J(3 * n(), static_cast<Eigen::Index>(active.size()));
    Eigen::VectorXd wp, wm;
    for (size_t k = 0; k < active.size(); ++k) {
      ModelVector xp = x, xm = x;
      xp[active[k]] += step / unit[active[k]];
      xm[active[k]] -= step / unit[active[k]];
      residuals(xp, &wp, nullptr);
      residuals(xm, &wm, nullptr);
      J.col(static_cast<Eigen::Index>(k)) = -(wp - wm) / (2.0 * step);
    }
    return J;
  }
};

Eigen::VectorXd rowsOf(const Eigen::VectorXd& v, const std::vector<int>& rows) {
  Eigen::VectorXd out(3 * static_cast<Eigen::Index>(rows.size()));
  for (size_t k = 0; k < rows.size(); ++k) out.segment<3>(3 * static_cast<Eigen::Index>(k)) = v.segment<3>(3 * rows[k]);
  return out;
}
Eigen::MatrixXd rowsOf(const Eigen::MatrixXd& J, const std::vector<int>& rows) {
  Eigen::MatrixXd out(3 * static_cast<Eigen::Index>(rows.size()), J.cols());
  for (size_t k = 0; k < rows.size(); ++k)
    out.middleRows<3>(3 * static_cast<Eigen::Index>(k)) = J.middleRows<3>(3 * rows[k]);
  return out;
}

// Weighted Gauss-Newton on every centre, from zero. Returns the Jacobian of the last iterate for
// the held-out refits.
SpaceframeFit fitAll(const Problem& pb, const std::vector<int>& active, double sigma_um, Eigen::MatrixXd* J_out) {
  SpaceframeFit f;
  f.active = active;
  ModelVector x = ModelVector::Zero();
  Eigen::VectorXd w, plain;
  pb.residuals(x, &w, nullptr);
  Eigen::MatrixXd J;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd;
  for (int it = 0; it < 10; ++it) {
    J = pb.jacobian(x, active);
    svd.compute(J, Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(1e-10);
    f.rank = static_cast<int>(svd.rank());
    const Eigen::VectorXd step = svd.solve(w);
    const Eigen::VectorXd predicted = w - J * step;
    for (size_t k = 0; k < active.size(); ++k) x[active[k]] += step[static_cast<Eigen::Index>(k)] / pb.unit[active[k]];
    pb.residuals(x, &w, nullptr);
    f.linearisation_um = (w - predicted).cwiseAbs().maxCoeff();
    if (step.cwiseAbs().maxCoeff() < 1e-6) {  // 1e-6 um / mdeg / um/m: far below any resolution
      f.converged = true;
      break;
    }
  }
  pb.residuals(x, &w, &plain);
  f.model = FrameModel::fromVector(pb.kin, x);
  const int m = static_cast<int>(w.size());
  f.dof = m - f.rank;
  f.chi2 = w.squaredNorm() / (sigma_um * sigma_um);
  f.residual_rms_um = std::sqrt(plain.squaredNorm() / m);
  // u (k = 1) with the a-posteriori noise: cov = s^2 (J^T J)^-1 in report units.
  const double s_post = f.dof > 0 ? std::sqrt(w.squaredNorm() / f.dof) : 0.0;
  const Eigen::MatrixXd V = svd.matrixV();
  const Eigen::VectorXd sv = svd.singularValues();
  for (size_t k = 0; k < active.size(); ++k) {
    double v = 0.0;
    for (int j = 0; j < f.rank; ++j) v += V(static_cast<Eigen::Index>(k), j) * V(static_cast<Eigen::Index>(k), j) / (sv[j] * sv[j]);
    f.u[active[k]] = s_post * std::sqrt(v) / pb.unit[active[k]];
  }
  *J_out = J;
  return f;
}

// Leave one orientation out: refit on the rest (chord Newton from the full-data solution with its
// Jacobian, the exact residual each step), predict the left-out centres exactly. Plain um rms.
std::pair<double, int> leaveOneOrientationOut(const Problem& pb, const SpaceframeFit& full, const Eigen::MatrixXd& J,
                                              const std::vector<int>& group, int groups) {
  double ss = 0.0;
  int count = 0;
  const ModelVector x_full = full.model.toVector();
  for (int g = 0; g < groups; ++g) {
    std::vector<int> train, test;
    for (int i = 0; i < pb.n(); ++i) (group[static_cast<size_t>(i)] == g ? test : train).push_back(i);
    if (test.empty()) continue;
    const Eigen::MatrixXd Jt = rowsOf(J, train);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jt, Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(1e-10);
    ModelVector x = x_full;
    Eigen::VectorXd w, plain;
    for (int it = 0; it < 3; ++it) {
      pb.residuals(x, &w, nullptr);
      const Eigen::VectorXd step = svd.solve(rowsOf(w, train));
      for (size_t k = 0; k < full.active.size(); ++k)
        x[full.active[k]] += step[static_cast<Eigen::Index>(k)] / pb.unit[full.active[k]];
    }
    pb.residuals(x, &w, &plain);
    const Eigen::VectorXd r = rowsOf(plain, test);
    ss += r.squaredNorm();
    count += static_cast<int>(r.size());
  }
  return {count ? std::sqrt(ss / count) : 0.0, count};
}

}  // namespace

SpaceframeDiagnosis diagnoseSpaceframe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                       const DiagnosisOptions& options) {
  std::string why;
  if (!options.validate(&why)) throw std::invalid_argument("diagnosis options: " + why);
  // The sphere fits and measured centres of the analysis (its own identification is not used).
  SpaceframeOptions so;
  so.max_iterations = 1;
  const SpaceframeAnalysis a = analyzeSpaceframe(plan, runs, so);
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  Problem pb;
  pb.plan = &plan;
  pb.kin = plan.machine.kinematics;
  pb.origin_w_mm = layout.origin_w_mm;
  pb.points = a.points;
  pb.measured_m_mm = a.measured_m_mm;
  pb.unit = FrameModel::reportUnits(pb.kin);
  double ss_fit = 0.0;
  int dof_fit = 0;
  for (const auto& fit : a.fits) {
    // Per unit touch noise, a ratio: the same in mm^2 / mm^2 as in um^2 / um^2.
    const Eigen::LLT<Eigen::Matrix3d> llt(fit.cov_centre_per_sigma2 / static_cast<double>(runs.size()));
    if (llt.info() != Eigen::Success) throw std::invalid_argument("a sphere fit has no centre covariance");
    pb.W.push_back(llt.matrixL().solve(Eigen::Matrix3d::Identity()));
    ss_fit += fit.residual_rms_um * fit.residual_rms_um * fit.triggers;
    dof_fit += fit.dof;
  }
  SpaceframeDiagnosis d;
  d.centres = pb.n();
  d.fit_noise_um = dof_fit > 0 ? std::sqrt(ss_fit / dof_fit) : 0.0;
  d.sigma_um = std::max(options.prior_sigma_um, d.fit_noise_um);

  // One orientation: the pose's A and C modulo 360 (theta = 0 and 360 are the same table pose).
  std::map<std::pair<long, long>, int> ids;
  std::vector<int> group;
  for (const auto& f : pb.points) {
    const long c = std::lround(std::fmod(std::fmod(f.pose.C, 360.0) + 360.0, 360.0) * 1e6);
    const auto key = std::make_pair(std::lround(f.pose.A * 1e6), c);
    const auto it = ids.emplace(key, static_cast<int>(ids.size())).first;
    group.push_back(it->second);
  }
  d.holdout_groups = static_cast<int>(ids.size());

  const std::vector<int> full = activeParameters(layout.nominal_from == "initial");
  std::vector<int> base;
  for (int i : full)
    if (!isScale(i)) base.push_back(i);
  Eigen::MatrixXd Jb, Jc;
  d.baseline = fitAll(pb, base, d.sigma_um, &Jb);
  d.candidate = fitAll(pb, full, d.sigma_um, &Jc);
  d.baseline_p_value = chiSquareSurvival(d.baseline.chi2, d.baseline.dof);
  const auto [hb, nb] = leaveOneOrientationOut(pb, d.baseline, Jb, group, d.holdout_groups);
  const auto [hc, nc] = leaveOneOrientationOut(pb, d.candidate, Jc, group, d.holdout_groups);
  (void)nc;
  d.baseline_holdout_rms_um = hb;
  d.candidate_holdout_rms_um = hc;
  d.holdout_coordinates = nb;

  CandidateScore sc;
  sc.cause = "linear_axis_scale";
  sc.variant = layout.nominal_from == "initial" ? "xy_relative_to_z" : "xyz";
  sc.parameters = d.candidate.rank - d.baseline.rank;
  sc.residual_rms_um = d.candidate.residual_rms_um;
  sc.holdout_rms_um = hc;
  sc.chi2 = d.baseline.chi2 - d.candidate.chi2;  // same sigma: the drop in units of it
  sc.p_value = chiSquareSurvival(sc.chi2, std::max(1, sc.parameters));
  const double m = 3.0 * d.centres;
  const double rss = d.candidate.chi2 * d.sigma_um * d.sigma_um;
  sc.bic = m * std::log(std::max(rss, 1e-300) / m) + d.candidate.rank * std::log(m);
  const double p_thr = options.alpha;  // one candidate
  d.needed_gain = std::max(options.min_holdout_gain, options.holdout_sigmas / std::sqrt(2.0 * std::max(1, nb)));
  const double gain = hb > 0 ? 1.0 - hc / hb : 0.0;
  if (d.baseline_p_value >= p_thr)
    sc.verdict = fmt::format("baseline fits within the touch noise (chi2 {:.1f} on {} dof, p {:.2g} >= {:.2g})",
                             d.baseline.chi2, d.baseline.dof, d.baseline_p_value, p_thr);
  else if (gain < d.needed_gain)
    sc.verdict = fmt::format("held-out gain {:.1f} % below the {:.1f} % the noise allows", 100 * gain, 100 * d.needed_gain);
  else
    sc.verdict = "accepted";
  d.candidates.push_back(sc);
  d.found = sc.verdict == "accepted";
  d.gain_pct = 100.0 * gain;
  return d;
}

namespace {


Json fitJson(const SpaceframeFit& f) {
  Json j;
  j["location_errors"] = locationErrorsJson(f.model.errors, f.u.head<kNumLocationErrors>());
  Json st = Json::object();
  const char* ax[3] = {"X", "Y", "Z"};
  for (int i = 0; i < 3; ++i) {
    st[std::string("translation_") + ax[i]] = {{"value", round6(mmToUm(f.model.setup_translation_mm[i]))}, {"unit", "um"},
                                               {"u", round6(mmToUm(f.u[kNumLocationErrors + 3 + i]))}};
    st[std::string("rotation_") + ax[i]] = {{"value", round6(radToMdeg(f.model.setup_rotation_rad[i]))}, {"unit", "mdeg"},
                                            {"u", round6(radToMdeg(f.u[kNumLocationErrors + 6 + i]))}};
  }
  bool has_scale = false, has_setup = false;
  for (int i : f.active) {
    has_scale = has_scale || isScale(i);
    has_setup = has_setup || (i >= kNumLocationErrors + 3 && i < FrameModel::kRigidSize);
  }
  if (has_setup) {
    j["frame_setup"] = st;
  } else {  // self-calibration: the setup is held in every sphere's offset
    Json sp = Json::object();
    for (int i = 0; i < 7; ++i) {
      const Eigen::Vector3d o = f.model.sphere_offset_w_mm[static_cast<size_t>(i)];
      const Eigen::Vector3d uo = f.u.segment<3>(FrameModel::kRigidSize + 3 * i);
      sp[std::to_string(i + 1)] = {{"offset_w_um", {round6(mmToUm(o.x())), round6(mmToUm(o.y())), round6(mmToUm(o.z()))}},
                                   {"u_um", {round6(mmToUm(uo.x())), round6(mmToUm(uo.y())), round6(mmToUm(uo.z()))}}};
    }
    j["frame_spheres"] = sp;
  }
  if (has_scale) {
    Json sc = Json::object();
    for (int i = 0; i < 3; ++i)
      sc[ax[i]] = {{"value", round6(f.model.scale[i] * 1e6)}, {"unit", "um/m"}, {"u", round6(f.u[kNumLocationErrors + i] * 1e6)}};
    j["linear_axis_scale"] = sc;
  }
  j["residual_rms_um"] = round6(f.residual_rms_um);
  j["chi2"] = round6(f.chi2);
  j["dof"] = f.dof;
  j["rank"] = f.rank;
  j["parameters"] = f.active.size();
  j["converged"] = f.converged;
  j["linearisation_um"] = f.linearisation_um;
  return j;
}

}  // namespace

Json spaceframeDiagnosisJson(const SpaceframeDiagnosis& d, const ProbePlan& plan) {
  Json j;
  j["format"] = "rotacal-diagnosis/1";
  j["cycle"] = "spaceframe";
  j["machine"] = plan.machine.name;
  Json b = fitJson(d.baseline);
  b["model"] = "rotary-axis location errors and the frame (its setup on the table; every sphere when it self-calibrates), no linear-axis scale errors";
  b["holdout_rms_um"] = round6(d.baseline_holdout_rms_um);
  b["p_value"] = d.baseline_p_value;
  j["baseline"] = b;
  j["holdout_scheme"] = fmt::format("leave one orientation out ({} orientations, {} centres)", d.holdout_groups, d.centres);
  j["sigma_um"] = round6(d.sigma_um);
  j["fit_noise_um"] = round6(d.fit_noise_um);
  j["needed_gain_pct"] = round6(100 * d.needed_gain);
  j["verdict"] = d.found ? "effect_found" : "no_significant_effect";
  Json cands = Json::array();
  for (const auto& c : d.candidates)
    cands.push_back({{"cause", c.cause},
                     {"variant", c.variant},
                     {"parameters", c.parameters},
                     {"residual_rms_um", round6(c.residual_rms_um)},
                     {"holdout_rms_um", round6(c.holdout_rms_um)},
                     {"chi2", round6(c.chi2)},
                     {"p_value", c.p_value},
                     {"bic", round6(c.bic)},
                     {"gain_pct", round6(d.gain_pct)},
                     {"verdict", c.verdict}});
  j["candidates"] = cands;
  Json findings = Json::array();
  if (d.found) {
    Json e = fitJson(d.candidate);
    const Eigen::Vector3d s = d.candidate.model.scale * 1e6;
    int big = 0;
    for (int i = 1; i < 3; ++i)
      if (std::abs(s[i]) > std::abs(s[big])) big = i;
    e["cause"] = "linear_axis_scale";
    e["variant"] = d.candidates.front().variant;
    e["summary"] = fmt::format("the linear axes' scales are off: X {:+.1f} um/m, Y {:+.1f} um/m, Z {:+.1f} um/m (largest on "
                               "{}: {:+.1f} um over 100 mm); recalibrate the axis (laser interferometer) or compensate its "
                               "pitch",
                               s.x(), s.y(), s.z(), "XYZ"[big], s[big] * 0.1);
    Json params = Json::object();  // the contract's parameters: the cause's own terms
    for (int i = 0; i < 3; ++i)
      params[std::string("scale_") + "XYZ"[i]] = {{"value", round6(s[i])}, {"unit", "um/m"},
                                                   {"u", round6(d.candidate.u[kNumLocationErrors + i] * 1e6)}};
    e["parameters"] = params;
    e["holdout_rms_um"] = round6(d.candidate_holdout_rms_um);
    e["gain_pct"] = round6(d.gain_pct);
    findings.push_back(e);
  }
  j["findings"] = findings;
  j["confounded"] = Json::array();
  return j;
}

std::string spaceframeDiagnosisText(const SpaceframeDiagnosis& d) {
  std::string s = fmt::format(
      "spaceframe diagnosis: baseline (location errors + frame) residual {:.3f} um rms, held-out {:.3f} um rms "
      "(leave one of {} orientations out); chi2 {:.1f} on {} dof at sigma {:.3f} um (p {:.2g})\n",
      d.baseline.residual_rms_um, d.baseline_holdout_rms_um, d.holdout_groups, d.baseline.chi2, d.baseline.dof, d.sigma_um,
      d.baseline_p_value);
  for (const auto& c : d.candidates)
    s += fmt::format("  {}/{}: residual {:.3f} um, held-out {:.3f} um (gain {:.1f} %, needed {:.1f} %): {}\n", c.cause,
                     c.variant, c.residual_rms_um, c.holdout_rms_um, d.gain_pct, 100 * d.needed_gain, c.verdict);
  const Eigen::Vector3d sc = d.candidate.model.scale * 1e6, u = d.candidate.u.segment<3>(kNumLocationErrors) * 1e6;
  s += fmt::format("  scale estimate X {:+.2f} +- {:.2f}, Y {:+.2f} +- {:.2f}, Z {:+.2f} +- {:.2f} um/m\n", sc.x(), u.x(),
                   sc.y(), u.y(), sc.z(), u.z());
  s += d.found ? fmt::format("verdict: effect found (linear_axis_scale), held-out gain {:.0f} %\n", d.gain_pct)
               : "verdict: no significant effect\n";
  return s;
}

}  // namespace rotacal
