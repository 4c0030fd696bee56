#include "cycles/rtest/diagnose.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/rng.hpp"

#include "core/require_valid.hpp"
#include "core/units.hpp"
#include "cycles/judge_contract.hpp"

namespace rotacal {

bool RtestDiagnosisOptions::validate(std::string* why) const {
  if (!judge.validate(why)) return false;
  if (!(sensor_sigma_um > 0) || !std::isfinite(sensor_sigma_um)) return invalidBecause(why, "sensor_sigma_um must be > 0");
  if (!(reading_sigma_um >= 0) || !std::isfinite(reading_sigma_um))
    return invalidBecause(why, "reading_sigma_um must be >= 0");
  return true;
}

namespace {

// Report units: lengths in um, angles in mdeg. A Jacobian column of J_wq_omega is mm per mm or
// mm per rad; per report unit it is (um per um) = the same number, (um per mdeg) = x 1e3 / kMdegPerRad.
double perReportUnit(int p) { return rtestParameterIsLength(p) ? 1.0 : mmToUm(1.0) * mdegToRad(1.0); }
double rep(int p, double v) { return rtestParameterIsLength(p) ? mmToUm(v) : radToMdeg(v); }
std::string unitOf(int p) { return rtestParameterIsLength(p) ? "um" : "mdeg"; }

constexpr const char* kSpindle = "spindle_growth";
constexpr const char* kLinear = "linear_axis_drift";
constexpr const char* kDrift = "thermal_drift";
constexpr const char* kStepPrefix = "sensor_step_cycle_";
constexpr const char* kInStepPrefix = "sensor_step_in_cycle_";

bool isInStep(const std::string& cause) { return cause.rfind(kInStepPrefix, 0) == 0; }
bool isStep(const std::string& cause) { return cause.rfind(kStepPrefix, 0) == 0 || isInStep(cause); }
std::string stepCycle(const std::string& cause) {
  return cause.substr(std::string(isInStep(cause) ? kInStepPrefix : kStepPrefix).size());
}

/// A candidate passes by the judge's one rule at the main judgement's per-test level.
bool passes(const JudgeCandidate& c, double per_test_alpha) {
  return c.k_eff > 0 && c.p_value < per_test_alpha && c.holdout_passes;
}

const JudgeCandidate* stepZero(const JudgeSummary& s, const std::string& cause) {
  for (const auto& c : s.candidate_tests)
    if (c.step == 0 && c.cause == cause) return &c;
  return nullptr;
}

std::string tiltLabel(Kinematics k, double tilt) { return fmt::format("{}={:g}", tiltAxis(k), tilt); }

}  // namespace

RtestJudgeSetup rtestJudgeSetup(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, double sigma_um,
                                const std::vector<std::pair<int, int>>& excluded) {
  if (cycles.empty()) throw std::invalid_argument("rtest: no cycles to diagnose");
  const Kinematics k = plan.machine.kinematics;
  const Eigen::Vector3d nest = rtestNest_w(plan);
  std::vector<double> tilts;
  std::vector<int> tilt_of;
  for (const auto& p : plan.points) {
    const double t = tiltOf(k, p.pose);
    auto it = std::find(tilts.begin(), tilts.end(), t);
    if (it == tilts.end()) it = tilts.insert(tilts.end(), t);
    tilt_of.push_back(static_cast<int>(it - tilts.begin()));
  }
  const int nt = static_cast<int>(tilts.size());
  const int ref = rtestReferencePoint(plan) - 1;
  const int ref_tilt = tilt_of[static_cast<size_t>(ref)];
  std::vector<Eigen::Matrix<double, 3, kRtestParams>> J;
  std::vector<Eigen::Matrix3d> Rt;  // d wq / d rq = R^T: a sphere offset in the machine frame
  for (const auto& p : plan.points) {
    J.push_back(J_wq_omega(k, p.pose, nest));
    Rt.push_back(T_m_w_nominal(k, p.pose).linear().transpose());
  }
  // Columns of the baseline: every error at every tilt but dz and c at the reset's tilt (not
  // observable against the reset: the tool length and the C zero, docs/rtest.md).
  std::vector<int> cols;
  for (int q = 0; q < kRtestParams * nt; ++q)
    if (q != kRtestParams * ref_tilt + 2 && q != kRtestParams * ref_tilt + 5) cols.push_back(q);

  // Rows: per cycle the reset (when read), the poses, the re-read; every value the sensors'
  // count since the zero at the first cycle's reset (a step persists in the counts).
  const int np = static_cast<int>(plan.points.size());
  const int nc = static_cast<int>(cycles.size());
  std::vector<int> first_row(static_cast<size_t>(nc) + 1, 0), reread_row(static_cast<size_t>(nc), -1);
  for (int c = 0; c < nc; ++c) {
    const auto& cyc = cycles[static_cast<size_t>(c)];
    if (cyc.readings.size() != plan.points.size()) throw std::invalid_argument("rtest: cycle with missing readings");
    const int rows = 3 * (np + (cyc.reset ? 1 : 0) + (cyc.reread ? 1 : 0));
    first_row[static_cast<size_t>(c) + 1] = first_row[static_cast<size_t>(c)] + rows;
    if (cyc.reread) reread_row[static_cast<size_t>(c)] = first_row[static_cast<size_t>(c) + 1] - 3;
  }
  const int n = first_row.back();
  RtestJudgeSetup s;
  JudgeProblem& pb = s.problem;
  pb.unit = "um";
  pb.y.resize(n);
  pb.sigma = Eigen::VectorXd::Constant(n, sigma_um);
  pb.J0 = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(cols.size()));
  JudgeCause drift{kDrift, "the errors between the spindle's sphere and the table change linearly with time",
                   Eigen::MatrixXd::Zero(n, kRtestParams * nt), {}};
  JudgeCause spindle{kSpindle, "the spindle grows along Z (the sphere rises) linearly with time", Eigen::MatrixXd::Zero(n, 1),
                     {{"dZ/h", "um/h"}}};
  JudgeCause linear{kLinear, "the linear axes drift (the sphere moves in X, Y, Z) linearly with time",
                    Eigen::MatrixXd::Zero(n, 3), {{"dX/h", "um/h"}, {"dY/h", "um/h"}, {"dZ/h", "um/h"}}};
  for (int i = 0; i < nt; ++i)
    for (int p = 0; p < kRtestParams; ++p)
      drift.parameters.push_back(
          {fmt::format("{}({})/h", rtestParameterName(k, p), tiltLabel(k, tilts[static_cast<size_t>(i)])), unitOf(p) + "/h"});
  for (int q : cols) {
    const int i = q / kRtestParams, p = q % kRtestParams;
    pb.baseline_parameters.push_back({fmt::format("{}({})", rtestParameterName(k, p), tiltLabel(k, tilts[static_cast<size_t>(i)])), unitOf(p)});
  }
  // Sensor steps (the sensors' zero jumps: a knock, a lost count; it stays in the counts):
  // between cycles K-1 and K (from K's first reading on), and, where the cycle was re-read,
  // inside cycle K (from its re-read on: the re-read is what tells the two apart; the poses of
  // cycle K read after the step are left to the adequacy test).
  std::vector<JudgeCause> steps;
  const std::vector<JudgeParameter> dxyz = {{"dx", "um"}, {"dy", "um"}, {"dz", "um"}};
  for (int K = 1; K <= nc; ++K) {
    if (K >= 2) {
      JudgeCause st{fmt::format("{}{}", kStepPrefix, K), fmt::format("the sensors' zero stepped between cycles {} and {}", K - 1, K),
                    Eigen::MatrixXd::Zero(n, 3), dxyz};
      for (int r = first_row[static_cast<size_t>(K) - 1]; r < n; r += 3) st.J.block(r, 0, 3, 3).setIdentity();
      steps.push_back(std::move(st));
    }
    const int rr = reread_row[static_cast<size_t>(K) - 1];
    if (rr >= 0) {
      JudgeCause st{fmt::format("{}{}", kInStepPrefix, K),
                    fmt::format("the sensors' zero stepped during cycle {} (between its reset and its re-read)", K),
                    Eigen::MatrixXd::Zero(n, 3), dxyz};
      for (int r = rr; r < n; r += 3) st.J.block(r, 0, 3, 3).setIdentity();
      steps.push_back(std::move(st));
    }
  }
  // The sensors' zero: the first cycle's reset reading (or, without one, its reset pose).
  std::vector<int> dropped;  // rows of the values the screen left out
  const double t0 = cycles.front().reset ? cycles.front().reset->t_s : cycles.front().readings.at(static_cast<size_t>(ref)).t_s;
  JudgeFactor f_time{"time", {}, {}, "h"}, f_tilt{"tilt", {}, {}, ""}, f_c{"C", {}, {}, ""}, f_dir{"direction", {}, {}, ""},
      f_cycle{"cycle", {}, {}, ""}, f_read{"reading", {}, {}, ""};
  for (int c = 0; c < nc; ++c) {
    const auto& cyc = cycles[static_cast<size_t>(c)];
    std::vector<std::pair<const RtestReading*, int>> rows;  // reading, plan point index (the reset: ref)
    if (cyc.reset) rows.emplace_back(&*cyc.reset, ref);
    for (size_t j = 0; j < plan.points.size(); ++j) rows.emplace_back(&cyc.readings[j], static_cast<int>(j));
    if (cyc.reread) rows.emplace_back(&*cyc.reread, ref);
    int r = first_row[static_cast<size_t>(c)];
    for (size_t w = 0; w < rows.size(); ++w, r += 3) {
      const RtestReading& rd = *rows[w].first;
      const size_t j = static_cast<size_t>(rows[w].second);
      const bool is_reset = rd.pose_id == 0;
      const double tau = (rd.t_s - t0) / 3600.0;
      const int ti = tilt_of[j];
      // 002 Eq. (6): reading = J_j omega(tilt_j) - J_ref omega(tilt_ref), the zero at t0.
      Eigen::Matrix<double, 3, Eigen::Dynamic> full = Eigen::MatrixXd::Zero(3, kRtestParams * nt);
      full.middleCols(kRtestParams * ti, kRtestParams) += J[j];
      full.middleCols(kRtestParams * ref_tilt, kRtestParams) -= J[static_cast<size_t>(ref)];
      for (size_t q = 0; q < cols.size(); ++q)
        pb.J0.block(r, static_cast<Eigen::Index>(q), 3, 1) = full.col(cols[q]) * perReportUnit(cols[q] % kRtestParams);
      for (int p = 0; p < kRtestParams; ++p)
        drift.J.block(r, kRtestParams * ti + p, 3, 1) = tau * J[j].col(p) * perReportUnit(p);
      spindle.J.block(r, 0, 3, 1) = tau * Rt[j].col(2);
      linear.J.block(r, 0, 3, 3) = tau * Rt[j];
      pb.y.segment<3>(r) = mmToUm(1.0) * rd.dq_w_mm;
      for (int d = 0; d < 3; ++d)
        if (!is_reset && std::binary_search(excluded.begin(), excluded.end(), std::make_pair(c, 3 * static_cast<int>(j) + d)))
          dropped.push_back(r + d);
      for (int d = 0; d < 3; ++d) {
        pb.groups.push_back(c);
        s.t_h.push_back(tau);
        s.cycle.push_back(c);
        s.plan_row.push_back(3 * static_cast<int>(j) + d);
        f_time.values.push_back(tau);
        f_tilt.levels.push_back(fmt::format("{:g}", tilts[static_cast<size_t>(ti)]));
        f_c.levels.push_back(fmt::format("{:g}", plan.points[j].pose.C));
        f_dir.levels.push_back(std::string(1, "xyz"[d]));
        f_cycle.levels.push_back(std::to_string(c + 1));
        f_read.levels.push_back(!is_reset ? "pose" : (w == 0 ? "reset" : "re-read"));
      }
    }
  }
  pb.group_name = "cycle";
  pb.factors = {f_time, f_tilt, f_c, f_dir, f_cycle};
  if (cycles.front().reset) pb.factors.push_back(f_read);
  pb.causes.push_back(std::move(drift));
  for (auto& st : steps) pb.causes.push_back(std::move(st));
  s.confounds = {std::move(spindle), std::move(linear)};
  if (!dropped.empty()) {
    std::vector<int> keep;
    for (int i = 0; i < n; ++i)
      if (std::find(dropped.begin(), dropped.end(), i) == dropped.end()) keep.push_back(i);
    auto pick = [&keep](auto& v) {
      auto all = v;
      v.clear();
      for (int i : keep) v.push_back(all[static_cast<size_t>(i)]);
    };
    pb.y = Eigen::VectorXd(pb.y(keep));
    pb.sigma = Eigen::VectorXd(pb.sigma(keep));
    pb.J0 = Eigen::MatrixXd(pb.J0(keep, Eigen::all));
    for (auto& c : pb.causes) c.J = Eigen::MatrixXd(c.J(keep, Eigen::all));
    for (auto& c : s.confounds) c.J = Eigen::MatrixXd(c.J(keep, Eigen::all));
    pick(pb.groups);
    pick(s.t_h);
    pick(s.cycle);
    pick(s.plan_row);
    for (auto& f : pb.factors) {
      if (!f.levels.empty()) pick(f.levels);
      if (!f.values.empty()) pick(f.values);
    }
  }
  return s;
}

