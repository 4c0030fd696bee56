#include "cycles/spheres3/diagnose.hpp"

#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/declared_noise.hpp"
#include "core/sphere_centre_fit.hpp"
#include "core/units.hpp"
#include "cycles/judge_contract.hpp"
#include "core/require_valid.hpp"

namespace rotacal {

bool Spheres3DiagnosisOptions::validate(std::string* why) const {
  if (!validJudgeAndProbe(judge, sigma_um, why)) return false;
  if (max_harmonic < 1) {
    if (why) *why = "max_harmonic must be at least 1";
    return false;
  }
  return true;
}

namespace {

bool isAngleComponent(int c) { return c >= 3; }

// Which error-motion family a component term belongs to.
const char* familyOf(const ComponentTerm& t) {
  switch (t.component) {
    case 0:
    case 1: return kSpheres3Radial;
    case 2: return kSpheres3Axial;
    case 3:
    case 4: return kSpheres3Tilt;
    default: return kSpheres3Angular;
  }
}

const char* familyDescription(const std::string& f) {
  if (f == kSpheres3Radial) return "radial error motion of C (EXC, EYC as harmonics of C)";
  if (f == kSpheres3Axial) return "axial error motion of C (EZC as harmonics of C)";
  if (f == kSpheres3Tilt) return "tilt error motion of C (EAC, EBC as harmonics of C)";
  if (f == kSpheres3Angular) return "angular positioning error of C (ECC as harmonics of C)";
  if (f == kSpheres3Scale) return "scale errors of the linear axes X, Y, Z";
  if (f == kSpheres3Squareness) return "squareness errors of the linear axes (S_xy, S_xz, S_yz)";
  return "thermal drift: the table's position changes linearly with time";
}

}  // namespace

JudgeProblem spheres3JudgeProblem(const Spheres3Result& b, const std::vector<MeasurementRun>& runs,
                                  const Spheres3DiagnosisOptions& options) {
  JudgeProblem p;
  const auto& obs = b.observations;
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(obs.size());
  p.unit = "um";
  p.y.resize(n);
  p.sigma.resize(n);
  // Trigger times per run (s): a centre's time is the mean of its touches'.
  std::vector<std::map<int, double>> times(runs.size());
  for (size_t r = 0; r < runs.size(); ++r)
    for (const auto& t : runs[r].points) times[r][t.point_id] = t.t_s;
  std::vector<double> t_h(obs.size(), 0.0);
  bool clock = true;
  for (size_t k = 0; k < obs.size(); ++k) {
    const auto& o = obs[k];
    double s = 0.0;
    for (int id : o.point_ids) s += times[static_cast<size_t>(o.run)].at(id);
    t_h[k] = s / static_cast<double>(o.point_ids.size()) / 3600.0;
    if (!std::isfinite(t_h[k])) clock = false;
  }
  if (clock) {
    double t0 = t_h.front();
    for (double t : t_h) t0 = std::min(t0, t);
    for (double& t : t_h) t -= t0;  // hours since the first centre: keeps the slope's columns small
  }

  // The exact model at the baseline's solution and its derivatives (central differences; the
  // model is smooth and the steps, 1e-4 um / 1e-7 rad, far below any parameter's size).
  const Eigen::Vector4d L = b.location;
  auto predict = [&](const Eigen::Vector4d& loc, const ComponentVector& e, const Eigen::Vector3d& s, double c) {
    return Eigen::Vector3d(spheres3Table_m_w(loc, e, c) * s);
  };
  const ComponentVector zero = ComponentVector::Zero();
  const int n_angles = static_cast<int>(b.c_deg.size());
  const std::vector<ComponentTerm> all_terms = componentTerms(ComponentModel::Full, n_angles);
  std::vector<ComponentTerm> terms;
  for (const auto& t : all_terms)
    if (t.k <= options.max_harmonic) terms.push_back(t);

  p.J0 = Eigen::MatrixXd::Zero(n, 13);
  for (int i = 0; i < 4; ++i) {
    const bool angle = i >= 2;
    p.baseline_parameters.push_back({spheres3LocationNames()[static_cast<size_t>(i)], angle ? "mdeg" : "um"});
  }
  for (int s = 0; s < 3; ++s)
    for (int a = 0; a < 3; ++a) p.baseline_parameters.push_back({fmt::format("sphere{}_{}", s + 1, "xyz"[a]), "um"});
  std::map<std::string, JudgeCause> fam;
  const std::vector<std::string> fam_order = {kSpheres3Radial, kSpheres3Axial, kSpheres3Tilt, kSpheres3Angular};
  for (const auto& f : fam_order) {
    fam[f].name = f;
    fam[f].description = familyDescription(f);
    fam[f].J = Eigen::MatrixXd::Zero(n, 0);
  }
  for (const auto& t : terms) {
    JudgeCause& c = fam[familyOf(t)];
    c.parameters.push_back({t.name(), isAngleComponent(t.component) ? "mdeg" : "um"});
  }
  for (auto& [name, c] : fam) c.J = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(c.parameters.size()));
  JudgeCause scale{kSpheres3Scale, familyDescription(kSpheres3Scale), Eigen::MatrixXd::Zero(n, 3),
                   {{"X_scale", "um/m"}, {"Y_scale", "um/m"}, {"Z_scale", "um/m"}}};
  JudgeCause square{kSpheres3Squareness, familyDescription(kSpheres3Squareness), Eigen::MatrixXd::Zero(n, 3),
                    {{"S_xy", "um/m"}, {"S_xz", "um/m"}, {"S_yz", "um/m"}}};
  JudgeCause drift{kSpheres3Drift, familyDescription(kSpheres3Drift), Eigen::MatrixXd::Zero(n, 3),
                   {{"X/h", "um/h"}, {"Y/h", "um/h"}, {"Z/h", "um/h"}}};

