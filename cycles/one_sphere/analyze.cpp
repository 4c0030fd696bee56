#include "cycles/one_sphere/analyze.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <utility>

#include "core/contributor_draw.hpp"
#include "core/errors.hpp"
#include "core/report_envelope.hpp"
#include "core/rotary_backlash.hpp"
#include "core/units.hpp"
#include "cycles/one_sphere/design.hpp"
#include "cycles/one_sphere/plan.hpp"
#include "cycles/probing.hpp"

namespace rotacal {

namespace {

std::string fitExtraDescription(const std::string& name) {
  if (name == "dR") return "the probe's effective radius on this sphere less R + r";
  if (name.rfind("backlash_", 0) == 0)
    return fmt::format("lost motion of the {} axis: it stops half of it short of its command, in the direction it last "
                       "moved (read from both sides of the plan's there-and-back poses)",
                       name.back());
  if (name.rfind("lead_in_", 0) == 0)
    return fmt::format("offset of the {} axis at the touches before the plan first moves it (it came from wherever the "
                       "machine stood): a nuisance parameter, so that the lost motion assumes nothing about the start",
                       name.back());
  if (name == "S_xy") return "out-of-squareness of the linear axes X and Y: X's error along Y (000 Eq. (23); mdeg, 1 mdeg = 17.45 um/m)";
  if (name == "S_xz") return "out-of-squareness of the linear axes X and Z: X's error along Z (000 Eq. (23); mdeg, 1 mdeg = 17.45 um/m)";
  return "out-of-squareness of the linear axes Y and Z: Y's error along Z (000 Eq. (23); mdeg, 1 mdeg = 17.45 um/m)";
}

double toReport(ParamKind kind, double v) { return kind == ParamKind::Length ? mmToUm(v) : radToMdeg(v); }

struct Trigger {
  Eigen::Vector3d t_mm;
  Pose pose;
  Eigen::Vector3d direction;  // of each rotary axis's last move (rotaryApproachDirections)
  int point_index;
  int run;
  double t_s;
};

}  // namespace

SphereCycleResult identifySphereCycle(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                      const SphereCycleOptions& options) {
  const SphereLayout l = sphereLayoutOf(plan);
  const Kinematics kin = plan.machine.kinematics;
  SphereCycleResult out;
  out.model = sphereModel(plan.machine, l.center_w_mm);
  const KinematicModel& m = out.model;
  const int np = m.size();
  const bool sq = l.fit_squareness;
  out.names = sphereFitParameters(m, sq);
  const std::vector<Eigen::Vector3d> directions = rotaryApproachDirections(plan, false);
  if (l.backlash) out.backlash = appendBacklashParameters(plan.machine, directions, &out.names);
  const SphereBacklashTerms& terms = out.backlash;
  const auto nx = static_cast<Eigen::Index>(out.names.size());
  const double rho = l.radius_mm + plan.machine.probe.ball_radius_mm();

  // Every touch of the plan (what the plan can separate is decided on them all) and the fitted ones.
  std::vector<Trigger> all, triggers, held;
  for (const PlannedTrigger& pt : triggersInPlanOrder(plan, runs)) {
    const Trigger t{pt.trigger->position_m_mm, plan.points[pt.point_index].pose, directions[pt.point_index],
                    static_cast<int>(pt.point_index), pt.run, pt.t_s};
    all.push_back(t);
    (options.hold_out && options.hold_out(pt.run, plan.points[pt.point_index]) ? held : triggers).push_back(t);
  }
  out.touches = static_cast<int>(triggers.size());

  // What the plan can show, at nominal: the held parameters stay at 0, the others are fitted.
  const auto jacobian = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
    r.resize(static_cast<Eigen::Index>(triggers.size()));
    if (J) J->resize(r.size(), nx);
    Eigen::RowVectorXd row;
    for (size_t j = 0; j < triggers.size(); ++j) {
      const auto jj = static_cast<Eigen::Index>(j);
      r[jj] = sphereTouchResidual(m, sq, terms, x, triggers[j].pose, triggers[j].direction, triggers[j].t_mm, rho,
                                  J ? &row : nullptr);
      if (J) J->row(jj) = row;
    }
  };
  // The plan's Jacobian, at its nominal triggers: what this plan confounds, whatever the data.
  // (At the measured triggers a direction the plan confounds exactly, such as the squareness
  // under a head, is only nearly null, and its rounding leaks into the exact null directions.)
  Eigen::MatrixXd J0(static_cast<Eigen::Index>(all.size()), nx);
  {
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(nx);
    Eigen::RowVectorXd row;
    for (size_t j = 0; j < all.size(); ++j) {
      sphereTouchResidual(m, sq, terms, zero, all[j].pose, all[j].direction,
                          plan.points[static_cast<size_t>(all[j].point_index)].trigger_m_mm, rho, &row);
      J0.row(static_cast<Eigen::Index>(j)) = row;
    }
  }
  out.identifiability = identifiability(J0, out.names, sphereHeldFirst(m));
  std::vector<Eigen::Index> free;
  for (Eigen::Index i = 0; i < nx; ++i)
    if (!out.identifiability.held[static_cast<size_t>(i)]) free.push_back(i);
  const auto nf = static_cast<Eigen::Index>(free.size());
  const auto expand = [&](const Eigen::VectorXd& z) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(nx);
    for (Eigen::Index k = 0; k < nf; ++k) x[free[static_cast<size_t>(k)]] = z[k];
    return x;
  };
  const LeastSquaresResult fit = solveLeastSquares(
      [&](const Eigen::VectorXd& z, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
        Eigen::MatrixXd Jf;
        jacobian(expand(z), r, J ? &Jf : nullptr);
        if (J) {
          J->resize(r.size(), nf);
          for (Eigen::Index k = 0; k < nf; ++k) J->col(k) = Jf.col(free[static_cast<size_t>(k)]);
        }
      },
      Eigen::VectorXd::Zero(nf));
  out.summary = fit.summary;
  if (!fit.summary.usable())
    throw InputError(runs.empty() ? std::string("results") : runs.front().source, 0,
                     "the sphere cycle's fit did not converge: " + fit.summary.briefReport());
  if (!held.empty() && fit.summary.rank < nf)
    throw InputError(runs.empty() ? std::string("results") : runs.front().source, 0,
                     fmt::format("with {} touches left out the sphere cycle's fit sees {} of its {} parameters",
                                 held.size(), fit.summary.rank, nf));
  out.x = expand(fit.x);
  out.cov_per_sigma2 = Eigen::MatrixXd::Zero(nx, nx);
  for (Eigen::Index a = 0; a < nf; ++a)
    for (Eigen::Index b = 0; b < nf; ++b)
      out.cov_per_sigma2(free[static_cast<size_t>(a)], free[static_cast<size_t>(b)]) = fit.covariance(a, b);
  Eigen::VectorXd r;
  jacobian(out.x, r, &out.J_r_x);
  for (const auto& t : triggers) {
    out.normals.push_back(sphereTouchNormal(m, sq, out.x, backlashPose(terms, out.x, t.pose, t.direction), t.t_mm));
    out.point_index.push_back(t.point_index);
    out.run_index.push_back(t.run);
    out.t_s.push_back(t.t_s);
  }
  out.dof = out.touches - fit.summary.rank;
  out.residual_sd_um = out.dof > 0 ? mmToUm(std::sqrt(r.squaredNorm() / out.dof)) : 0.0;
  for (Eigen::Index j = 0; j < r.size(); ++j) out.residuals_um.push_back(mmToUm(r[j]));
  for (const auto& t : held)
    out.held_out.push_back({t.point_index, t.run,
                            mmToUm(sphereTouchResidual(m, sq, terms, out.x, t.pose, t.direction, t.t_mm, rho, nullptr))});

  // The papers' parameters, for the offsets and the reports that speak them (tilting tables:
  // a head machine's are its ISO 230-7 parameters alone).
  out.location.kinematics = kin;
  if (!hasPapersLocationErrors(kin)) return out;
  const auto& pairs = spherePapersNames(kin);
  for (const auto& [paper, iso] : pairs) {
    const int i = parameterIndex(kin, paper);
    const int k = m.parameterIndex(iso);
    out.location.values[i] = out.x[k];
    out.location_index_in_x[static_cast<size_t>(i)] = k;
  }
  const Eigen::Vector3d setup(out.x[m.parameterIndex("dX_S")], out.x[m.parameterIndex("dY_S")],
                              out.x[m.parameterIndex("dZ_S")]);
  for (const auto& pose : plan.poses) {
    const Eigen::Vector3d papers = T_m_w(out.location, pose.pose) * (l.center_w_mm + setup);
    out.mapping_residual_um = std::max(out.mapping_residual_um,
                                       mmToUm((papers - sphereCentreInAxes(m, out.x.head(np), pose.pose)).norm()));
  }
  return out;
}