RtestDiagnosis diagnoseRtest(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestDiagnosisOptions& o) {
  requireValid(o, "rtest diagnosis");
  RtestDiagnosis d;
  RtestFitOptions fo;
  fo.sensor_sigma_um = o.sensor_sigma_um;
  fo.reading_sigma_um = o.reading_sigma_um;
  fo.declaration = o.declaration;
  fo.structured_um2 = o.structured_um2;
  fo.structured_draws_um = o.structured_draws_um;
  d.analysis = analyzeRtest(plan, cycles, fo);
  d.cycles = static_cast<int>(cycles.size());
  RtestJudgeSetup setup = rtestJudgeSetup(plan, cycles, o.readingSigmaUm(), d.analysis.screen.excluded());
  setup.problem.declaration = o.declaration;
  if (o.structured_um2.size() > 0) {
    // The same machine in every cycle: any two readings share what their plan rows share.
    JudgeProblem& pb = setup.problem;
    const auto np3 = 3 * static_cast<Eigen::Index>(plan.points.size());
    if (o.structured_um2.rows() != np3 || o.structured_um2.cols() != np3)
      throw std::invalid_argument("rtest diagnose: the structured part is not 3 x the plan's points square");
    std::vector<Eigen::Index> at(setup.plan_row.begin(), setup.plan_row.end());
    pb.covariance = o.structured_um2(at, at);
    pb.covariance.diagonal() += pb.sigma.cwiseAbs2();
    if (o.structured_draws_um.cols() >= kMinNullDraws) {
      if (o.structured_draws_um.rows() != np3)
        throw std::invalid_argument("rtest diagnose: the structured draws are not 3 x the plan's points");
      // One machine in every cycle (its draw shared by every row), each reading's own white part.
      pb.null_draws = o.structured_draws_um(at, Eigen::all);
      Rng rng(kRtestNullSeed, 127);
      for (Eigen::Index c = 0; c < pb.null_draws.cols(); ++c)
        for (Eigen::Index r = 0; r < pb.null_draws.rows(); ++r) pb.null_draws(r, c) += pb.sigma[r] * rng.normal();
    }
  }
  d.summary = judge(setup.problem, o.judge);
  const double level = d.summary.per_test_alpha;
  const JudgeCause& drift = setup.problem.causes.front();

  // The nested judgements below ask who drifts, on the model the judge accepted: a sensor step it
  // found stays in their baseline (left out, the step's residual is read by the drift families
  // and the table drift passes beyond the linear axes' on a series they explain).
  JudgeProblem base = setup.problem;
  for (const auto& f : d.summary.findings) {
    if (f.cause == kDrift) continue;
    for (const auto& c : setup.problem.causes) {
      if (c.name != f.cause) continue;
      base.J0.conservativeResize(Eigen::NoChange, base.J0.cols() + c.J.cols());
      base.J0.rightCols(c.J.cols()) = c.J;
      for (const auto& p : c.parameters) base.baseline_parameters.push_back({c.name + "." + p.name, p.unit});
    }
  }

  // How each confound is read as table drift: the judge with the drift in the model.
  JudgeProblem with_drift = base;
  with_drift.J0.conservativeResize(Eigen::NoChange, base.J0.cols() + drift.J.cols());
  with_drift.J0.rightCols(drift.J.cols()) = drift.J;
  for (const auto& p : drift.parameters) with_drift.baseline_parameters.push_back({std::string(kDrift) + "." + p.name, p.unit});
  with_drift.causes = setup.confounds;
  const JudgeSummary read_as = judge(with_drift, o.judge);

  for (const auto& cf : setup.confounds) {
    RtestConfound rc;
    for (const auto& e : read_as.confounded)
      if (e.cause == cf.name && e.with_model) rc.entry = e;
    if (rc.entry.cause.empty()) continue;  // not exactly confounded on this plan: nothing to state
    // Does it alone explain the signal? Its own test against the baseline, and the table
    // drift's test with it in the model.
    JudgeProblem alone = base;
    alone.causes = {cf};
    const JudgeSummary sa = judge(alone, o.judge);
    JudgeProblem beyond = base;
    beyond.J0.conservativeResize(Eigen::NoChange, base.J0.cols() + cf.J.cols());
    beyond.J0.rightCols(cf.J.cols()) = cf.J;
    for (const auto& p : cf.parameters) beyond.baseline_parameters.push_back({cf.name + "." + p.name, p.unit});
    beyond.causes = {drift};
    const JudgeSummary sb = judge(beyond, o.judge);
    rc.alone = *stepZero(sa, cf.name);
    rc.drift_beyond = *stepZero(sb, kDrift);
    rc.explains = passes(rc.alone, level) && !passes(rc.drift_beyond, level);
    // Restate the entry as the pair it is (the confound against the table drift family).
    rc.entry.with = {kDrift};
    rc.entry.with_model = false;
    for (auto& t : rc.entry.with_terms)
      if (t.name.rfind(std::string(kDrift) + ".", 0) == 0) t.name = t.name.substr(std::string(kDrift).size() + 1);
    rc.entry.signal = passes(rc.alone, level);
    rc.entry.why = fmt::format(
        "the R-test sees the sphere against the nest only (002 Sec. 4.3): on this plan {} moves the readings exactly as "
        "a drift of the table's errors does (principal angle {:.2g} deg): {} is read as {}",
        cf.name, rc.entry.angle_deg,
        rc.entry.cause_terms.empty() ? std::string("it")
                                     : fmt::format("{} = {:.4g} {}", rc.entry.cause_terms[0].name,
                                                   rc.entry.cause_terms[0].coefficient, rc.entry.cause_terms[0].unit),
        [&] {
          std::string s;
          for (const auto& t : rc.entry.with_terms) s += (s.empty() ? "" : ", ") + fmt::format("{} = {:.4g} {}", t.name, t.coefficient, t.unit);
          return s;
        }());
    d.summary.confounded.push_back(rc.entry);
    d.confounds.push_back(std::move(rc));
  }
  return d;
}