  const double hl = umToMm(1e-4), ha = 1e-7;
  const double per_mdeg = mdegToRad(1.0);
  JudgeFactor angle_f{"C angle", {}, {}, ""}, sphere_f{"sphere", {}, {}, ""}, coord_f{"coordinate", {}, {}, ""},
      repeat_f{"repeat", {}, {}, ""}, time_f{"time", {}, {}, "h"};
  int n_runs = 0;
  for (size_t k = 0; k < obs.size(); ++k) {
    const auto& o = obs[k];
    const Eigen::Index r0 = 3 * static_cast<Eigen::Index>(k);
    const double c = degToRad(b.c_deg[static_cast<size_t>(o.angle)]);
    const Eigen::Vector3d& s = b.sphere_w_mm[static_cast<size_t>(o.sphere)];
    const Eigen::Vector3d pc = predict(L, zero, s, c);
    p.y.segment<3>(r0) = mmToUm(1.0) * o.residual_mm;
    for (int a = 0; a < 3; ++a) p.sigma[r0 + a] = options.sigma_um * std::sqrt(o.fit.cov_centre_per_sigma2(a, a));
    // Baseline columns: um of centre per um or per mdeg of the parameter.
    for (int i = 0; i < 4; ++i) {
      const double h = i < 2 ? hl : ha;
      Eigen::Vector4d lp = L, lm = L;
      lp[i] += h;
      lm[i] -= h;
      const Eigen::Vector3d d = (predict(lp, zero, s, c) - predict(lm, zero, s, c)) / (2 * h);
      p.J0.block<3, 1>(r0, i) = mmToUm(1.0) * d * (i < 2 ? umToMm(1.0) : per_mdeg);
    }
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3d sp = s, sm = s;
      sp[a] += hl;
      sm[a] -= hl;
      const Eigen::Vector3d d = (predict(L, zero, sp, c) - predict(L, zero, sm, c)) / (2 * hl);
      p.J0.block<3, 1>(r0, 4 + 3 * o.sphere + a) = d;  // mm per mm = um per um
    }
    // Error-motion columns: the analysis model's own terms, one column per coefficient.
    std::map<std::string, int> col;
    for (const auto& t : terms) {
      JudgeCause& cf = fam[familyOf(t)];
      const bool angle = isAngleComponent(t.component);
      const double h = angle ? ha : hl;
      const ComponentVector v = t.value(c);
      const Eigen::Vector3d d = (predict(L, h * v, s, c) - predict(L, -h * v, s, c)) / (2 * h);
      cf.J.block<3, 1>(r0, col[cf.name]++) = mmToUm(1.0) * d * (angle ? per_mdeg : umToMm(1.0));
    }
    // Linear axes: the controller reads actual - E(actual) (core/simulation.hpp), E = diag(s) p
    // for scale and (S_xy y + S_xz z, S_yz z, 0) for squareness; 1 um/m at p mm is 1e-3 p um.
    for (int a = 0; a < 3; ++a) scale.J(r0 + a, a) = -1e-3 * pc[a];
    square.J(r0 + 0, 0) = -1e-3 * pc.y();
    square.J(r0 + 0, 1) = -1e-3 * pc.z();
    square.J(r0 + 1, 2) = -1e-3 * pc.z();
    // Drift: the table (every centre) moves by v t.
    for (int a = 0; a < 3; ++a) drift.J(r0 + a, a) = clock ? t_h[k] : 0.0;
    for (int a = 0; a < 3; ++a) {
      p.groups.push_back(o.angle);
      angle_f.levels.push_back(fmt::format("C={:g}", b.c_deg[static_cast<size_t>(o.angle)]));
      sphere_f.levels.push_back(fmt::format("sphere {}", o.sphere + 1));
      coord_f.levels.emplace_back(1, "xyz"[a]);
      repeat_f.levels.push_back(std::to_string(o.run + 1));
      time_f.values.push_back(t_h[k]);
    }
    n_runs = std::max(n_runs, o.run + 1);
  }
  if (options.noise) {
    // The centres' declared covariance: each sphere fit maps its touches' displacements along
    // their approaches linearly (linearSphereFit), C_centres = M C_touches M^T, the touches'
    // covariance white per reading and shared (the same machine) between every two.
    const Spheres3Noise& nz = *options.noise;
    std::vector<std::pair<int, int>> readings;  // (run, plan index)
    std::vector<std::pair<Eigen::Index, Eigen::Index>> block;  // per observation: first reading, count
    std::vector<Eigen::MatrixXd> maps;
    for (const auto& o : obs) {
      std::vector<Eigen::Vector3d> pts, approaches;
      block.emplace_back(static_cast<Eigen::Index>(readings.size()), static_cast<Eigen::Index>(o.point_ids.size()));
      for (int id : o.point_ids) {
        const int idx = nz.index_of_id.at(id);
        readings.emplace_back(o.run, idx);
        approaches.push_back(nz.approach[static_cast<size_t>(idx)]);
        for (const auto& t : runs[static_cast<size_t>(o.run)].points)
          if (t.point_id == id) pts.push_back(t.position_m_mm);
      }
      maps.push_back(linearSphereFit(pts, approaches, o.fit).centre);
    }
    const Eigen::MatrixXd C = nz.trigger.covariance(readings);
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(readings.size()));
    for (size_t k = 0; k < obs.size(); ++k)
      M.block(3 * static_cast<Eigen::Index>(k), block[k].first, 3, block[k].second) = maps[k];
    p.covariance = M * C * M.transpose();
    // The null from draws of the declared machine carried the same way (the node spacing one per
    // machine makes it a scale mixture, heavier-tailed than a normal of the same covariance); the
    // draws analyze's adequacy test reads.
    p.null_draws = M * nz.trigger.nullDraws(readings, kDeclaredNullSeed + 2);
    p.declaration = nz.trigger.declaration;
    p.sigma = Eigen::VectorXd();
  }
  for (const auto& f : fam_order)
    if (!fam[f].parameters.empty()) p.causes.push_back(fam[f]);
  p.causes.push_back(scale);
  p.causes.push_back(square);
  // Drift needs repeats: within one run, time and C angle are the same order and a slope is a
  // first harmonic's piece; with repeats, the time at each angle differs between runs.
  if (n_runs > 1 && clock) p.causes.push_back(drift);
  p.group_name = "C angle";
  p.factors = {angle_f, sphere_f, coord_f};
  if (n_runs > 1) p.factors.push_back(repeat_f);
  if (clock) p.factors.push_back(time_f);
  return p;
}