DeclaredNoise sphereDeclaredNoise(const ProbePlan& plan, const ContributorSet* declared) {
  DeclaredNoise noise = perTouchDeclaration(declared, plan.machine.probe.repeatability_um);
  if (!declared) return noise;
  const SphereLayout l = sphereLayoutOf(plan);
  const KinematicModel m = sphereModel(plan.machine, l.center_w_mm);
  const Eigen::VectorXd nominal = Eigen::VectorXd::Zero(m.size());
  std::vector<Eigen::Vector3d> t, u;
  Eigen::VectorXd nu(static_cast<Eigen::Index>(plan.points.size()));
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const ProbePoint& p = plan.points[i];
    t.push_back(p.trigger_m_mm);
    u.push_back(p.approach_m);
    const Eigen::Vector3d n = (p.trigger_m_mm - sphereCentreInAxes(m, nominal, p.pose)).normalized();
    nu[static_cast<Eigen::Index>(i)] = n.dot(p.approach_m);
  }
  addProbeAxesPart(*declared, t, u, nu, &noise);
  return noise;
}

SphereFittedProblem sphereFittedProblem(const DeclaredNoise& noise, const SphereCycleResult& r) {
  const auto n = static_cast<Eigen::Index>(r.residuals_um.size());
  SphereFittedProblem f;
  f.residual_um = Eigen::Map<const Eigen::VectorXd>(r.residuals_um.data(), n);
  std::vector<std::pair<int, int>> kept;
  for (Eigen::Index j = 0; j < n; ++j)
    kept.emplace_back(r.run_index[static_cast<size_t>(j)], r.point_index[static_cast<size_t>(j)]);
  f.covariance_um2 = noise.covariance(kept);
  f.readings = kept;
  f.J.resize(n, 0);
  for (size_t i = 0; i < r.names.size(); ++i) {
    if (r.identifiability.held[i]) continue;
    f.J.conservativeResize(n, f.J.cols() + 1);
    f.J.col(f.J.cols() - 1) = r.J_r_x.col(static_cast<Eigen::Index>(i));
  }
  return f;
}

