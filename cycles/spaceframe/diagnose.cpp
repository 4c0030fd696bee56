#include "cycles/spaceframe/diagnose.hpp"

#include <limits>
#include <Eigen/Dense>
#include <cmath>
#include <algorithm>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/least_squares.hpp"
#include "core/report_envelope.hpp"
#include "core/units.hpp"
#include "cycles/judge_contract.hpp"
#include "core/require_valid.hpp"

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
  /// With a declared covariance of the centres: its inverse root (1/um) replaces W, and `raw`
  /// (once the baseline is fitted) hands the judge plain um, which it whitens itself.
  Eigen::MatrixXd W_full;
  bool raw = false;
  ModelVector unit;

  int n() const { return static_cast<int>(points.size()); }
  // Whitened residual (um per unit touch sigma), and the plain one (um), of every centre.
  std::vector<double> t_h;  // each centre's mean touch time, hours from the data's mean
  void residuals(const ModelVector& x, Eigen::VectorXd* w, Eigen::VectorXd* plain) const {
    residuals(x, Causes{}, w, plain);
  }
  // The same with the causes' parameters (internal units: mm/mm, mm/h, 1).
  struct Causes {
    Eigen::Vector3d squareness = Eigen::Vector3d::Zero();  // S_xy, S_xz, S_yz
    Eigen::Vector3d drift = Eigen::Vector3d::Zero();       // first three location errors per hour
    double frame_expansion = 0.0;
  };
  void residuals(const ModelVector& x, const Causes& c, Eigen::VectorXd* w, Eigen::VectorXd* plain) const {
    FrameModel fm = FrameModel::fromVector(kin, x);
    fm.shear << 0.0, c.squareness[0], c.squareness[1], 0.0, 0.0, c.squareness[2], 0.0, 0.0, 0.0;
    const ErrorVector e0 = fm.errors.values;
    Eigen::VectorXd r_all(3 * n());
    for (int i = 0; i < n(); ++i) {
      FramePoint p = points[i];
      p.center_w_mm *= 1.0 + c.frame_expansion;
      fm.errors.values = e0;
      fm.errors.values.head<3>() += c.drift * t_h[static_cast<size_t>(i)];
      r_all.segment<3>(3 * i) = mmToUm(1.0) * (measured_m_mm[i] - fm.fittedCentre_m(*plan, p, origin_w_mm));
    }
    if (raw) {
      *w = r_all;
    } else if (W_full.size() > 0) {
      *w = W_full * r_all;
    } else {
      w->resize(3 * n());
      for (int i = 0; i < n(); ++i) w->segment<3>(3 * i) = W[i] * r_all.segment<3>(3 * i);
    }
    if (plain) *plain = r_all;
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

// Weighted least squares on every centre, from zero, by the shared engine (core/least_squares):
// r = the whitened residual w, over the active parameters in report units. Converged when no
// parameter moves by 1e-6 um / mdeg / um/m in a step (far below any resolution), the engine's own
// tolerances off. Returns the Jacobian at the solution for the held-out refits.
SpaceframeFit fitAll(const Problem& pb, const std::vector<int>& active, double sigma_um, Eigen::MatrixXd* J_out) {
  SpaceframeFit f;
  f.active = active;
  const auto np = static_cast<Eigen::Index>(active.size());
  const auto full = [&](const Eigen::VectorXd& p) {
    ModelVector x = ModelVector::Zero();
    for (Eigen::Index k = 0; k < np; ++k) x[active[static_cast<size_t>(k)]] = p[k] / pb.unit[active[static_cast<size_t>(k)]];
    return x;
  };
  // The last two evaluations (w and pb.jacobian = -dw/dp): how far the step's linear prediction
  // missed the residual it reached (the linearisation's check).
  Eigen::VectorXd w_prev, w_now;
  Eigen::MatrixXd J_prev, J_now;
  LeastSquaresOptions lo;
  lo.max_iterations = 10;
  lo.rank_tolerance = 1e-10;
  lo.step_tolerance = std::numeric_limits<double>::min();
  lo.function_tolerance = 0.0;
  lo.converged = [&](const Eigen::VectorXd& before, const Eigen::VectorXd& after) {
    const Eigen::VectorXd step = after - before;
    f.linearisation_um = (w_now - (w_prev - J_prev * step)).cwiseAbs().maxCoeff();
    return step.cwiseAbs().maxCoeff() < 1e-6;
  };
  const LeastSquaresResult solved = solveLeastSquares(
      [&](const Eigen::VectorXd& p, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
        const ModelVector x = full(p);
        Eigen::VectorXd w;
        pb.residuals(x, &w, nullptr);
        w_prev = std::move(w_now);
        J_prev = std::move(J_now);
        w_now = w;
        J_now = pb.jacobian(x, active);
        r = w;
        if (J) *J = -J_now;
      },
      Eigen::VectorXd::Zero(np), lo);
  f.converged = solved.summary.usable();
  f.rank = solved.summary.rank;
  const ModelVector x = full(solved.x);
  Eigen::VectorXd w, plain;
  pb.residuals(x, &w, &plain);
  f.model = FrameModel::fromVector(pb.kin, x);
  const int m = static_cast<int>(w.size());
  f.dof = m - f.rank;
  f.chi2 = w.squaredNorm() / (sigma_um * sigma_um);
  f.residual_rms_um = std::sqrt(plain.squaredNorm() / m);
  // u (k = 1) with the a-posteriori noise: cov = s^2 (J^T J)^-1 in report units.
  const double s_post = f.dof > 0 ? std::sqrt(w.squaredNorm() / f.dof) : 0.0;
  for (Eigen::Index k = 0; k < np; ++k)
    f.u[active[static_cast<size_t>(k)]] = s_post * std::sqrt(solved.covariance(k, k)) / pb.unit[active[static_cast<size_t>(k)]];
  *J_out = J_now;
  return f;
}

}  // namespace

