#include "cycles/tooltip/diagnose.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/require_valid.hpp"
#include "core/units.hpp"
#include "cycles/judge_contract.hpp"
#include "cycles/tooltip/noise.hpp"

namespace rotacal {

bool TooltipDiagnosisOptions::validate(std::string* why) const {
  if (!judge.validate(why)) return false;
  if (!(noise_um >= 0) || !std::isfinite(noise_um)) return invalidBecause(why, "noise_um (the declared laser noise) must be >= 0");
  return true;
}

namespace {

constexpr const char* kPivot = "pivot_length";
constexpr const char* kScale = "linear_axis_scale";
constexpr const char* kDrift = "thermal_drift";

int angleIndex(const std::vector<double>& angles, double a) {
  for (size_t j = 0; j < angles.size(); ++j)
    if (std::abs(angles[j] - a) < 1e-9) return static_cast<int>(j);
  throw std::logic_error("tooltip: angle not in the plan");
}

/// The distinct commanded angles of the stepping axis in a plan, ascending (analyze's layout).
std::vector<double> planAngles(const ProbePlan& plan, char axis) {
  std::vector<double> a;
  for (const auto& pt : plan.points) {
    const double v = axis == 'A' ? pt.pose.A : pt.pose.B;
    if (std::none_of(a.begin(), a.end(), [&](double w) { return std::abs(w - v) < 1e-9; })) a.push_back(v);
  }
  std::sort(a.begin(), a.end());
  return a;
}

}  // namespace

TooltipJudgeSetup tooltipJudgeSetup(const std::vector<TooltipSet>& sets, double noise_um,
                                    const ContributorSet* contributors) {
  if (sets.empty() || sets.front().runs.empty()) throw std::invalid_argument("tooltip diagnose: no results");
  if (!(noise_um > 0)) throw std::invalid_argument("tooltip diagnose: the declared laser noise must be > 0");
  const TooltipOptions o0 = tooltipOptionsFrom(sets.front().plan->options, sets.front().plan->machine);
  TooltipJudgeSetup s;
  // The shared angles: the union over the sets (one axis, so one error per commanded angle).
  for (const auto& set : sets) {
    const TooltipOptions o = tooltipOptionsFrom(set.plan->options, set.plan->machine);
    if (o.axis != o0.axis) throw std::invalid_argument("tooltip diagnose: the plans step different axes");
    for (double a : planAngles(*set.plan, o.axis))
      if (std::none_of(s.angles_deg.begin(), s.angles_deg.end(), [&](double w) { return std::abs(w - a) < 1e-9; }))
        s.angles_deg.push_back(a);
  }
  std::sort(s.angles_deg.begin(), s.angles_deg.end());
  const int na = static_cast<int>(s.angles_deg.size());
  // The linearisation point: 004's model fitted to the first set (exactly its solution when
  // there is one set, so y is the baseline's own residual).
  TooltipFitOptions fo;
  fo.fit_pivot_length = false;
  s.baseline = fitTooltip(*sets.front().plan, sets.front().runs, fo);
  Eigen::VectorXd e_lin = Eigen::VectorXd::Zero(na);  // rad
  // An angle the screen left out of the first set has no value there (NaN): it is linearised at
  // zero (its own column in J0 takes what it is; the model is linear in it to (e R)^2 / R).
  for (size_t k = 0; k < s.baseline.angles_deg.size(); ++k)
    if (std::isfinite(s.baseline.e_mdeg[k]))
      e_lin[angleIndex(s.angles_deg, s.baseline.angles_deg[k])] = mdegToRad(s.baseline.e_mdeg[k]);

  // A drift is testable where an angle is read at two different times since its sweep's zero
  // (the dynamic test of 004 Sec. VI). Static repeats re-zero and read each angle at the same
  // time since the zero: there a drift is a function of the angle, read as the angular errors
  // plus a radial pattern (a principal angle of about 2 deg to them), so it is not offered.
  bool repeated = false;
  int total_runs = 0;
  for (const auto& set : sets) {
    total_runs += static_cast<int>(set.runs.size());
    const ProbePlan& plan = *set.plan;
    const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
    const std::vector<int> refs = tooltipReferences(plan);
    std::vector<std::pair<double, double>> seen;  // (angle, time since the zero)
    for (size_t k = 0; k < plan.points.size(); ++k) {
      if (refs[k] == static_cast<int>(k)) continue;
      const double a = o.axis == 'A' ? plan.points[k].pose.A : plan.points[k].pose.B;
      const double t = plan.points[k].t_s - plan.points[static_cast<size_t>(refs[k])].t_s;
      for (const auto& [a2, t2] : seen) repeated = repeated || (std::abs(a2 - a) < 1e-9 && std::abs(t2 - t) > 1e-6);
      seen.emplace_back(a, t);
    }
  }
  const bool by_repeat = total_runs >= 3;

  std::vector<double> y, tau;
  std::vector<Eigen::VectorXd> j0, piv, sc;
  std::vector<int> group, comp;
  std::vector<std::pair<int, int>> kept;  // (set, 2 k + c) of each value: the declaration's index
  std::vector<int> kept_run;              // each value's run over all sets: whose laser zero it reads against
  JudgeFactor f_angle{"angle", {}, {}, ""}, f_comp{"component", {}, {}, ""}, f_rep{"repeat", {}, {}, ""},
      f_time{"time", {}, {}, "h"}, f_tool{"tool", {}, {}, ""};
  const char tname = o0.axis == 'A' ? 'Y' : 'X';
  int run_global = 0;
  for (size_t si = 0; si < sets.size(); ++si) {
    const ProbePlan& plan = *sets[si].plan;
    const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
    const std::vector<double> own = planAngles(plan, o.axis);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(own.size()) + 1);
    for (size_t k = 0; k < own.size(); ++k) x[static_cast<Eigen::Index>(k)] = e_lin[angleIndex(s.angles_deg, own[k])];
    const TooltipModelEval ev = evaluateTooltipModel(plan, sets[si].runs, x);
    const std::vector<int> refs = tooltipReferences(plan);
    const int ti = o.axis == 'A' ? 1 : 0;
    int obs = 0;
    for (size_t r = 0; r < sets[si].runs.size(); ++r, ++run_global) {
      const TooltipRun& run = sets[si].runs[r];
      for (size_t k = 0; k < run.size(); ++k) {
        if (refs[k] == static_cast<int>(k)) continue;  // the zero reading: 0 by construction
        const Pose& pose = plan.points[k].pose;
        const Pose& ref = plan.points[static_cast<size_t>(refs[k])].pose;
        const Eigen::Vector3d dF = tipOffset_m(degToRad(ref.A), degToRad(ref.B), o.radius_mm) -
                                   tipOffset_m(degToRad(pose.A), degToRad(pose.B), o.radius_mm);  // mm
        const double th = o.axis == 'A' ? pose.A : pose.B;
        const double t_h = (plan.points[k].t_s - plan.points[static_cast<size_t>(refs[k])].t_s) / 3600.0;
        for (int c = 0; c < 2; ++c) {
          const Eigen::Index row = 2 * obs + c;
          if (!std::isfinite(c == 0 ? run[k].t_um : run[k].z_um)) continue;  // left out by the screen
          kept.emplace_back(static_cast<int>(si), static_cast<int>(2 * k) + c);
          kept_run.push_back(run_global);
          comp.push_back(c);
          y.push_back((c == 0 ? run[k].t_um : run[k].z_um) - ev.model_um[row]);
          Eigen::VectorXd jr = Eigen::VectorXd::Zero(na);
          for (size_t q = 0; q < own.size(); ++q)
            jr[angleIndex(s.angles_deg, own[q])] += ev.J_model_x(row, static_cast<Eigen::Index>(q)) * mdegToRad(1.0);
          j0.push_back(jr);
          Eigen::VectorXd p(1);
          p[0] = ev.J_model_x(row, static_cast<Eigen::Index>(own.size())) * umToMm(1.0);  // um per um of dR
          piv.push_back(p);
          // s in um/m moves the pivot by s x 1e-6 x its command (mm): s x 1e-3 x dF um.
          Eigen::VectorXd sv = Eigen::VectorXd::Zero(2);
          sv[c] = 1e-3 * (c == 0 ? dF[ti] : dF.z());
          sc.push_back(sv);
          tau.push_back(t_h);
          group.push_back(by_repeat ? run_global : angleIndex(s.angles_deg, th));
          f_angle.levels.push_back(fmt::format("{:g}", th));
          f_comp.levels.push_back(std::string(1, c == 0 ? tname : 'Z'));
          f_rep.levels.push_back(sets.size() > 1 ? fmt::format("{}/{}", si + 1, r + 1) : std::to_string(r + 1));
          f_time.values.push_back(t_h);
          f_tool.levels.push_back(fmt::format("R={:g}", o.radius_mm));
        }
        ++obs;
      }
    }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(y.size());
  JudgeProblem& pb = s.problem;
  pb.unit = "um";
  pb.y = Eigen::Map<const Eigen::VectorXd>(y.data(), n);
  // Each set's per-reading variance, for the laser's zero below.
  std::vector<double> white;
  if (!contributors) {
    pb.sigma = Eigen::VectorXd::Constant(n, noise_um);
    pb.declaration = fmt::format("declared: laser noise {:.3f} um only (laser_noise_um)", noise_um);
    white.assign(sets.size(), noise_um * noise_um);
    pb.covariance = pb.sigma.array().square().matrix().asDiagonal();
  } else {
    // The machine's declaration: white per value of each set's plan, the structured part shared
    // between every value of every set and repeat (one machine), about the first run's readings.
    std::vector<const ProbePlan*> plans;
    std::vector<const TooltipRun*> about;
    std::vector<Eigen::Index> first;
    Eigen::Index m = 0;
    for (const auto& set : sets) {
      plans.push_back(set.plan);
      about.push_back(&set.runs.front());
      const DeclaredNoise dn = tooltipDeclaredNoise(*set.plan, contributors);
      white.push_back(dn.white_um2);
      if (pb.declaration.empty()) pb.declaration = dn.declaration;
      first.push_back(m);
      m += 2 * static_cast<Eigen::Index>(set.plan->points.size());
    }
    const Eigen::MatrixXd S = tooltipStructuredUm2(plans, *contributors, about);
    pb.covariance.resize(n, n);
    for (Eigen::Index a = 0; a < n; ++a)
      for (Eigen::Index b = 0; b < n; ++b) {
        const auto& ka = kept[static_cast<size_t>(a)];
        const auto& kb = kept[static_cast<size_t>(b)];
        pb.covariance(a, b) = S(first[static_cast<size_t>(ka.first)] + ka.second, first[static_cast<size_t>(kb.first)] + kb.second);
      }
    for (Eigen::Index a = 0; a < n; ++a) pb.covariance(a, a) += white[static_cast<size_t>(kept[static_cast<size_t>(a)].first)];
  }
  // The laser's zero, read once per run with the per-reading scatter: shared by the values of
  // one run (cycles/tooltip/noise.hpp), not between runs or tools (each zeroes anew).
  std::vector<Eigen::MatrixXd> per_run;
  for (size_t si = 0; si < sets.size(); ++si) per_run.push_back(tooltipPerRunUm2(*sets[si].plan, white[si]));
  for (Eigen::Index a = 0; a < n; ++a)
    for (Eigen::Index b = 0; b < n; ++b) {
      const auto& ka = kept[static_cast<size_t>(a)];
      const auto& kb = kept[static_cast<size_t>(b)];
      if (kept_run[static_cast<size_t>(a)] == kept_run[static_cast<size_t>(b)])
        pb.covariance(a, b) += per_run[static_cast<size_t>(ka.first)](ka.second, kb.second);
    }
  pb.J0.resize(n, na);
  for (Eigen::Index i = 0; i < n; ++i) pb.J0.row(i) = j0[static_cast<size_t>(i)].transpose();
  for (double a : s.angles_deg) pb.baseline_parameters.push_back({fmt::format("e({}={:g})", o0.axis, a), "mdeg"});
  JudgeCause pivot{kPivot, "the tool tip is farther from the pivot than the program assumes", Eigen::MatrixXd(n, 1),
                   {{"dR", "um"}}};
  JudgeCause scale{kScale, fmt::format("the {} and Z axes position with a scale error", tname), Eigen::MatrixXd(n, 2),
                   {{fmt::format("s_{}", tname), "um/m"}, {"s_Z", "um/m"}}};
  for (Eigen::Index i = 0; i < n; ++i) {
    pivot.J(i, 0) = piv[static_cast<size_t>(i)][0];
    scale.J.row(i) = sc[static_cast<size_t>(i)].transpose();
  }
  pb.causes = {pivot, scale};
  if (repeated) {
    JudgeCause drift{kDrift, "the tool tip drifts in the read plane with time", Eigen::MatrixXd::Zero(n, 2),
                     {{fmt::format("d{}/h", tname), "um/h"}, {"dZ/h", "um/h"}}};
    for (Eigen::Index i = 0; i < n; ++i) drift.J(i, comp[static_cast<size_t>(i)]) = tau[static_cast<size_t>(i)];
    pb.causes.push_back(drift);
  }
  pb.groups = group;
  pb.group_name = by_repeat ? "repeat" : "commanded angle";
  pb.factors = {f_angle, f_comp, f_rep, f_time};
  if (sets.size() > 1) pb.factors.push_back(f_tool);
  return s;
}

TooltipDiagnosis diagnoseTooltip(const std::vector<TooltipSet>& sets, const TooltipDiagnosisOptions& o) {
  requireValid(o, "tooltip diagnosis");
  if (sets.empty()) throw std::invalid_argument("tooltip diagnose: no results");
  TooltipDiagnosis d;
  const double noise =
      o.noise_um > 0 ? o.noise_um : tooltipOptionsFrom(sets.front().plan->options, sets.front().plan->machine).noise_um;
  d.setup = tooltipJudgeSetup(sets, noise, o.contributors);
  d.sets = static_cast<int>(sets.size());
  for (const auto& s : sets) {
    d.runs += static_cast<int>(s.runs.size());
    d.radius_mm.push_back(tooltipOptionsFrom(s.plan->options, s.plan->machine).radius_mm);
  }
  d.summary = judge(d.setup.problem, o.judge);
  return d;
}

namespace {

const JudgeEstimate* paramOf(const JudgeFinding& f, size_t i) { return i < f.parameters.size() ? &f.parameters[i] : nullptr; }

std::string separateWith(const JudgeConfounded& c) {
  // `with` names another cause, or a parameter of an accepted one ("pivot_length.dR").
  auto is = [](const std::string& w, const std::string& cause) { return w == cause || w.rfind(cause + ".", 0) == 0; };
  const bool pivot_scale = (c.cause == kPivot || c.cause == kScale) &&
                           std::any_of(c.with.begin(), c.with.end(), [&](const std::string& w) {
                             return is(w, kPivot) || is(w, kScale);
                           });
  if (pivot_scale)
    return "a second tool length (the same angles with another radius_mm, diagnosed together): a scale error moves the "
           "tip in proportion to R, a pivot-length error does not";
  return "a plan on which their columns differ (other angles, a second tool length, repeats)";
}

/// A cause in the words of the text ("pivot_length or linear-axis scale").
std::string causeWords(const std::string& cause) {
  if (cause == kScale) return "linear-axis scale";
  if (cause == kDrift) return "thermal drift";
  return cause;
}

std::string termsWords(const std::vector<JudgeTerm>& terms) {
  std::vector<std::string> t;
  for (const auto& x : terms) t.push_back(fmt::format("{} = {:.4g} {}", x.name, x.coefficient, x.unit));
  return fmt::format("{}", fmt::join(t, ", "));
}

std::string ownSummary(const JudgeFinding& f);

std::string findingSummary(const JudgeFinding& f) {
  if (f.confounded_with.empty()) return ownSummary(f);
  // One signal the plan cannot attribute: name every cause, how to tell them apart, then the
  // estimate as the model extension reads it and what that is in the others' terms.
  std::vector<std::string> names = {causeWords(f.cause)};
  for (const auto& c : f.confounded_with) names.push_back(causeWords(c));
  std::string s = fmt::format("{}: the plan cannot tell them apart; {}. Read as {}: {}", fmt::join(names, " or "),
                              findingSeparateWith(f, separateWith), causeWords(f.cause), ownSummary(f));
  for (const auto& e : f.confounding)
    s += fmt::format(" On this plan {} is read as {}.", termsWords(e.cause_terms), termsWords(e.with_terms));
  return s;
}

std::string ownSummary(const JudgeFinding& f) {
  if (f.cause == kPivot) {
    const JudgeEstimate& p = *paramOf(f, 0);
    return fmt::format("The tool tip sits {:.1f} um (u {:.1f} um) {} from the pivot than the program assumes; 004's formula "
                       "reads this as an angular error growing with tan A.",
                       std::abs(p.value), p.u, p.value > 0 ? "farther" : "closer");
  }
  if (f.cause == kScale)
    return fmt::format("The linear axes in the read plane position with a scale error: {} = {:.1f} um/m (u {:.1f}), {} = "
                       "{:.1f} um/m (u {:.1f}).",
                       f.parameters[0].name, f.parameters[0].value, f.parameters[0].u, f.parameters[1].name,
                       f.parameters[1].value, f.parameters[1].u);
  return fmt::format("The tool tip drifts with time: {} = {:.2f} um/h (u {:.2f}), {} = {:.2f} um/h (u {:.2f}).",
                     f.parameters[0].name, f.parameters[0].value, f.parameters[0].u, f.parameters[1].name,
                     f.parameters[1].value, f.parameters[1].u);
}



}  // namespace

Json tooltipDiagnosisJson(const TooltipDiagnosis& d) {
  const JudgeSummary& s = d.summary;
  Json j;
  stampDiagnosis(j, "tooltip");
  j["radius_mm"] = d.radius_mm;
  j["repeats"] = d.runs;
  j["declared_sigma_um"] = s.declared_sigma_rms;
  j["baseline"] = contractBaselineJson(s, "angular (004: one angular error per angle, pivot length as programmed)");
  j["baseline"]["holdout"] = fmt::format("leave one {} out", s.group_name);
  verdictJson(j, s);
  j["findings"] = contractFindingsJson(s, findingSummary, [](const JudgeFinding& f, Json& e) {
    if (f.cause == kPivot)
      e["location_errors"] = {{"dR", {{"value", f.parameters[0].value}, {"unit", "um"}, {"u", f.parameters[0].u}}}};
  });
  writeConfounded(j, s, separateWith);
  j["judge"] = judgeToJson(s);
  return j;
}

std::string tooltipDiagnosisText(const TooltipDiagnosis& d) {
  std::string s = fmt::format("rotacal diagnose tooltip: {} tool length(s) (R = {} mm), {} repeat(s), declared laser noise "
                              "{:.3g} um\n",
                              d.sets, fmt::join(d.radius_mm, ", "), d.runs, d.summary.declared_sigma_rms);
  s += judgeText(d.summary, separateWith);
  for (const auto& f : d.summary.findings) s += fmt::format("finding {}: {}\n", f.cause, findingSummary(f));
  return s;
}

}  // namespace rotacal