SphereScreen screenSphereTouches(const ProbePlan& plan, const std::vector<MeasurementRun>& runs, const DeclaredNoise& noise) {
  // Each fit the screen asks for, by the touches it holds out: the statistic reads its Jacobian.
  using Key = std::vector<std::pair<int, int>>;  // (run, point id), sorted
  const auto fits = std::make_shared<std::map<Key, std::shared_ptr<const SphereCycleResult>>>();
  const auto keyOf = [](const std::vector<PointResidual>& residuals) { return heldOutTouches(residuals); };
  const auto fit = [&](const std::function<bool(int, const ProbePoint&)>& hold) {
    ScreenedFit out;
    std::shared_ptr<const SphereCycleResult> r;
    if (!hold) {
      r = std::make_shared<const SphereCycleResult>(identifySphereCycle(plan, runs));
    } else {
      try {
        r = std::make_shared<const SphereCycleResult>(identifySphereCycle(plan, runs, {hold}));
      } catch (const InputError& e) {
        // This touch cannot be left out (the fit loses a parameter): the screen keeps it.
        out.summary.termination = Termination::RankDeficient;
        out.summary.message = e.what();
        return out;
      }
    }
    out.summary.termination = Termination::Converged;
    for (size_t j = 0; j < r->residuals_um.size(); ++j)
      out.residuals.push_back({r->run_index[j], plan.points[static_cast<size_t>(r->point_index[j])].id, r->residuals_um[j],
                               0.0, false});
    for (const auto& h : r->held_out)
      out.residuals.push_back({h.run, plan.points[static_cast<size_t>(h.point_index)].id, h.residual_um, 0.0, true});
    (*fits)[keyOf(out.residuals)] = r;
    return out;
  };
  SphereScreen s;
  s.options.sigma_um = std::sqrt(noise.white_um2);
  s.options.declaration = noise.declaration;
  s.options.statistic = [fits, keyOf, noise](const ScreenedFit& f) {
    const auto it = fits->find(keyOf(f.residuals));
    if (it == fits->end()) throw std::logic_error("sphere outlier screen: a statistic asked of a fit never made");
    const SphereFittedProblem p = sphereFittedProblem(noise, *it->second);
    return deletionStatistics(p.residual_um, p.J, p.covariance_um2);
  };
  s.options.null_maxima = [fits, keyOf, noise](const ScreenedFit& f) {
    const SphereFittedProblem p = sphereFittedProblem(noise, *fits->at(keyOf(f.residuals)));
    const Eigen::MatrixXd draws = noise.nullDraws(p.readings, kDeclaredNullSeed + 1);
    if (draws.cols() == 0) return Eigen::VectorXd();
    return screenNullMaxima(deletionStatisticsColumns(draws, p.J, p.covariance_um2));
  };
  s.options.sensitivity = [fits, keyOf, noise](const ScreenedFit& f) {
    const SphereFittedProblem p = sphereFittedProblem(noise, *fits->at(keyOf(f.residuals)));
    return deletionSensitivity(p.J, p.covariance_um2);
  };
  s.screen = screenOutliers(fit, s.options);
  const Key last = [&] {
    Key k;
    for (const auto& e : s.screen.excluded) k.emplace_back(e.run, e.point_id);
    std::sort(k.begin(), k.end());
    return k;
  }();
  const auto it = fits->find(last);
  s.fit = it != fits->end() ? *it->second : identifySphereCycle(plan, runs, {s.screen.holdOut()});
  return s;
}

