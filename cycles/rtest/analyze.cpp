#include "cycles/rtest/analyze.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/units.hpp"
#include "core/report_envelope.hpp"

namespace rotacal {

Eigen::Matrix<double, 3, kRtestParams> J_wq_omega(Kinematics k, const Pose& pose, const Eigen::Vector3d& nest_w) {
  LocationErrors zero;
  zero.kinematics = k;
  // T wq = rq with rq fixed: dT wq + T dwq = 0, so dwq = -R^T (d(T p)/de at p = wq).
  const Eigen::Matrix3d R = T_m_w_nominal(k, pose).linear();
  const auto J = J_pm_e(zero, pose, nest_w);
  Eigen::Matrix<double, 3, kRtestParams> out;
  const auto& idx = rtestParameterIndices(k);
  for (int p = 0; p < kRtestParams; ++p) out.col(p) = -R.transpose() * J.col(idx[p]);
  return out;
}

Eigen::Matrix<double, 3, kNumLocationErrors> J_wq_e(Kinematics k, const Pose& pose, const Eigen::Vector3d& nest_w) {
  LocationErrors zero;
  zero.kinematics = k;
  const Eigen::Matrix3d R = T_m_w_nominal(k, pose).linear();
  return -R.transpose() * J_pm_e(zero, pose, nest_w);
}

void RtestFitOptions::validate() const {
  if (!(sensor_sigma_um > 0)) throw std::invalid_argument("rtest fit: sensor_sigma_um must be > 0");
}

namespace {

struct Layout {
  std::vector<double> tilts;
  std::vector<int> tilt_of_point;  // plan point index -> tilt index
  int ref_point = 0;               // 0-based
  int ref_tilt = 0;
};

Layout layoutOf(const ProbePlan& plan) {
  Layout l;
  const Kinematics k = plan.machine.kinematics;
  for (const auto& p : plan.points) {
    const double t = tiltOf(k, p.pose);
    auto it = std::find(l.tilts.begin(), l.tilts.end(), t);
    if (it == l.tilts.end()) {
      l.tilts.push_back(t);
      it = l.tilts.end() - 1;
    }
    l.tilt_of_point.push_back(static_cast<int>(it - l.tilts.begin()));
  }
  l.ref_point = rtestReferencePoint(plan) - 1;
  l.ref_tilt = l.tilt_of_point[l.ref_point];
  return l;
}

/// Exact wq at a pose with the six errors of its tilt set from the estimate (column i).
Eigen::Vector3d exactW(const ProbePlan& plan, const Eigen::MatrixXd& value, int tilt, const Pose& pose) {
  Truth t;
  t.errors.kinematics = plan.machine.kinematics;
  const auto& idx = rtestParameterIndices(plan.machine.kinematics);
  for (int p = 0; p < kRtestParams; ++p) t.errors.values[idx[p]] = value(p, tilt);
  return rtestSphere_w(plan, t, {}, pose, 0.0);
}

/// The eight location errors from the first cycle's readings y (referred to the reset at tilt
/// 0, C 0): rows J_wq_e(pose_j) - J_wq_e(reset pose), 002 Eq. (6) with constant errors.
RtestLocationFit fitLocation(const ProbePlan& plan, const Layout& L, const Eigen::VectorXd& y, double sensor_sigma_um) {
  const Kinematics k = plan.machine.kinematics;
  const Eigen::Vector3d nest = rtestNest_w(plan);
  const int m = static_cast<int>(y.size());
  const auto Jref = J_wq_e(k, plan.points[static_cast<size_t>(L.ref_point)].pose, nest);
  Eigen::MatrixXd A(m, kNumLocationErrors);
  for (size_t j = 0; j < plan.points.size(); ++j)
    A.middleRows(3 * static_cast<Eigen::Index>(j), 3) = J_wq_e(k, plan.points[j].pose, nest) - Jref;
  RtestLocationFit f;
  Eigen::VectorXd scale(kNumLocationErrors);
  for (int q = 0; q < kNumLocationErrors; ++q) scale[q] = std::max(A.col(q).norm(), 1e-300);
  const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(As, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (!(sv[sv.size() - 1] > 1e-8 * sv[0])) {
    f.why = fmt::format("the plan's tilts ({} = {}) do not separate the eight location errors (condition {:.3g}); "
                        "the per-tilt errors are reported alone",
                        tiltAxis(k), fmt::join(L.tilts, ", "), sv[0] / std::max(sv[sv.size() - 1], 1e-300));
    return f;
  }
  f.identifiable = true;
  const Eigen::VectorXd x = scale.cwiseInverse().asDiagonal() * svd.solve(y);
  const Eigen::VectorXd r = y - A * x;
  const int dof = m - kNumLocationErrors - 3;  // the reset's own rows are 0 = 0
  const double s_res = dof > 0 ? mmToUm(std::sqrt(r.squaredNorm() / dof)) : 0.0;
  f.residual_rms_um = mmToUm(std::sqrt(r.squaredNorm() / std::max(1, m - 3)));
  f.sigma_um = std::max(sensor_sigma_um, s_res);
  const Eigen::MatrixXd Ns_inv = svd.matrixV() * sv.cwiseInverse().cwiseAbs2().asDiagonal() * svd.matrixV().transpose();
  for (int q = 0; q < kNumLocationErrors; ++q) {
    f.value[q] = x[q];
    f.u[q] = umToMm(f.sigma_um) * std::sqrt(std::max(0.0, Ns_inv(q, q))) / scale[q];
  }
  return f;
}

double toReport(int p, double v) { return rtestParameterIsLength(p) ? mmToUm(v) : radToMdeg(v); }
std::string unitOf(int p) { return rtestParameterIsLength(p) ? "um" : "mdeg"; }

}  // namespace

RtestAnalysis analyzeRtest(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestFitOptions& opt) {
  opt.validate();
  if (plan.cycle != "rtest") throw std::invalid_argument("not an rtest plan");
  if (cycles.empty()) throw std::invalid_argument("rtest: no cycles to analyze");
  const Kinematics k = plan.machine.kinematics;
  const Layout L = layoutOf(plan);
  const int nt = static_cast<int>(L.tilts.size());
  const int n = kRtestParams * nt;
  const int m = 3 * static_cast<int>(plan.points.size());
  const Eigen::Vector3d nest = rtestNest_w(plan);
  std::vector<Eigen::Matrix<double, 3, kRtestParams>> J;
  for (const auto& p : plan.points) J.push_back(J_wq_omega(k, p.pose, nest));
  const auto& Jref = J[L.ref_point];
  // Not observable in the first cycle (docs/rtest.md): dz at tilt 0 (along the C axis: the
  // tool length) and c at tilt 0 (about the C axis: the C zero, which the reset at C = 0 defines).
  const int dz_ref_col = kRtestParams * L.ref_tilt + 2, c_ref_col = kRtestParams * L.ref_tilt + 5;

  RtestAnalysis out;
  out.kinematics = k;
  out.tilt_deg = L.tilts;
  Eigen::Vector3d ref_dev = Eigen::Vector3d::Zero();  // J_ref omega_0: wq(0,0,t0) - wq*, first cycle
  Eigen::Matrix3d ref_cov = Eigen::Matrix3d::Zero();
  for (size_t c = 0; c < cycles.size(); ++c) {
    const auto& cyc = cycles[c];
    if (cyc.readings.size() != plan.points.size()) throw std::invalid_argument("rtest: cycle with missing readings");
    const bool first = c == 0;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, n);
    Eigen::VectorXd y(m);
    for (size_t j = 0; j < plan.points.size(); ++j) {
      const int ti = L.tilt_of_point[j];
      A.block(3 * j, kRtestParams * ti, 3, kRtestParams) += J[j];
      if (first) A.block(3 * j, kRtestParams * L.ref_tilt, 3, kRtestParams) -= Jref;  // 002 Eq. (6)
      y.segment<3>(3 * j) = cyc.readings[j].dq_w_mm + (first ? Eigen::Vector3d::Zero() : ref_dev);
    }
    // Columns used: all but dz and c at tilt 0 in the first cycle.
    std::vector<int> cols;
    for (int q = 0; q < n; ++q)
      if (!(first && (q == dz_ref_col || q == c_ref_col))) cols.push_back(q);
    Eigen::MatrixXd Au(m, cols.size());
    for (size_t q = 0; q < cols.size(); ++q) Au.col(q) = A.col(cols[q]);
    // Scale columns (mm and rad differ by 1e2) before the rank test.
    Eigen::VectorXd scale(cols.size());
    for (size_t q = 0; q < cols.size(); ++q) scale[q] = std::max(Au.col(q).norm(), 1e-300);
    const Eigen::MatrixXd As = Au * scale.cwiseInverse().asDiagonal();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(As, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto& sv = svd.singularValues();
    if (sv.size() == 0 || sv[sv.size() - 1] < 1e-8 * sv[0])
      throw std::invalid_argument(fmt::format(
          "rtest: the plan cannot separate the six errors at every tilt (condition {:.3g}); use at least 3 C angles "
          "and a nest off the C axis",
          sv[0] / std::max(sv[sv.size() - 1], 1e-300)));
    const Eigen::VectorXd xs = svd.solve(y);
    const Eigen::VectorXd xu = scale.cwiseInverse().asDiagonal() * xs;
    const Eigen::MatrixXd Ns_inv = svd.matrixV() * sv.cwiseInverse().cwiseAbs2().asDiagonal() * svd.matrixV().transpose();
    const Eigen::MatrixXd N_inv = scale.cwiseInverse().asDiagonal() * Ns_inv * scale.cwiseInverse().asDiagonal();
    const Eigen::VectorXd r = y - Au * xu;
    const int dof = m - static_cast<int>(cols.size()) - (first ? 3 : 0);  // the reset rows are 0 = 0 in cycle 1
    const double s_res = dof > 0 ? mmToUm(std::sqrt(r.squaredNorm() / dof)) : 0.0;
    RtestCycleFit f;
    f.t_s = cyc.t_s();
    f.sigma_um = std::max(opt.sensor_sigma_um, s_res);
    f.residual_rms_um = mmToUm(std::sqrt(r.squaredNorm() / (m - (first ? 3 : 0))));
    f.dz_reference_fixed = first;
    Eigen::MatrixXd cov_u = umToMm(f.sigma_um) * umToMm(f.sigma_um) * N_inv;
    if (!first) {
      // The reference term J_ref omega_0 carries the first cycle's uncertainty into every row.
      Eigen::MatrixXd S(m, 3);
      for (int j = 0; j < m / 3; ++j) S.block<3, 3>(3 * j, 0).setIdentity();
      const Eigen::MatrixXd G = N_inv * Au.transpose() * S;
      cov_u += G * ref_cov * G.transpose();
    }
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    f.cov = Eigen::MatrixXd::Zero(n, n);
    for (size_t a = 0; a < cols.size(); ++a) {
      x[cols[a]] = xu[a];
      for (size_t b = 0; b < cols.size(); ++b) f.cov(cols[a], cols[b]) = cov_u(a, b);
    }
    f.value = Eigen::Map<const Eigen::MatrixXd>(x.data(), kRtestParams, nt);
    f.u = Eigen::MatrixXd(kRtestParams, nt);
    for (int i = 0; i < nt; ++i)
      for (int p = 0; p < kRtestParams; ++p) f.u(p, i) = std::sqrt(std::max(0.0, f.cov(kRtestParams * i + p, kRtestParams * i + p)));
    for (size_t j = 0; j < plan.points.size(); ++j) f.residual_w_mm.push_back(r.segment<3>(3 * j));
    // Linearisation: the exact model at the estimate against the linear one.
    const Eigen::VectorXd lin = A * x;
    const Eigen::Vector3d ref_exact =
        first ? Eigen::Vector3d(exactW(plan, f.value, L.ref_tilt, plan.points[L.ref_point].pose) - nest) : ref_dev;
    for (size_t j = 0; j < plan.points.size(); ++j) {
      const Eigen::Vector3d ex = exactW(plan, f.value, L.tilt_of_point[j], plan.points[j].pose) - nest - ref_exact;
      const Eigen::Vector3d li = lin.segment<3>(3 * j) - (first ? Eigen::Vector3d::Zero() : ref_dev);
      f.linearisation_um = std::max(f.linearisation_um, mmToUm((ex - li).cwiseAbs().maxCoeff()));
    }
    if (first) {
      out.location = fitLocation(plan, L, y, opt.sensor_sigma_um);
      const Eigen::VectorXd x_ref = x.segment<kRtestParams>(kRtestParams * L.ref_tilt);
      ref_dev = Jref * x_ref;
      ref_cov = Jref * f.cov.block<kRtestParams, kRtestParams>(kRtestParams * L.ref_tilt, kRtestParams * L.ref_tilt) *
                Jref.transpose();
    }
    out.cycles.push_back(std::move(f));
  }
  // Trend across cycles: weighted straight line per parameter and tilt (002 Fig. 10).
  out.rate = Eigen::MatrixXd::Zero(kRtestParams, nt);
  out.rate_u = Eigen::MatrixXd::Zero(kRtestParams, nt);
  out.change = out.cycles.back().value - out.cycles.front().value;
  if (out.cycles.size() >= 3) {
    for (int i = 0; i < nt; ++i)
      for (int p = 0; p < kRtestParams; ++p) {
        double sw = 0, st = 0, sy = 0, stt = 0, sty = 0;
        // Values fixed by the first cycle's convention (u = 0) carry no information on the rate.
        for (const auto& f : out.cycles) {
          if (!(f.u(p, i) > 0)) continue;
          const double w = 1.0 / (f.u(p, i) * f.u(p, i));
          sw += w;
          st += w * f.t_s;
          sy += w * f.value(p, i);
          stt += w * f.t_s * f.t_s;
          sty += w * f.t_s * f.value(p, i);
        }
        const double det = sw * stt - st * st;
        if (det <= 0) continue;
        out.rate(p, i) = (sw * sty - st * sy) / det;
        // Cycles share the first cycle's reference, so their errors are correlated; the
        // independent-errors formula is a floor, widened by the scatter about the line.
        double chi2 = 0;
        const double b0 = (sy - out.rate(p, i) * st) / sw;
        int used = 0;
        for (const auto& f : out.cycles) {
          if (!(f.u(p, i) > 0)) continue;
          const double e = f.value(p, i) - b0 - out.rate(p, i) * f.t_s;
          chi2 += e * e / (f.u(p, i) * f.u(p, i));
          ++used;
        }
        const double dofc = static_cast<double>(used) - 2.0;
        if (dofc < 1) continue;
        out.rate_u(p, i) = std::sqrt(sw / det) * std::max(1.0, std::sqrt(chi2 / dofc));
      }
  }
  return out;
}

Json rtestReportJson(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestAnalysis& a,
                     const std::vector<std::string>& files) {
  const Kinematics k = a.kinematics;
  const char ax = tiltAxis(k);
  const int nt = static_cast<int>(a.tilt_deg.size());
  Json j = documentEnvelope("rotacal-report/1", plan, files);
  j["kinematics"] = std::string(kinematicsName(k));
  j["method"] = "002 Eq. (6): linearised least squares at every tilt angle, per cycle";
  j["tilt_axis"] = std::string(1, ax);
  j["tilt_deg"] = a.tilt_deg;
  j["conventions"] = {
      {"reset", fmt::format("002 Eq. (4): sensors zeroed once at {} = C = 0 before the first cycle", ax)},
      {"tool_length", fmt::format("002 Sec. 4.3: {} at {} = 0 is not observable in the first cycle and is set to 0; a "
                                  "tool-length error appears as a fixed pattern in the translations at the other "
                                  "tilts; changes with time are free of it",
                                  rtestParameterName(k, 2), ax)},
      {"c_zero", fmt::format("{} at {} = 0 (a rotation about the C axis) is the C zero, defined by the reset at C = 0: "
                             "set to 0 in the first cycle, its change with time is observed",
                             rtestParameterName(k, 5), ax)},
      {"u", "standard uncertainty (k = 1) from max(sensor repeatability, residual), later cycles include the first "
            "cycle's reference"}};
  size_t used = 0;
  double rss = 0;
  Json cj = Json::array();
  for (size_t c = 0; c < a.cycles.size(); ++c) {
    const auto& f = a.cycles[c];
    Json e = Json::object();
    for (int p = 0; p < kRtestParams; ++p) {
      std::vector<double> v, u;
      for (int i = 0; i < nt; ++i) {
        v.push_back(toReport(p, f.value(p, i)));
        u.push_back(toReport(p, f.u(p, i)));
      }
      e[rtestParameterName(k, p)] = {{"unit", unitOf(p)}, {"values", v}, {"u", u}};
    }
    cj.push_back({{"index", c + 1},
                  {"t_h", f.t_s / 3600.0},
                  {"residual_rms_um", f.residual_rms_um},
                  {"linearisation_um", f.linearisation_um},
                  {"sigma_um", f.sigma_um},
                  {"errors", e}});
    for (const auto& r : f.residual_w_mm) rss += mmToUm(mmToUm(r.squaredNorm()));
    used += f.residual_w_mm.size();
  }
  j["cycles"] = cj;
  j["points_used"] = used;
  j["residual_rms_um"] = std::sqrt(rss / std::max<size_t>(1, 3 * used));
  // What the R-test measures: the six errors of the table at each tilt (the first cycle), under
  // 002 Table 2's names and their ISO 230-7 component-error counterparts of the tilt axis.
  {
    Json pt = Json::object();
    for (int p = 0; p < kRtestParams; ++p) {
      std::vector<double> v, u;
      for (int i = 0; i < nt; ++i) {
        v.push_back(toReport(p, a.cycles.front().value(p, i)));
        u.push_back(toReport(p, a.cycles.front().u(p, i)));
      }
      pt[rtestParameterName(k, p)] = {{"iso", fmt::format("E{}{}({})", "XYZABC"[p], ax, ax)}, {"unit", unitOf(p)},
                                      {"values", v}, {"u", u}};
    }
    j["per_tilt_errors"] = {
        {"tilt_axis", std::string(1, ax)},
        {"tilt_deg", a.tilt_deg},
        {"cycle", 1},
        {"errors", pt},
        {"note", fmt::format("the table's (C axis average line's) position and orientation at each {} angle, first "
                             "cycle (002 Table 2): the {} axis's errors with the C axis's offsets from it turned by {}",
                             ax, ax, ax)}};
  }
  // ISO 230-7 location errors of both axes, separated by the constant-error fit (issue 17: no
  // longer the mean of the per-tilt errors, which read X0C - X0B = 10 um as X0B = 7.46 um).
  Json le = Json::object();
  const auto& info = locationParameters(k);
  const auto& idx = rtestParameterIndices(k);
  for (int q = 0; q < kNumLocationErrors; ++q) {
    const bool len = info[static_cast<size_t>(q)].kind == ParamKind::Length;
    const double v = len ? mmToUm(a.location.value[q]) : radToMdeg(a.location.value[q]);
    const double u = len ? mmToUm(a.location.u[q]) : radToMdeg(a.location.u[q]);
    std::string note = "constant location error, fitted to the first cycle's readings (002 Eq. (6))";
    if (len && std::find(idx.begin(), idx.end(), q) != idx.end())
      note += "; relative to the sphere's actual position (a sphere offset, e.g. a tool-length error, reads as minus "
              "this error)";
    if (!a.location.identifiable) continue;  // location_errors_fit says why
    le[std::string(info[static_cast<size_t>(q)].name)] = {{"value", v}, {"unit", len ? "um" : "mdeg"}, {"u", u},
                                                          {"iso", std::string(info[static_cast<size_t>(q)].iso)},
                                                          {"note", note}};
  }
  j["location_errors"] = le;
  j["location_errors_fit"] = {{"identifiable", a.location.identifiable},
                              {"residual_rms_um", a.location.residual_rms_um},
                              {"sigma_um", a.location.sigma_um},
                              {"model", "the eight location errors constant over the tilt, first cycle"},
                              {"note", a.location.identifiable
                                           ? std::string("a residual well above the sensor noise means the errors "
                                                         "depend on the tilt (per_tilt_errors; 002)")
                                           : a.location.why}};
  if (a.cycles.size() >= 3) {
    Json d = Json::object();
    for (int p = 0; p < kRtestParams; ++p) {
      std::vector<double> rate, u, ch;
      for (int i = 0; i < nt; ++i) {
        rate.push_back(toReport(p, a.rate(p, i)) * 3600.0);
        u.push_back(toReport(p, a.rate_u(p, i)) * 3600.0);
        ch.push_back(toReport(p, a.change(p, i)));
      }
      d[rtestParameterName(k, p)] = {{"rate_unit", unitOf(p) + "/h"}, {"rate", rate}, {"u", u},
                                     {"change_unit", unitOf(p)}, {"change_first_to_last", ch}};
    }
    j["drift"] = d;
  }
  // Figures (briefs/figures.md): parameters over time (002 Fig. 10), sensor position profiles.
  Json figs = Json::array();
  for (int p = 0; p < kRtestParams; ++p) {
    const std::string name = rtestParameterName(k, p);
    Json series = Json::array();
    for (int i = 0; i < nt; ++i) {
      std::vector<double> x, y, u;
      for (const auto& f : a.cycles) {
        x.push_back(f.t_s / 3600.0);
        y.push_back(toReport(p, f.value(p, i)));
        u.push_back(toReport(p, f.u(p, i)));
      }
      series.push_back({{"name", fmt::format("{} = {:g} deg", ax, a.tilt_deg[i])},
                        {"style", a.cycles.size() > 1 ? "line" : "points"}, {"x", x}, {"y", y}, {"u", u}});
    }
    std::string id = "rtest_" + name + "_over_time";
    for (auto& ch : id) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    figs.push_back({{"id", id},
                    {"title", fmt::format("{} at each {} angle over time (002 Fig. 10)", name, ax)},
                    {"x", {{"label", "time"}, {"unit", "h"}}},
                    {"y", {{"label", name}, {"unit", unitOf(p)}}},
                    {"series", series},
                    {"note", p == 2 ? fmt::format("{} at {} = 0 is 0 at the first cycle by the tool-length convention",
                                                  name, ax)
                                    : "a trend across cycles is thermal drift of the error"}});
  }
  // Sensor position profile (002 Sec. 3.1): -wq_bar turned into the reference frame with the
  // nominal pose, against C, for the first and the last cycle.
  for (int i = 0; i < nt; ++i) {
    Json series = Json::array();
    std::vector<size_t> which = {0};
    if (cycles.size() > 1) which.push_back(cycles.size() - 1);
    for (size_t c : which) {
      std::vector<std::vector<double>> comp(3);
      std::vector<double> cx;
      for (size_t jp = 0; jp < plan.points.size(); ++jp) {
        const auto& pt = plan.points[jp];
        if (tiltOf(k, pt.pose) != a.tilt_deg[i]) continue;
        const Eigen::Vector3d s = -(T_m_w_nominal(k, pt.pose).linear() * cycles[c].readings[jp].dq_w_mm);
        cx.push_back(pt.pose.C);
        for (int d = 0; d < 3; ++d) comp[d].push_back(mmToUm(s[d]));
      }
      for (int d = 0; d < 3; ++d)
        series.push_back({{"name", fmt::format("{} t = {:.2f} h", "XYZ"[d], a.cycles[c].t_s / 3600.0)},
                          {"style", "line"}, {"x", cx}, {"y", comp[d]}});
    }
    const long tilt_i = std::lround(a.tilt_deg[i]);
    figs.push_back({{"id", fmt::format("rtest_sensor_profile_{}{}{}", ax == 'B' ? "b" : "a", tilt_i < 0 ? "m" : "",
                                       std::labs(tilt_i))},
                    {"title", fmt::format("Sensor position profile at {} = {:g} deg, reference frame (002 Figs. 7-9)",
                                          ax, a.tilt_deg[i])},
                    {"x", {{"label", "C"}, {"unit", "deg"}}},
                    {"y", {{"label", "nest displacement from command"}, {"unit", "um"}}},
                    {"series", series},
                    {"note", "the nest's position error relative to the spindle sphere as C turns: a circle "
                             "offset or tilted is a location error of C at this tilt"}});
  }
  j["figures"] = figs;
  return j;
}

std::string rtestReportText(const ProbePlan& plan, const RtestAnalysis& a) {
  const Kinematics k = a.kinematics;
  const char ax = tiltAxis(k);
  std::string s = fmt::format("rotacal rtest (002): {} poses, {} cycle(s), machine {}\n", plan.points.size(),
                              a.cycles.size(), plan.machine.name);
  for (size_t c = 0; c < a.cycles.size(); ++c) {
    const auto& f = a.cycles[c];
    s += fmt::format("cycle {} at t = {:.2f} h: residual {:.3f} um rms, linearisation {:.2g} um, sigma {:.3f} um\n",
                     c + 1, f.t_s / 3600.0, f.residual_rms_um, f.linearisation_um, f.sigma_um);
    if (c != 0 && c + 1 != a.cycles.size()) continue;
    s += fmt::format("  {:>8}", std::string(1, ax) + " deg");
    for (int p = 0; p < kRtestParams; ++p) s += fmt::format(" {:>16}", rtestParameterName(k, p) + " " + unitOf(p));
    s += "\n";
    for (size_t i = 0; i < a.tilt_deg.size(); ++i) {
      s += fmt::format("  {:>8g}", a.tilt_deg[i]);
      for (int p = 0; p < kRtestParams; ++p)
        s += fmt::format(" {:>8.3f} +-{:<6.3f}", toReport(p, f.value(p, static_cast<int>(i))),
                         toReport(p, f.u(p, static_cast<int>(i))));
      s += "\n";
    }
  }
  if (a.location.identifiable) {
    s += fmt::format("location errors (ISO 230-7, constant over the tilt, first cycle; fit residual {:.3f} um rms):\n",
                     a.location.residual_rms_um);
    const auto& info = locationParameters(k);
    for (int q = 0; q < kNumLocationErrors; ++q) {
      const bool len = info[static_cast<size_t>(q)].kind == ParamKind::Length;
      s += fmt::format("  {:<8} {:>8} {:>9.3f} +-{:<6.3f} {}\n", info[static_cast<size_t>(q)].name,
                       info[static_cast<size_t>(q)].iso, len ? mmToUm(a.location.value[q]) : radToMdeg(a.location.value[q]),
                       len ? mmToUm(a.location.u[q]) : radToMdeg(a.location.u[q]), len ? "um" : "mdeg");
    }
  } else {
    s += "location errors: " + a.location.why + "\n";
  }
  if (a.cycles.size() >= 3) {
    s += "drift (straight line across cycles), per hour:\n";
    for (size_t i = 0; i < a.tilt_deg.size(); ++i) {
      s += fmt::format("  {:>8g}", a.tilt_deg[i]);
      for (int p = 0; p < kRtestParams; ++p)
        s += fmt::format(" {:>8.3f} +-{:<6.3f}", toReport(p, a.rate(p, static_cast<int>(i))) * 3600.0,
                         toReport(p, a.rate_u(p, static_cast<int>(i))) * 3600.0);
      s += "\n";
    }
  }
  return s;
}

}  // namespace rotacal