std::vector<std::string> spaceframeCatalog() {
  return {"linear_axis_scale", "linear_axis_squareness", "thermal_drift", "frame_temperature"};
}

SpaceframeDiagnosis diagnoseSpaceframe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                       const SpaceframeDiagnosisOptions& options) {
  requireValid(options.judge, "diagnosis options");
  if (!(options.sigma_um > 0)) throw std::invalid_argument("diagnosis options: the declared probe noise must be > 0 um");
  // The sphere fits and measured centres of the analysis (its own identification is not used).
  SpaceframeOptions so;
  so.max_iterations = 1;
  so.held_out_ids = options.held_out_ids;
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
  // Each centre's time: the mean of its touches' planned times (repeats shift every centre alike).
  double t_mean = 0.0;
  for (const auto& f : pb.points) {
    double t = 0.0;
    for (int id : f.point_ids) t += plan.findPoint(id)->t_s;
    pb.t_h.push_back(t / static_cast<double>(std::max<size_t>(1, f.point_ids.size())) / 3600.0);
    t_mean += pb.t_h.back();
  }
  t_mean /= std::max(1, pb.n());
  for (auto& t : pb.t_h) t -= t_mean;

  SpaceframeDiagnosis d;
  d.centres = pb.n();
  d.fit_noise_um = dof_fit > 0 ? std::sqrt(ss_fit / dof_fit) : 0.0;
  d.sigma_um = options.sigma_um;
  d.declaration = fmt::format("declared: the probe's noise only ({:.3f} um per touch, carried to each centre by its "
                              "sphere fit)", options.sigma_um);
  if (options.noise) {
    d.problem.covariance = spaceframeCentreCovariance(plan, pb.points, *options.noise, static_cast<int>(runs.size()));
    // The adequacy test's null from draws of the declared machine, analyze's own draws.
    d.problem.null_draws = spaceframeCentreNullDraws(plan, pb.points, *options.noise, static_cast<int>(runs.size()),
                                                     kDeclaredNullSeed + 2);
    pb.W_full = inverseSquareRoot(d.problem.covariance);
    d.sigma_um = std::sqrt(options.noise->touch.white_um2);
    d.declaration = options.noise->touch.declaration;
  }
  // With a declared covariance the whitened residual is unitless: chi2 = |W r|^2.
  const double fit_sigma = options.noise ? 1.0 : d.sigma_um;

  JudgeProblem& jp = d.problem;
  // One orientation: the pose's A and C modulo 360 (theta = 0 and 360 are the same table pose).
  std::map<std::pair<long, long>, int> ids;
  JudgeFactor sphere{"sphere", {}, {}, ""}, c_angle{"C", {}, {}, ""}, a_angle{"A", {}, {}, ""}, time{"time", {}, {}, "h"};
  JudgeFactor xyz[3] = {{"X", {}, {}, "mm"}, {"Y", {}, {}, "mm"}, {"Z", {}, {}, "mm"}};
  for (int i = 0; i < pb.n(); ++i) {
    const FramePoint& f = pb.points[static_cast<size_t>(i)];
    const double c360 = std::fmod(std::fmod(f.pose.C, 360.0) + 360.0, 360.0);
    const auto key = std::make_pair(std::lround(f.pose.A * 1e6), std::lround(c360 * 1e6));
    const int g = ids.emplace(key, static_cast<int>(ids.size())).first->second;
    for (int k = 0; k < 3; ++k) {  // three coordinates per centre, one group
      jp.groups.push_back(g);
      sphere.levels.push_back(std::to_string(f.sphere));
      c_angle.levels.push_back(fmt::format("{:g}", c360));
      a_angle.levels.push_back(fmt::format("{:g}", f.pose.A));
      time.values.push_back(pb.t_h[static_cast<size_t>(i)]);
      for (int ax = 0; ax < 3; ++ax) xyz[ax].values.push_back(f.nominal_m_mm[ax]);
    }
  }
  d.holdout_groups = static_cast<int>(ids.size());
  jp.group_name = "orientation";
  jp.factors = {sphere, c_angle, a_angle, time, xyz[0], xyz[1], xyz[2]};

  // Baseline: location errors and the frame, never the scale.
  const std::vector<int> full = activeParameters(layout.nominal_from == "initial");
  std::vector<int> base;
  for (int i : full)
    if (!isScale(i)) base.push_back(i);
  Eigen::MatrixXd Jb;
  d.baseline = fitAll(pb, base, fit_sigma, &Jb);
  // The judge whitens by the declared covariance itself: from here on it reads plain um.
  if (options.noise) pb.raw = true;
  const ModelVector xb = d.baseline.model.toVector();
  // The judge's y: whitened um (unit variance per touch sigma) and sigma the declared noise.
  Eigen::VectorXd w;
  pb.residuals(xb, &w, nullptr);
  jp.y = w;
  jp.declaration = d.declaration;
  if (options.noise) {
    jp.unit = "um";
  } else {
    jp.sigma = Eigen::VectorXd::Constant(w.size(), d.sigma_um);
    jp.unit = "um (whitened by each centre's sphere-fit covariance)";
  }
  jp.J0 = pb.jacobian(xb, base);
  const auto& lp = locationParameters(pb.kin);
  for (int i : base) {
    std::string name, unit;
    if (i < kNumLocationErrors) {
      name = std::string(lp[static_cast<size_t>(i)].name);
      unit = std::string(reportUnit(lp[static_cast<size_t>(i)].kind));
    } else if (i < FrameModel::kRigidSize) {
      const int k = i - kNumLocationErrors - 3;
      name = fmt::format("setup_{}_{}", k < 3 ? "translation" : "rotation", "XYZ"[k % 3]);
      unit = k < 3 ? "um" : "mdeg";
    } else {
      const int k = i - FrameModel::kRigidSize;
      name = fmt::format("sphere{}_offset_{}", k / 3 + 1, "XYZ"[k % 3]);
      unit = "um";
    }
    jp.baseline_parameters.push_back({name, unit});
  }
  // Causes: central differences of the exact centre model at the baseline (whitened um per
  // report unit; steps of 1e-3 report units, as the baseline's own Jacobian).
  auto causeColumns = [&](int k, auto set) {
    Eigen::MatrixXd J(w.size(), k);
    Eigen::VectorXd wp, wm;
    for (int j = 0; j < k; ++j) {
      Problem::Causes cp, cm;
      set(&cp, j, 1e-3);
      set(&cm, j, -1e-3);
      pb.residuals(xb, cp, &wp, nullptr);
      pb.residuals(xb, cm, &wm, nullptr);
      J.col(j) = -(wp - wm) / 2e-3;
    }
    return J;
  };
  const std::vector<std::string> wanted = options.candidates.empty() ? spaceframeCatalog() : options.candidates;
  for (const auto& name : wanted) {
    JudgeCause c;
    c.name = name;
    if (name == "linear_axis_scale") {
      c.description = "the linear axes position with a scale error: actual = read (1 + s)";
      c.J = pb.jacobian(xb, {kNumLocationErrors, kNumLocationErrors + 1, kNumLocationErrors + 2});
      c.parameters = {{"s_x", "um/m"}, {"s_y", "um/m"}, {"s_z", "um/m"}};
    } else if (name == "linear_axis_squareness") {
      c.description = "the linear axes are not square (000 Eq. (23)): E_xy = S_xy y, E_xz = S_xz z, E_yz = S_yz z";
      c.J = causeColumns(3, [](Problem::Causes* p, int j, double h) { p->squareness[j] = h * 1e-6; });
      c.parameters = {{"S_xy", "um/m"}, {"S_xz", "um/m"}, {"S_yz", "um/m"}};
    } else if (name == "thermal_drift") {
      c.description = "the table moves against the spindle at a constant rate (dx, dy, dz of the first rotary axis)";
      c.J = causeColumns(3, [](Problem::Causes* p, int j, double h) { p->drift[j] = h * 1e-3; });
      c.parameters = {{std::string(lp[0].name) + "/h", "um/h"}, {std::string(lp[1].name) + "/h", "um/h"},
                      {std::string(lp[2].name) + "/h", "um/h"}};
    } else if (name == "frame_temperature") {
      c.description = "the frame grows with its temperature about its origin (expansion e, um/m)";
      c.J = causeColumns(1, [](Problem::Causes* p, int, double h) { p->frame_expansion = h * 1e-6; });
      c.parameters = {{"e", "um/m"}};
    } else {
      throw std::invalid_argument("spaceframe diagnosis: unknown cause '" + name + "'");
    }
    jp.causes.push_back(c);
  }
  d.judged = judge(jp, options.judge);
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


/// What separates a confounded entry's causes on this cycle.
std::string separateWith(const JudgeConfounded& c) {
  const bool frame =
      c.cause == "frame_temperature" || std::find(c.with.begin(), c.with.end(), "frame_temperature") != c.with.end();
  return frame ? std::string("a frame whose length is known at its temperature (a calibrated step gauge, or the "
                             "frame's measured temperature and expansion coefficient) separates its expansion "
                             "from the linear axes' scale")
               : "add orientations or spheres where the Jacobian columns of " + c.cause + " and what it is read as differ";
}

}  // namespace