std::string rtestFindingSummary(const ProbePlan& plan, const RtestDiagnosis& d, const JudgeFinding& f) {
  const Kinematics k = plan.machine.kinematics;
  if (isStep(f.cause)) {
    const JudgeEstimate* top = &f.parameters.front();
    for (const auto& p : f.parameters)
      if (std::abs(p.value / p.u) > std::abs(top->value / top->u)) top = &p;
    if (isInStep(f.cause))
      return fmt::format("the sensors' readings stepped by {:.2f} um in {} ({}) during cycle {}: its re-read of the reset "
                         "pose differs from its reset reading and the later cycles keep the offset; a knock, a lost "
                         "count or a sensor slipping in the nest, not the machine; cycle {}'s readings after the step "
                         "are off (analyze refers every cycle to its own reset: repeat that cycle)",
                         top->value, top->name.substr(1), fmt::format("u {:.2f} um", top->u), stepCycle(f.cause),
                         stepCycle(f.cause));
    return fmt::format("the sensors' readings stepped by {:.2f} um in {} ({}) from cycle {} on: a knock, a lost count or "
                       "a sensor slipping in the nest, not the machine",
                       top->value, top->name.substr(1), fmt::format("u {:.2f} um", top->u), stepCycle(f.cause));
  }
  // thermal_drift: the slope that stands out most, and who can have caused it.
  const JudgeEstimate* top = &f.parameters.front();
  for (const auto& p : f.parameters)
    if (p.identifiable && std::abs(p.value / p.u) > std::abs(top->value / top->u)) top = &p;
  std::vector<std::string> by;
  for (const auto& c : d.confounds)
    if (c.explains) by.push_back(c.entry.cause == kSpindle ? "a growth of the spindle along Z" : "a drift of the linear axes");
  const std::string what = fmt::format("{} moves {:+.2f} {} (u {:.2f})", top->name.substr(0, top->name.size() - 2), top->value,
                                       top->unit, top->u);
  (void)k;
  if (!by.empty())
    return fmt::format("the sphere-to-table position changes with time ({}); {} explains the same signal, which the R-test "
                       "cannot tell from a drift of the rotary table's errors (002 Sec. 4.3)",
                       what, fmt::join(by, " or "));
  return fmt::format("the rotary table's errors change with time ({}), in a pattern that neither a spindle growth nor a "
                     "drift of the linear axes alone explains",
                     what);
}