Spheres3Diagnosis diagnoseSpheres3(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                   const Spheres3DiagnosisOptions& options) {
  requireValid(options, "diagnosis options");
  Spheres3Diagnosis d;
  Spheres3Options base;
  base.model = ComponentModel::None;
  base.prior_sigma_um = options.sigma_um;
  d.baseline = identifySpheres3(plan, runs, base);
  d.problem = spheres3JudgeProblem(d.baseline, runs, options);
  d.judged = judge(d.problem, options.judge);
  return d;
}

namespace {

// Location errors in REPORT.json's form from judge estimates (Oxc Oyc in um, Sxc Syc in mdeg).
Json locationJson(const std::vector<JudgeEstimate>& es) {
  Json le = Json::object();
  for (int i = 0; i < 4; ++i) {
    const char* name = spheres3LocationNames()[static_cast<size_t>(i)];
    for (const auto& e : es)
      if (e.name == name)
        le[name] = {{"value", e.value}, {"unit", e.unit}, {"u", e.u}, {"iso", spheres3LocationIso()[static_cast<size_t>(i)]}};
  }
  return le;
}

// The contract's cause id and variant of a judge cause name.
std::pair<std::string, std::string> contractCause(const std::string& judge_name) {
  const std::string rem = "rotary_error_motion_";
  if (judge_name.rfind(rem, 0) == 0) return {"rotary_error_motion", judge_name.substr(rem.size())};
  return {judge_name, ""};
}

std::string separationHint(const std::vector<std::string>& causes) {
  bool scale = false, sphere = false;
  for (const auto& c : causes) {
    if (c.find("scale") != std::string::npos) scale = true;
    if (c.rfind("sphere", 0) == 0) sphere = true;
  }
  if (scale && sphere)
    return "a scale error moves each sphere by a constant amount, as a sphere position does: measure the scale "
           "with a length standard (or the spheres at a second tilt angle / second height set)";
  return "a plan whose poses move these columns apart (more C angles, spheres at other heights or radii, a tilt "
         "angle other than 0); the confounding is computed from this plan's Jacobians";
}

std::string separateWith(const JudgeConfounded& c) {
  std::vector<std::string> causes = {c.cause};
  causes.insert(causes.end(), c.with.begin(), c.with.end());
  return separationHint(causes);
}

}  // namespace