Json spaceframeDiagnosisJson(const SpaceframeDiagnosis& d, const ProbePlan& plan) {
  const JudgeSummary& s = d.judged;
  Json j = judgeToJson(s);
  stampDiagnosis(j, "spaceframe");
  j["machine"] = plan.machine.name;
  // The contract's fields beside the judge's own.
  Json b = fitJson(d.baseline);
  for (auto& [k, v] : b.items()) j["baseline"][k] = v;
  j["baseline"]["model"] =
      "rotary-axis location errors and the frame (its setup on the table; every sphere when it self-calibrates), no "
      "linear-axis errors";
  j["baseline"]["holdout_rms_um"] = s.baseline_holdout_rms;
  j["baseline"]["p_value"] = s.baseline.p_value;
  j["holdout_scheme"] = fmt::format("leave one orientation out ({} orientations, {} centres)", d.holdout_groups, d.centres);
  j["sigma_um"] = round6(d.sigma_um);
  j["declaration"] = d.declaration;
  j["fit_noise_um"] = round6(d.fit_noise_um);
  const auto& lp = locationParameters(plan.machine.kinematics);
  for (size_t k = 0; k < s.findings.size(); ++k) {
    Json& f = j["findings"][k];
    const JudgeFinding& jf = s.findings[k];
    const std::string params = findingParametersText(jf);
    const double gain = holdoutGainPct(s, jf);
    f["summary"] = jf.description + ": " + params;
    // Location errors with the causes: the baseline's plus the judge's linear step.
    Json le = Json::object();
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const std::string name(lp[static_cast<size_t>(i)].name);
      double delta = 0.0, u = 0.0;
      for (const auto& e : s.final_estimates)
        if (e.name == name) {
          delta = e.value;
          u = e.u;
        }
      const double base = d.baseline.model.errors.reportValue(i);
      le[name] = {{"value", round6(base + delta)}, {"unit", std::string(reportUnit(lp[static_cast<size_t>(i)].kind))},
                  {"u", round6(u)}};
    }
    f["location_errors"] = le;
    f["residual_rms_um"] = s.final_model.rms_residual;
    f["holdout_rms_um"] = jf.holdout_rms_cause;
    f["gain_pct"] = gain;
  }
  writeConfounded(j, s, separateWith);
  return j;
}

std::string spaceframeDiagnosisText(const SpaceframeDiagnosis& d) {
  std::string s = fmt::format(
      "spaceframe diagnosis: baseline (location errors + frame) residual {:.3f} um rms over {} centres; declared probe "
      "noise {:.3f} um per touch (the sphere fits' own: {:.3f} um); {}\n",
      d.baseline.residual_rms_um, d.centres, d.sigma_um, d.fit_noise_um, d.declaration);
  return s + judgeText(d.judged, separateWith);
}

}  // namespace rotacal