namespace {


std::string separateWith(const std::string& cause) {
  if (cause == kSpindle)
    return "a second series with a longer or shorter sphere holder, or a spindle-growth sensor: the table's drift does "
           "not follow the sphere";
  if (cause == kLinear)
    return "the linear axes' drift measured on their own during the same warm-up (laser or ballbar at a fixed table "
           "angle), or a second nest position";
  return "a plan on which their Jacobians differ";
}

}  // namespace

Json rtestDiagnosisJson(const ProbePlan& plan, const RtestDiagnosis& d) {
  const Kinematics k = plan.machine.kinematics;
  const char ax = tiltAxis(k);
  const JudgeSummary& s = d.summary;
  Json j;
  stampDiagnosis(j, "rtest");
  j["cycles"] = d.cycles;
  j["declared_sigma_um"] = s.declared_sigma_rms;
  j["baseline"] =
      contractBaselineJson(s, "002 Table 2 errors at each tilt, constant over the series (Eq. (6) over all cycles)");
  j["holdout_scheme"] = "leave one cycle out";
  verdictJson(j, s);
  Json findings = Json::array();
  for (const auto& f : s.findings) {
    Json e = contractFindingJson(s, f);
    e["cause"] = isStep(f.cause) ? std::string("sensor_step") : f.cause;
    e["variant"] = isStep(f.cause) ? fmt::format(isInStep(f.cause) ? "during cycle {}" : "from cycle {}", stepCycle(f.cause))
                                   : std::string("linear");
    e["summary"] = rtestFindingSummary(plan, d, f);
    if (f.cause == kDrift) {
      // The errors re-estimated at the last cycle's time: the per-cycle estimates of analyze.
      Json le = Json::object();
      const auto& last = d.analysis.cycles.back();
      for (int p = 0; p < kRtestParams; ++p) {
        std::vector<double> v, u;
        for (size_t i = 0; i < d.analysis.tilt_deg.size(); ++i) {
          v.push_back(rep(p, last.value(p, static_cast<int>(i))));
          u.push_back(rep(p, last.u(p, static_cast<int>(i))));
        }
        le[rtestParameterName(k, p)] = {{"unit", unitOf(p)}, {"values", v}, {"u", u},
                                        {"note", fmt::format("at the last cycle, t = {:.2f} h, per {} angle", last.t_s / 3600.0, ax)}};
      }
      e["location_errors"] = le;
    }
    findings.push_back(e);
  }
  j["findings"] = findings;
  writeConfounded(j, s, [](const JudgeConfounded& c) { return separateWith(c.cause); });
  Json cj = Json::array();
  for (const auto& c : d.confounds)
    cj.push_back({{"cause", c.entry.cause},
                  {"alone_p_value", c.alone.p_value},
                  {"alone_passes", passes(c.alone, s.per_test_alpha)},
                  {"table_drift_beyond_p_value", c.drift_beyond.p_value},
                  {"table_drift_beyond_passes", passes(c.drift_beyond, s.per_test_alpha)},
                  {"explains_the_drift", c.explains}});
  j["drift_confounds"] = cj;
  j["judge"] = judgeToJson(s);
  j["outliers"] = rtestScreenJson(plan, d.analysis.screen);
  if (d.cycles >= 3) {
    Json figs = Json::array();
    for (int p = 0; p < kRtestParams; ++p) {
      Json series = Json::array();
      std::vector<double> x, y, u;
      for (size_t i = 0; i < d.analysis.tilt_deg.size(); ++i) {
        x.push_back(d.analysis.tilt_deg[i]);
        y.push_back(rep(p, d.analysis.rate(p, static_cast<int>(i))) * 3600.0);
        u.push_back(rep(p, d.analysis.rate_u(p, static_cast<int>(i))) * 3600.0);
      }
      series.push_back({{"name", rtestParameterName(k, p) + "/h"}, {"style", "points"}, {"x", x}, {"y", y}, {"u", u}});
      std::string id = "rtest_drift_rate_" + rtestParameterName(k, p);
      for (auto& ch : id) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      figs.push_back({{"id", id},
                      {"title", fmt::format("Drift rate of {} at each {} angle (per-cycle estimates)", rtestParameterName(k, p), ax)},
                      {"x", {{"label", std::string(1, ax)}, {"unit", "deg"}}},
                      {"y", {{"label", "rate"}, {"unit", unitOf(p) + "/h"}}},
                      {"series", series},
                      {"note", "the straight line through each cycle's own estimates; the verdict is the judge's joint test"}});
    }
    j["figures"] = figs;
  }
  return j;
}

std::string rtestDiagnosisText(const ProbePlan& plan, const RtestDiagnosis& d) {
  std::string s = fmt::format("rotacal diagnose rtest: {} cycles, declared noise per reading {:.3g} um{}\n", d.cycles,
                              d.summary.declared_sigma_rms,
                              d.summary.declaration.empty() ? std::string() : " (" + d.summary.declaration + ")");
  s += rtestScreenText(plan, d.analysis.screen) + "\n";
  s += judgeText(d.summary, [](const JudgeConfounded& c) { return separateWith(c.cause); });
  for (const auto& f : d.summary.findings) s += fmt::format("finding {}: {}\n", f.cause, rtestFindingSummary(plan, d, f));
  for (const auto& c : d.confounds)
    s += fmt::format("{} alone: p {:.2g}, {}; the table drift beyond it: p {:.2g}, {}{}\n", c.entry.cause, c.alone.p_value,
                     passes(c.alone, d.summary.per_test_alpha) ? "passes" : "does not pass", c.drift_beyond.p_value,
                     passes(c.drift_beyond, d.summary.per_test_alpha) ? "passes" : "does not pass",
                     c.explains ? ": it explains the drift signal as well as the table's errors do" : "");
  return s;
}

}  // namespace rotacal