Json sphereReportJson(const ProbePlan& plan, const SphereCycleResult& r, const UncertaintyBudget& b,
                      const std::vector<std::string>& files) {
  Json j = documentEnvelope("rotacal-report/1", plan, files);
  j["method"] = "sphere_lsq";
  ErrorVector u = ErrorVector::Zero();
  const Eigen::VectorXd uc = b.uC();
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const int k = r.location_index_in_x[static_cast<size_t>(i)];
    for (int q = 0; q < b.size(); ++q)
      if (b.names[static_cast<size_t>(q)] == r.names[static_cast<size_t>(k)].name) {
        // back to mm / rad, as locationErrorsJson takes them
        u[i] = r.names[static_cast<size_t>(k)].kind == ParamKind::Length ? umToMm(uc[q]) : mdegToRad(uc[q]);
      }
  }
  if (hasPapersLocationErrors(plan.machine.kinematics)) {
    j["location_errors"] = locationErrorsJson(r.location, u);
    j["location_errors_note"] = fmt::format(
        "the machine's papers' parameters ({}), each the ISO 230-7 parameter of kinematic_parameters it is to first "
        "order; the two models' sphere positions differ by at most {:.6f} um over the plan's poses",
        plan.machine.kinematics == Kinematics::TableAC   ? "000 Eq. (1)"
        : plan.machine.kinematics == Kinematics::TableBC ? "002 Eq. (2)"
                                                          : "the A/B table's chain in 002's style, docs/conventions.md",
        r.mapping_residual_um);
  } else {
    j["location_errors_note"] = fmt::format(
        "a {} machine: its location errors are the ISO 230-7 parameters of kinematic_parameters, in the uncertainty "
        "table (the papers' eight describe tilting tables)",
        kinematicsName(plan.machine.kinematics));
  }
  Json kp = Json::object();
  for (size_t i = 0; i < r.names.size(); ++i) {
    const auto& q = r.names[i];
    Json e = {{"value", round6(toReport(q.kind, r.x[static_cast<Eigen::Index>(i)]))}, {"unit", reportUnit(q.kind)}};
    if (r.identifiability.held[i]) e["held"] = true;
    // The sphere's place on the table: a new set-up every calibration (history leaves it out).
    if (q.name == "dX_S" || q.name == "dY_S" || q.name == "dZ_S") e["set_up"] = true;
    else e["separable"] = static_cast<bool>(r.identifiability.separable[i]);
    e["description"] = i < r.model.parameters.size() ? r.model.parameters[i].description : fitExtraDescription(q.name);
    kp[q.name] = e;
  }
  // Each fitted parameter's budget beside its value (u_between: what history trends with).
  addBudgetFields(&kp, b);
  j["kinematic_parameters"] = kp;
  // Each of the papers' location errors is one model parameter to first order: its budget too.
  if (j.contains("location_errors"))
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const std::string& model = r.names[static_cast<size_t>(r.location_index_in_x[static_cast<size_t>(i)])].name;
      const std::string paper(locationParameters(plan.machine.kinematics)[static_cast<size_t>(i)].name);
      if (!kp.contains(model) || !j["location_errors"].contains(paper)) continue;
      // The fit's own name of it: the uncertainty's covariance is in the fit's names.
      j["location_errors"][paper]["parameter"] = model;
      if (!kp[model].contains("u_c")) continue;
      for (const char* f : {"u", "u_a", "u_b", "u_c", "u_between", "U", "k"}) j["location_errors"][paper][f] = kp[model][f];
    }
  Json unseen = Json::array();
  for (const auto& c : r.identifiability.combinations)
    unseen.push_back({{"held", r.names[static_cast<size_t>(c.held)].name}, {"direction", c.text}});
  j["unseparable"] = unseen;
  // The envelope's figures every report shows (the fit's own below): rms over the touches.
  j["points_used"] = r.touches;
  j["residual_rms_um"] = round6(r.touches > 0 ? r.residual_sd_um * std::sqrt(static_cast<double>(r.dof) / r.touches) : 0.0);
  j["fit"] = {{"touches", r.touches},
              {"dof", r.dof},
              {"residual_sd_um", round6(r.residual_sd_um)},
              {"rank", r.summary.rank},
              {"termination", std::string(terminationName(r.summary.termination))}};
  Eigen::VectorXd values(b.size());
  for (int q = 0; q < b.size(); ++q)
    for (size_t i = 0; i < r.names.size(); ++i)
      if (r.names[i].name == b.names[static_cast<size_t>(q)])
        values[q] = toReport(r.names[i].kind, r.x[static_cast<Eigen::Index>(i)]);
  j["uncertainty"] = budgetJson(b, values);
  return j;
}