Json spheres3DiagnosisJson(const Spheres3Diagnosis& d) {
  const JudgeSummary& s = d.judged;
  Json j = judgeToJson(s);
  stampDiagnosis(j, "spheres3");
  // The contract's fields (../shared/contract.md), beside the judge's own.
  Json& b = j["baseline"];
  b["model"] = "C-axis location errors Oxc Oyc Sxc Syc and the sphere positions (no error motion)";
  b["residual_rms_um"] = d.baseline.residual_rms_um;
  b["holdout_rms_um"] = s.baseline_holdout_rms;
  b["location_errors"] = locationJson(s.baseline_estimates);
  j["holdout_scheme"] = "leave one C angle out (every sphere and repeat at it), exact for the linearised model";
  j["sigma_um"] = s.declared_sigma_rms;
  for (size_t k = 0; k < s.findings.size() && k < j["findings"].size(); ++k) {
    Json& f = j["findings"][k];
    const JudgeFinding& jf = s.findings[k];
    const auto [cause, variant] = contractCause(jf.cause);
    f["judge_cause"] = jf.cause;
    f["cause"] = cause;
    f["variant"] = variant;
    const std::string params = findingParametersText(jf);
    const double gain = holdoutGainPct(s, jf);
    f["summary"] = fmt::format("{}: {}; held-out residual {:.3f} -> {:.3f} um ({:+.0f} %)", jf.description, params,
                               s.baseline_holdout_rms, jf.holdout_rms_cause, -gain);
    // Re-estimated with every accepted cause in (one Gauss-Newton step from the baseline).
    f["location_errors"] = locationJson(s.final_estimates);
    f["holdout_rms_um"] = jf.holdout_rms_cause;
    f["gain_pct"] = gain;
  }
  writeConfounded(j, s, separateWith);
  return j;
}

std::string spheres3DiagnosisText(const Spheres3Diagnosis& d) {
  std::string s = fmt::format(
      "spheres3 diagnosis: baseline (location errors + sphere positions) residual {:.3f} um rms, held-out {:.3f} um "
      "rms (leave one C angle out)\n",
      d.baseline.residual_rms_um, d.judged.baseline_holdout_rms);
  s += fmt::format("declared noise (MACHINE.json probe repeatability, carried to the centres): {:.3f} um rms\n",
                   d.judged.declared_sigma_rms);
  s += judgeText(d.judged, separateWith);
  return s;
}

}  // namespace rotacal