Json sphereFiguresJson(const ProbePlan& plan, const SphereCycleResult& r, double white_sd_um) {
  // Each touch's residual against each rotary axis the plan turns and against time: a pattern in
  // the angle is what the model misses (diagnose names it), scatter within the band is the probe's.
  struct Touch {
    const ProbePoint* point;
    double t_s, residual_um;
  };
  std::vector<Touch> fitted, left_out;
  for (size_t j = 0; j < r.residuals_um.size(); ++j)
    fitted.push_back({&plan.points[static_cast<size_t>(r.point_index[j])], r.t_s[j], r.residuals_um[j]});
  for (const auto& h : r.held_out) {
    const ProbePoint& p = plan.points[static_cast<size_t>(h.point_index)];
    left_out.push_back({&p, p.t_s, h.residual_um});
  }
  const auto series = [](const std::string& name, const std::vector<Touch>& touches, const std::function<double(const Touch&)>& x) {
    std::vector<double> xs, ys;
    for (const auto& t : touches) {
      xs.push_back(round6(x(t)));
      ys.push_back(round6(t.residual_um));
    }
    return Json{{"name", name}, {"style", "points"}, {"x", xs}, {"y", ys}};
  };
  const auto figure = [&](const std::string& id, const std::string& title, const std::string& x_label,
                          const std::string& x_unit, const std::function<double(const Touch&)>& x) {
    Json ser = Json::array({series("touches fitted", fitted, x)});
    if (!left_out.empty()) ser.push_back(series("left out by the outlier screen", left_out, x));
    double lo = 0.0, hi = 0.0;
    bool first = true;
    for (const auto* set : {&fitted, &left_out})
      for (const auto& t : *set) {
        const double v = x(t);
        lo = first ? v : std::min(lo, v);
        hi = first ? v : std::max(hi, v);
        first = false;
      }
    Json fig = {{"id", id},
                {"title", title},
                {"x", {{"label", x_label}, {"unit", x_unit}}},
                {"y", {{"label", "residual"}, {"unit", "um"}}},
                {"series", ser}};
    if (white_sd_um > 0.0 && hi > lo)
      fig["bands"] = Json::array({{{"name", fmt::format("+-2 x the declared per-touch scatter ({:.2f} um)", white_sd_um)},
                                   {"x", {round6(lo), round6(hi)}},
                                   {"lo", {round6(-2 * white_sd_um), round6(-2 * white_sd_um)}},
                                   {"hi", {round6(2 * white_sd_um), round6(2 * white_sd_um)}}}});
    return fig;
  };
  Json figs = Json::array();
  for (const char axis : {'A', 'B', 'C'}) {
    bool turns = false;
    for (const auto& p : plan.points) turns = turns || std::abs(p.pose.angle(axis) - plan.points.front().pose.angle(axis)) > 1e-9;
    if (!turns) continue;
    figs.push_back(figure(fmt::format("one_sphere_residual_{}", static_cast<char>(axis - 'A' + 'a')), fmt::format("Residual of each touch against {}", axis),
                          std::string(1, axis), "deg", [axis](const Touch& t) { return t.point->pose.angle(axis); }));
  }
  figs.push_back(figure("one_sphere_residual_time", "Residual of each touch against time", "time", "min",
                        [](const Touch& t) { return t.t_s / 60.0; }));
  for (auto& f : figs)
    f["note"] = "the ball centre's distance from the fitted sphere's centre less the two radii (outward positive). "
                "The declared scatter is the white per-touch part; the linear axes' declared errors add a shared part on top.";
  return figs;
}

std::string sphereText(const SphereCycleResult& r, const UncertaintyBudget& b) {
  std::string s = fmt::format("sphere cycle: {} touches, residual {:.3f} um rms ({} dof), rank {} of {}\n", r.touches,
                              r.residual_sd_um, r.dof, r.summary.rank, r.names.size());
  Eigen::VectorXd values(b.size());
  for (int q = 0; q < b.size(); ++q)
    for (size_t i = 0; i < r.names.size(); ++i)
      if (r.names[i].name == b.names[static_cast<size_t>(q)])
        values[q] = toReport(r.names[i].kind, r.x[static_cast<Eigen::Index>(i)]);
  s += budgetText(b, values);
  if (!r.identifiability.combinations.empty()) {
    s += "not separable by one sphere (held at nominal; the others read relative to it):\n";
    for (const auto& c : r.identifiability.combinations) s += "  " + c.text + "\n";
  }
  if (hasPapersLocationErrors(r.location.kinematics))
    s += fmt::format("location errors in the papers' parameters: the model's to first order, {:.6f} um apart at most\n",
                     r.mapping_residual_um);
  return s;
}

}  // namespace rotacal
