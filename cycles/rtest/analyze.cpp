#include "cycles/rtest/analyze.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <functional>
#include <map>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/report_envelope.hpp"
#include "core/rng.hpp"
#include "core/require_valid.hpp"
#include "core/statistics.hpp"
#include "core/units.hpp"

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

RtestLocationEstimator rtestLocationEstimator(const ProbePlan& plan, bool own) {
  const Kinematics k = plan.machine.kinematics;
  const Eigen::Vector3d nest = rtestNest_w(plan);
  const int ref_point = rtestReferencePoint(plan) - 1;
  const int m = 3 * static_cast<int>(plan.points.size());
  const int rows = m + (own ? 6 : 0), ncol = kNumLocationErrors + (own ? 3 : 0);
  const auto Jref = J_wq_e(k, plan.points[static_cast<size_t>(ref_point)].pose, nest);
  RtestLocationEstimator e;
  e.own = own;
  e.zero_rows = own ? 0 : 3;  // without a reset reading the reset pose's own rows are 0 = 0
  e.A = Eigen::MatrixXd::Zero(rows, ncol);
  for (size_t j = 0; j < plan.points.size(); ++j) {
    const auto r = 3 * static_cast<Eigen::Index>(j);
    e.A.block(r, 0, 3, kNumLocationErrors) = J_wq_e(k, plan.points[j].pose, nest);
    if (own) e.A.block(r, kNumLocationErrors, 3, 3).setIdentity();
    else e.A.block(r, 0, 3, kNumLocationErrors) -= Jref;
  }
  if (own)
    for (int k2 = 0; k2 < 2; ++k2) {
      e.A.block(m + 3 * k2, 0, 3, kNumLocationErrors) = Jref;
      e.A.block(m + 3 * k2, kNumLocationErrors, 3, 3).setIdentity();
    }
  e.scale.resize(ncol);
  for (int q = 0; q < ncol; ++q) e.scale[q] = std::max(e.A.col(q).norm(), 1e-300);
  const Eigen::MatrixXd As = e.A * e.scale.cwiseInverse().asDiagonal();
  e.svd = Eigen::JacobiSVD<Eigen::MatrixXd>(As, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = e.svd.singularValues();
  if (!(sv[sv.size() - 1] > 1e-8 * sv[0])) {
    std::vector<double> tilts;
    for (const auto& p : plan.points) {
      const double t = tiltOf(k, p.pose);
      if (std::find(tilts.begin(), tilts.end(), t) == tilts.end()) tilts.push_back(t);
    }
    e.why = fmt::format("the plan's tilts ({} = {}) do not separate the eight location errors (condition {:.3g}); "
                        "the per-tilt errors are reported alone",
                        tiltAxis(k), fmt::join(tilts, ", "), sv[0] / std::max(sv[sv.size() - 1], 1e-300));
    return e;
  }
  e.identifiable = true;
  e.G = e.scale.cwiseInverse().asDiagonal() * e.svd.matrixV() * sv.cwiseInverse().asDiagonal() *
        e.svd.matrixU().transpose();
  return e;
}

Eigen::VectorXd rtestLocationRows(const ProbePlan& plan, const RtestCycle& cyc, bool own) {
  const int m = 3 * static_cast<int>(plan.points.size());
  Eigen::VectorXd y(m + (own ? 6 : 0));
  for (size_t j = 0; j < plan.points.size(); ++j) y.segment<3>(3 * static_cast<Eigen::Index>(j)) = cyc.readings[j].dq_w_mm;
  if (own) {
    if (!cyc.reset || !cyc.reread) throw std::invalid_argument("rtest: the location rows need the reset and re-read");
    y.segment<3>(m) = cyc.reset->dq_w_mm;
    y.segment<3>(m + 3) = cyc.reread->dq_w_mm;
  }
  return y;
}

double rtestSensorNoiseUm(const ProbePlan& plan) {
  return parseNumber("sensor_noise_um",
                     plan.options.count("sensor_noise_um") ? plan.options.at("sensor_noise_um") : std::string("0.2"));
}

namespace {

/// rtestStructuredUm2's model in two parts: what is Gaussian (the sphere offset, the drift, the
/// sensors' response: linear in normal variates, so its covariance says everything) and the
/// linear axes (their random nodes, one spacing per machine, a scale mixture: drawn, not only
/// summarised), read as D times the axes' error at t along u.
struct RtestStructuredParts {
  Eigen::MatrixXd gaussian_mm2;  // 3 np x 3 np
  ContributorSet linear;         // the declared linear-axis contributors (empty: none)
  std::vector<Eigen::Vector3d> t, u;
  Eigen::MatrixXd D;             // 3 np x 3 np: the axes' error at each centre, per direction, as read
};

RtestStructuredParts rtestStructuredParts(const ProbePlan& plan, const ContributorSet& set, const RtestCycle* about) {
  RtestStructuredParts parts;
  const Kinematics k = plan.machine.kinematics;
  const auto np = static_cast<Eigen::Index>(plan.points.size());
  const Eigen::Vector3d nest = rtestNest_w(plan);
  const int ref = rtestReferencePoint(plan) - 1;
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(3 * np, 3 * np);
  // d wq / d rq = R^T: what a displacement of the sphere in the machine frame reads, per pose.
  std::vector<Eigen::Matrix3d> Rt;
  std::vector<Eigen::Vector3d> q_m;  // the commanded sphere centre (machine frame), where the linear axes act
  for (const auto& p : plan.points) {
    const auto T = T_m_w_nominal(k, p.pose);
    Rt.push_back(T.linear().transpose());
    q_m.push_back(T * nest);
  }
  const Eigen::Matrix3d& Rt_ref = Rt[static_cast<size_t>(ref)];
  double gain = 0.0, direction = 0.0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero(), drift = Eigen::Vector3d::Zero();
  ContributorSet& linear = parts.linear;
  linear.node_spacing_min_mm = set.node_spacing_min_mm;
  linear.node_spacing_max_mm = set.node_spacing_max_mm;
  for (const Contributor& c : set.items) {
    switch (c.info->kind) {
      case ContributorKind::RtestSensorGain: gain = c.u[0]; break;
      case ContributorKind::RtestSensorDirection: direction = c.u[0]; break;
      case ContributorKind::RtestSphereOffset: offset = c.u.head<3>(); break;
      case ContributorKind::RtestCycleDrift: drift = c.u.head<3>(); break;
      default:
        if (isLinearAxisContributor(*c.info) && c.u.cwiseAbs().maxCoeff() > 0) linear.items.push_back(c);
    }
  }
  // A constant offset s of the sphere reads (R_i^T - R_ref^T) s: the sensors were zeroed at the
  // reset pose with the same offset on.
  if (offset.squaredNorm() > 0) {
    const Eigen::Matrix3d V = offset.cwiseAbs2().asDiagonal();
    for (Eigen::Index i = 0; i < np; ++i)
      for (Eigen::Index j = 0; j < np; ++j)
        S.block<3, 3>(3 * i, 3 * j) += (Rt[static_cast<size_t>(i)] - Rt_ref) * V * (Rt[static_cast<size_t>(j)] - Rt_ref).transpose();
  }
  // The drift within one cycle: the sphere moves by v t (applyRtestDraw: 0 at the clock's start,
  // the declared value at the end of the first cycle), read as R_i^T v t_i less the zero's.
  if (drift.squaredNorm() > 0) {
    const double T = std::max(1.0, rtestCycleTime_s(plan));
    const std::vector<double> times = rtestReadTimes(plan);
    const double t_ref = rtestResetReads(plan) ? times.front() : plan.points[static_cast<size_t>(ref)].t_s;
    const Eigen::Matrix3d V = (drift / T).cwiseAbs2().asDiagonal();
    std::vector<Eigen::Matrix3d> D;
    for (Eigen::Index i = 0; i < np; ++i) D.push_back(Rt[static_cast<size_t>(i)] * plan.points[static_cast<size_t>(i)].t_s - Rt_ref * t_ref);
    for (Eigen::Index i = 0; i < np; ++i)
      for (Eigen::Index j = 0; j < np; ++j)
        S.block<3, 3>(3 * i, 3 * j) += D[static_cast<size_t>(i)] * V * D[static_cast<size_t>(j)].transpose();
  }
  // The linear axes' error at each commanded centre, every machine direction (probeAxesCovariance,
  // the model drawLinearAxes draws), read through R_i^T less the reset pose's.
  if (!linear.items.empty()) {
    std::vector<Eigen::Vector3d> t, u;
    for (Eigen::Index i = 0; i < np; ++i)
      for (int a = 0; a < 3; ++a) {
        t.push_back(q_m[static_cast<size_t>(i)]);
        u.push_back(Eigen::Vector3d::Unit(a));
      }
    Eigen::MatrixXd D = Eigen::MatrixXd::Zero(3 * np, 3 * np);
    for (Eigen::Index i = 0; i < np; ++i) {
      D.block<3, 3>(3 * i, 3 * i) += Rt[static_cast<size_t>(i)];
      D.block<3, 3>(3 * i, 3 * ref) -= Rt_ref;
    }
    parts.t = std::move(t);
    parts.u = std::move(u);
    parts.D = std::move(D);
  }
  // The sensors' response (gain on the diagonal, cross-talk off it) scales what the sensors read:
  // first order in it about the displacements the readings show (none about the nominal machine,
  // where every reading is 0). Every entry independent: no term between two components.
  if ((gain > 0 || direction > 0) && about) {
    if (about->readings.size() != plan.points.size()) throw std::invalid_argument("rtest declared noise: a cycle does not match its plan");
    Eigen::MatrixXd d(3, np);
    for (Eigen::Index i = 0; i < np; ++i) d.col(i) = about->readings[static_cast<size_t>(i)].dq_w_mm;
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3d w = Eigen::Vector3d::Constant(direction * direction);
      w[a] = gain * gain;
      const Eigen::MatrixXd G = d.transpose() * w.asDiagonal() * d;  // np x np
      for (Eigen::Index i = 0; i < np; ++i)
        for (Eigen::Index j = 0; j < np; ++j) S(3 * i + a, 3 * j + a) += G(i, j);
    }
  }
  parts.gaussian_mm2 = std::move(S);
  return parts;
}

}  // namespace

Eigen::MatrixXd rtestStructuredUm2(const ProbePlan& plan, const ContributorSet& set, const RtestCycle* about) {
  const RtestStructuredParts p = rtestStructuredParts(plan, set, about);
  Eigen::MatrixXd S = p.gaussian_mm2;
  if (p.D.size() > 0) S += p.D * probeAxesCovariance(p.linear, isLinearAxisContributor, p.t, p.u) * p.D.transpose();
  return kUmPerMm * kUmPerMm * S;
}

Eigen::MatrixXd rtestStructuredDrawsUm(const ProbePlan& plan, const ContributorSet& set, const RtestCycle* about, int draws,
                                       std::uint64_t seed) {
  const RtestStructuredParts p = rtestStructuredParts(plan, set, about);
  // The Gaussian part by its symmetric root (positive semi-definite: the reset pose's rows are 0).
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (p.gaussian_mm2 + p.gaussian_mm2.transpose()));
  const Eigen::MatrixXd root = es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() *
                               es.eigenvectors().transpose();
  Eigen::MatrixXd Z(root.cols(), draws);
  Rng rng(seed, 125);
  for (Eigen::Index d = 0; d < draws; ++d)
    for (Eigen::Index i = 0; i < Z.rows(); ++i) Z(i, d) = rng.normal();
  Eigen::MatrixXd X = root * Z;
  if (p.D.size() > 0) X += p.D * probeAxesDraws(p.linear, isLinearAxisContributor, p.t, p.u, draws, seed);
  return kUmPerMm * X;
}

DeclaredNoise rtestDeclaredNoise(const ProbePlan& plan, const ContributorSet* declared, const RtestCycle* about) {
  const double sensor_um = rtestSensorNoiseUm(plan);
  DeclaredNoise d;
  d.white_um2 = sensor_um * sensor_um;
  std::string parts = fmt::format("sensors {:.3f} um (PLAN.json sensor_noise_um)", sensor_um);
  const Contributor* form = declared ? declared->find("rtest_sphere_form") : nullptr;
  if (form && form->u[0] > 0) {
    const double form_um = mmToUm(form->u[0]);
    d.white_um2 += form_um * form_um;
    parts += fmt::format(" + rtest_sphere_form {:.3f} um ({})", form_um,
                         declared->file.empty() ? std::string("the machine's contributors") : declared->file);
  }
  d.repeatability_only = !(form && form->u[0] > 0);
  d.declaration = fmt::format("declared per reading: {} = {:.3f} um", parts, std::sqrt(d.white_um2));
  if (!declared) return d;
  std::string shared;
  for (const Contributor& c : declared->items) {
    if (c.u.cwiseAbs().maxCoeff() <= 0) continue;
    const ContributorKind kd = c.info->kind;
    const bool acts = kd == ContributorKind::RtestSphereOffset || kd == ContributorKind::RtestCycleDrift ||
                      isLinearAxisContributor(*c.info) ||
                      ((kd == ContributorKind::RtestSensorGain || kd == ContributorKind::RtestSensorDirection) && about);
    if (acts) shared += fmt::format("{}{}", shared.empty() ? "" : ", ", c.info->id);
  }
  if (shared.empty()) return d;
  d.structured_um2 = rtestStructuredUm2(plan, *declared, about);
  d.structured_draws_um = rtestStructuredDrawsUm(plan, *declared, about, kRtestNullDraws, kRtestNullSeed);
  d.repeatability_only = false;
  d.declaration += fmt::format("; shared between readings, to first order: {} ({:.2f} um rms per reading)", shared,
                               std::sqrt(d.structured_um2.diagonal().mean()));
  return d;
}

bool RtestFitOptions::validate(std::string* why) const {
  if (!(sensor_sigma_um > 0)) return invalidBecause(why, "sensor_sigma_um must be > 0");
  if (!(reading_sigma_um >= 0) || !std::isfinite(reading_sigma_um))
    return invalidBecause(why, "reading_sigma_um must be >= 0");
  if (!(reset_alpha > 0 && reset_alpha < 1)) return invalidBecause(why, "reset_alpha must be in (0, 1)");
  return true;
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

/// The eight location errors from the first cycle's readings (referred to the reset at tilt 0,
/// C 0): rows J_wq_e(pose_j) - J_wq_e(reset pose), 002 Eq. (6) with constant errors; with reset
/// reads the cycle's zero is a free offset observed by the reset and re-read rows, as in the
/// per-tilt fit.
RtestLocationFit fitLocation(const ProbePlan& plan, const RtestCycle& cyc, double sensor_sigma_um,
                             const std::vector<int>& dropped_rows) {
  const bool own = cyc.reset.has_value() && cyc.reread.has_value();
  const RtestLocationEstimator e = rtestLocationEstimator(plan, own);
  RtestLocationFit f;
  if (!e.identifiable) {
    f.why = e.why;
    return f;
  }
  // The screen's values left out: the fit runs on the other rows (the estimator's own G, for the
  // budget's Monte Carlo, stays the plan's).
  const Eigen::VectorXd y_all = rtestLocationRows(plan, cyc, own);
  std::vector<int> keep;
  for (int i = 0; i < static_cast<int>(e.A.rows()); ++i)
    if (std::find(dropped_rows.begin(), dropped_rows.end(), i) == dropped_rows.end()) keep.push_back(i);
  const Eigen::MatrixXd A = e.A(keep, Eigen::all);
  const Eigen::VectorXd y = y_all(keep);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd =
      dropped_rows.empty() ? e.svd
                           : Eigen::JacobiSVD<Eigen::MatrixXd>(A * e.scale.cwiseInverse().asDiagonal(),
                                                               Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (!(sv[sv.size() - 1] > 1e-8 * sv[0])) {
    f.why = "the readings the screen left out leave the eight location errors unseparated";
    return f;
  }
  f.identifiable = true;
  const Eigen::VectorXd x = e.scale.cwiseInverse().asDiagonal() * svd.solve(y);
  const Eigen::VectorXd r = y - A * x;
  const int rows = static_cast<int>(A.rows()), ncol = static_cast<int>(A.cols());
  const int dof = rows - ncol - e.zero_rows;
  const double s_res = dof > 0 ? mmToUm(std::sqrt(r.squaredNorm() / dof)) : 0.0;
  f.residual_rms_um = mmToUm(std::sqrt(r.squaredNorm() / std::max(1, rows - e.zero_rows)));
  f.residual_sd_um = s_res;
  f.dof = dof;
  f.sigma_um = std::max(sensor_sigma_um, s_res);
  const Eigen::MatrixXd Ns_inv = svd.matrixV() * sv.cwiseInverse().cwiseAbs2().asDiagonal() * svd.matrixV().transpose();
  for (int q = 0; q < kNumLocationErrors; ++q) {
    f.value[q] = x[q];
    f.u[q] = umToMm(f.sigma_um) * std::sqrt(std::max(0.0, Ns_inv(q, q))) / e.scale[q];
  }
  return f;
}

double toReport(int p, double v) { return rtestParameterIsLength(p) ? mmToUm(v) : radToMdeg(v); }
std::string unitOf(int p) { return rtestParameterIsLength(p) ? "um" : "mdeg"; }

}  // namespace

std::vector<std::pair<int, int>> RtestScreen::excluded() const {
  std::vector<std::pair<int, int>> v;
  for (const auto& e : screen.excluded) v.emplace_back(e.run, e.point_id);
  std::sort(v.begin(), v.end());
  return v;
}

namespace {

/// One cycle's linear model for the screen, in um (rows: 3 per pose, then the reset and the
/// re-read when the cycle has them; columns scaled to unit norm): the errors at every tilt and,
/// where the cycle has no reset of its own after the first, the sensors' zero of the series as
/// 3 free offsets (analyze's reference from the first cycle, which the screen of one cycle does
/// not lean on). `screened` marks the rows the screen tests (the poses; not the reset pose's own
/// rows of a first cycle without a reset reading, which are 0 = 0).
struct ScreenDesign {
  Eigen::MatrixXd A;
  Eigen::VectorXd y;
  std::vector<bool> screened;
};

ScreenDesign screenDesign(const ProbePlan& plan, const std::vector<Eigen::Matrix<double, 3, kRtestParams>>& J,
                          const std::vector<int>& tilt_of, int ref_point, int ref_tilt, const RtestCycle& cyc, bool first) {
  const int np = static_cast<int>(plan.points.size()), nt = 1 + *std::max_element(tilt_of.begin(), tilt_of.end());
  const int n = kRtestParams * nt;
  const bool own = cyc.reset.has_value() && cyc.reread.has_value();
  const bool offset = own || !first;
  const int rows = 3 * np + (own ? 6 : 0), ncol = n + (offset ? 3 : 0);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, ncol);
  ScreenDesign d;
  d.y.resize(rows);
  d.screened.assign(static_cast<size_t>(rows), false);
  for (int j = 0; j < np; ++j) {
    A.block(3 * j, kRtestParams * tilt_of[static_cast<size_t>(j)], 3, kRtestParams) += J[static_cast<size_t>(j)];
    if (offset) A.block(3 * j, n, 3, 3).setIdentity();
    else A.block(3 * j, kRtestParams * ref_tilt, 3, kRtestParams) -= J[static_cast<size_t>(ref_point)];
    d.y.segment<3>(3 * j) = mmToUm(1.0) * cyc.readings[static_cast<size_t>(j)].dq_w_mm;
    for (int a = 0; a < 3; ++a) d.screened[static_cast<size_t>(3 * j + a)] = offset || j != ref_point;
  }
  if (own) {
    for (int k2 = 0; k2 < 2; ++k2) {
      A.block(3 * np + 3 * k2, kRtestParams * ref_tilt, 3, kRtestParams) = J[static_cast<size_t>(ref_point)];
      A.block(3 * np + 3 * k2, n, 3, 3).setIdentity();
    }
    d.y.segment<3>(3 * np) = mmToUm(1.0) * cyc.reset->dq_w_mm;
    d.y.segment<3>(3 * np + 3) = mmToUm(1.0) * cyc.reread->dq_w_mm;
  }
  // Unit columns (mm and rad differ by 1e2); a column of zeros (dz and c at the reset's tilt in a
  // cycle referred to a reset) stays zero: the fits below are rank-revealing.
  for (int q = 0; q < ncol; ++q) {
    const double nrm = A.col(q).norm();
    if (nrm > 0) A.col(q) /= nrm;
  }
  d.A = std::move(A);
  return d;
}

int rankOf(const Eigen::MatrixXd& A) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A);
  const auto& sv = svd.singularValues();
  int r = 0;
  for (int i = 0; i < sv.size(); ++i) r += sv[i] > 1e-8 * sv[0] ? 1 : 0;
  return r;
}

}  // namespace

RtestScreen screenRtestReadings(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, double reading_sigma_um,
                                const std::string& declaration, const Eigen::MatrixXd& structured_um2,
                                const Eigen::MatrixXd& structured_draws_um) {
  const auto np3 = 3 * static_cast<Eigen::Index>(plan.points.size());
  if (structured_um2.size() > 0 && (structured_um2.rows() != np3 || structured_um2.cols() != np3))
    throw std::invalid_argument("rtest screen: the structured part is not 3 x the plan's points square");
  if (!(reading_sigma_um > 0) || !std::isfinite(reading_sigma_um))
    throw std::invalid_argument("rtest screen: the declared noise per reading must be > 0");
  const Layout L = layoutOf(plan);
  const Eigen::Vector3d nest = rtestNest_w(plan);
  std::vector<Eigen::Matrix<double, 3, kRtestParams>> J;
  for (const auto& p : plan.points) J.push_back(J_wq_omega(plan.machine.kinematics, p.pose, nest));
  std::vector<ScreenDesign> designs;
  std::vector<int> full_rank;
  for (size_t c = 0; c < cycles.size(); ++c) {
    if (cycles[c].readings.size() != plan.points.size()) throw std::invalid_argument("rtest: cycle with missing readings");
    designs.push_back(screenDesign(plan, J, L.tilt_of_point, L.ref_point, L.ref_tilt, cycles[c], c == 0));
    full_rank.push_back(rankOf(designs.back().A));
  }
  const double s2 = reading_sigma_um * reading_sigma_um;
  // The rows of cycle c's full fit (nothing held out) and their declared covariance.
  auto keptRows = [&](const ScreenDesign& d) {
    std::vector<int> keep;
    for (int i = 0; i < d.A.rows(); ++i)
      if (d.screened[static_cast<size_t>(i)] || i >= 3 * static_cast<int>(plan.points.size())) keep.push_back(i);
    return keep;
  };
  // The reset and re-read rows read the reset pose: its rows of the shared part.
  auto sharedRows = [&](const std::vector<int>& keep) {
    std::vector<Eigen::Index> at;
    for (int i : keep) at.push_back(i < np3 ? i : 3 * (L.ref_point) + i % 3);
    return at;
  };
  // The threshold's null: the first fit's largest statistic over every cycle in each draw of the
  // declared machine (one machine: the structured draw shared by the cycles, the white part each
  // reading's own).
  Eigen::VectorXd null_max;
  if (structured_draws_um.cols() >= kMinScreenNullDraws && structured_um2.size() > 0) {
    if (structured_draws_um.rows() != np3) throw std::invalid_argument("rtest screen: the draws are not 3 x the plan's points");
    Rng rng(kRtestNullSeed, 126);
    null_max = Eigen::VectorXd::Zero(structured_draws_um.cols());
    for (const ScreenDesign& d : designs) {
      const std::vector<int> keep = keptRows(d);
      const std::vector<Eigen::Index> at = sharedRows(keep);
      Eigen::MatrixXd cov = s2 * Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(keep.size()), static_cast<Eigen::Index>(keep.size()));
      cov += structured_um2(at, at);
      Eigen::MatrixXd y = structured_draws_um(at, Eigen::all);
      for (Eigen::Index c = 0; c < y.cols(); ++c)
        for (Eigen::Index r = 0; r < y.rows(); ++r) y(r, c) += reading_sigma_um * rng.normal();
      std::vector<bool> screened;
      for (int i : keep) screened.push_back(d.screened[static_cast<size_t>(i)]);
      null_max = null_max.cwiseMax(screenNullMaxima(deletionStatisticsColumns(y, d.A(keep, Eigen::all), cov), screened));
    }
  }
  // Each fit's statistics, by the values it held out (the screen asks for them after the fit).
  std::map<std::vector<std::pair<int, int>>, Eigen::VectorXd> stats, sensitivities;
  auto fit = [&](const std::function<bool(int, const ProbePoint&)>& hold_out) {
    ScreenedFit res;
    res.summary.termination = Termination::Converged;
    std::vector<double> t_all, k_all;
    for (size_t c = 0; c < designs.size(); ++c) {
      const ScreenDesign& d = designs[c];
      std::vector<int> keep;
      std::vector<bool> held(static_cast<size_t>(d.A.rows()), false);
      for (int i = 0; i < d.A.rows(); ++i) {
        ProbePoint key;
        key.id = i;
        held[static_cast<size_t>(i)] = d.screened[static_cast<size_t>(i)] && hold_out && hold_out(static_cast<int>(c), key);
        const bool zero_row = !d.screened[static_cast<size_t>(i)] && i < 3 * static_cast<int>(plan.points.size());
        if (!held[static_cast<size_t>(i)] && !zero_row) keep.push_back(i);
      }
      const Eigen::MatrixXd Ak = d.A(keep, Eigen::all);
      if (rankOf(Ak) < full_rank[c]) res.summary.termination = Termination::RankDeficient;
      const Eigen::VectorXd b = Ak.completeOrthogonalDecomposition().solve(d.y(keep));
      const Eigen::VectorXd r = d.y - d.A * b;
      Eigen::MatrixXd cov = s2 * Eigen::MatrixXd::Identity(Ak.rows(), Ak.rows());
      if (structured_um2.size() > 0) cov += structured_um2(sharedRows(keep), sharedRows(keep));
      Eigen::VectorXd t = deletionStatistics(r(keep), Ak, cov);
      const Eigen::VectorXd sens = deletionSensitivity(Ak, cov);
      for (size_t k = 0; k < keep.size(); ++k) {
        const int i = keep[k];
        if (!d.screened[static_cast<size_t>(i)]) continue;
        // A value the others cannot predict (its leverage 1) cannot be tested: 0.
        t_all.push_back(std::isfinite(t[static_cast<Eigen::Index>(k)]) ? t[static_cast<Eigen::Index>(k)] : 0.0);
        k_all.push_back(sens[static_cast<Eigen::Index>(k)]);
      }
      for (int i = 0; i < d.A.rows(); ++i)
        if (d.screened[static_cast<size_t>(i)])
          res.residuals.push_back({static_cast<int>(c), i, r[i], 0.0, held[static_cast<size_t>(i)]});
    }
    stats[heldOutTouches(res.residuals)] = Eigen::Map<const Eigen::VectorXd>(t_all.data(), static_cast<Eigen::Index>(t_all.size()));
    sensitivities[heldOutTouches(res.residuals)] =
        Eigen::Map<const Eigen::VectorXd>(k_all.data(), static_cast<Eigen::Index>(k_all.size()));
    return res;
  };
  RtestScreen out;
  out.options.sigma_um = reading_sigma_um;
  out.options.alpha = kRtestScreenAlpha;
  out.options.max_fraction = kRtestScreenMaxFraction;
  out.options.declaration = declaration;
  out.options.null_maxima = [&null_max](const ScreenedFit&) { return null_max; };
  out.options.statistic = [&stats](const ScreenedFit& f) { return stats.at(heldOutTouches(f.residuals)); };
  out.options.sensitivity = [&sensitivities](const ScreenedFit& f) { return sensitivities.at(heldOutTouches(f.residuals)); };
  out.screen = screenOutliers(fit, out.options);
  out.options.statistic = nullptr;  // they read this call's fits
  out.options.null_maxima = nullptr;
  out.options.sensitivity = nullptr;
  for (auto& v : out.screen.reach) {
    const auto& p = plan.points[static_cast<size_t>(v.point_id / 3)];
    v.name = fmt::format("cycle {} pose {} d{}", v.run + 1, p.id, "xyz"[v.point_id % 3]);
    v.point_id = p.id;  // the pose, as the excluded list names it; the name says which sensor
  }
  return out;
}

Json rtestScreenJson(const ProbePlan& plan, const RtestScreen& s) {
  Json ex = Json::array();
  for (const auto& e : s.screen.excluded) {
    const auto& p = plan.points[static_cast<size_t>(e.point_id / 3)];
    ex.push_back({{"cycle", e.run + 1},
                  {"pose", p.id},
                  {"pose_name", p.pose_name},
                  {"axis", std::string(1, "xyz"[e.point_id % 3])},
                  {"residual_um", std::round(e.residual_um * 1e4) / 1e4},
                  {"t", std::round(e.t * 1e3) / 1e3},
                  {"reason", "beyond the threshold: a gross reading (a sensor glitch); left out of every fit"}});
  }
  return screenJson(s.screen, s.options,
                    "each pose reading's value against what the rest of its cycle predicts for it under the declared "
                    "noise per reading (deletion residual) against the normal quantile at alpha / (2 N), worst first, "
                    "refitted after each; the reset and re-read rows are the re-read check's",
                    "values", std::move(ex), rtestScreenText(plan, s));
}

std::string rtestScreenText(const ProbePlan& plan, const RtestScreen& s) {
  const OutlierScreen& o = s.screen;
  const std::string against = fmt::format("the declared noise per reading ({:.3f} um)", s.options.sigma_um);
  if (o.too_many)
    return fmt::format("reading screen: {} of {} values beyond {:.2f} x {} even with the worst left out: more than a "
                       "few glitches, a model that does not fit or a noise declared too small; none left out (rotacal "
                       "diagnose)",
                       o.beyond, o.touches, o.threshold_t, against);
  if (o.excluded.empty())
    return fmt::format("reading screen: no value beyond {:.2f} x {} ({} values)", o.threshold_t, against, o.touches);
  std::string list;
  for (const auto& e : o.excluded)
    list += fmt::format("{}cycle {} pose {} d{} ({:+.2f} um, {:.1f} x)", list.empty() ? "" : ", ", e.run + 1,
                        plan.points[static_cast<size_t>(e.point_id / 3)].id, "xyz"[e.point_id % 3], e.residual_um,
                        std::abs(e.t));
  return fmt::format("reading screen: left out {} of {} values beyond {:.2f} x {} (a sensor glitch; every fit runs "
                     "without them): {}",
                     o.excluded.size(), o.touches, o.threshold_t, against, list);
}

RtestAnalysis analyzeRtest(const ProbePlan& plan, const std::vector<RtestCycle>& cycles, const RtestFitOptions& opt) {
  requireValid(opt, "rtest fit");
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
  if (opt.screen) out.screen = screenRtestReadings(plan, cycles, opt.screenSigmaUm(), opt.declaration, opt.structured_um2,
                                                     opt.structured_draws_um);
  const std::vector<std::pair<int, int>> excluded = out.screen.excluded();
  Eigen::Vector3d ref_dev = Eigen::Vector3d::Zero();  // J_ref omega_0: wq(0,0,t0) - wq*, first cycle
  Eigen::Matrix3d ref_cov = Eigen::Matrix3d::Zero();
  for (size_t c = 0; c < cycles.size(); ++c) {
    const auto& cyc = cycles[c];
    if (cyc.readings.size() != plan.points.size()) throw std::invalid_argument("rtest: cycle with missing readings");
    const bool first = c == 0;
    // With reset reads every cycle is referred to its own reset (002 Eq. (4) per cycle): the
    // sensors' zero of the cycle is a free offset o (3 columns), observed by the reset and
    // re-read rows (model J_ref omega + o) with the poses (J_j omega + o), so that every row
    // keeps its own independent noise. Results without them: the first cycle against its reset
    // pose (Eq. (6) as written), later ones against the first cycle's reference.
    const bool own = cyc.reset.has_value() && cyc.reread.has_value();
    const bool referred = first || own;
    const int rows = m + (own ? 6 : 0);
    const int ncol = n + (own ? 3 : 0);
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, ncol);
    Eigen::VectorXd y(rows);
    for (size_t j = 0; j < plan.points.size(); ++j) {
      const int ti = L.tilt_of_point[j];
      A.block(3 * j, kRtestParams * ti, 3, kRtestParams) += J[j];
      if (own) A.block(3 * j, n, 3, 3).setIdentity();
      else if (first) A.block(3 * j, kRtestParams * L.ref_tilt, 3, kRtestParams) -= Jref;  // 002 Eq. (6)
      y.segment<3>(3 * j) = cyc.readings[j].dq_w_mm + (referred ? Eigen::Vector3d::Zero() : ref_dev);
    }
    if (own) {
      for (int k2 = 0; k2 < 2; ++k2) {
        A.block(m + 3 * k2, kRtestParams * L.ref_tilt, 3, kRtestParams) = Jref;
        A.block(m + 3 * k2, n, 3, 3).setIdentity();
      }
      y.segment<3>(m) = cyc.reset->dq_w_mm;
      y.segment<3>(m + 3) = cyc.reread->dq_w_mm;
    }
    // Columns used: all but dz and c at tilt 0 when the cycle is referred to a reset (they move
    // every reading at tilt 0 alike: the reset, or the offset, takes them).
    std::vector<int> cols;
    for (int q = 0; q < ncol; ++q)
      if (!(referred && (q == dz_ref_col || q == c_ref_col))) cols.push_back(q);
    Eigen::MatrixXd Au(rows, cols.size());
    for (size_t q = 0; q < cols.size(); ++q) Au.col(q) = A.col(cols[q]);
    // Scale columns (mm and rad differ by 1e2) before the rank test.
    Eigen::VectorXd scale(cols.size());
    for (size_t q = 0; q < cols.size(); ++q) scale[q] = std::max(Au.col(q).norm(), 1e-300);
    // The values the screen left out are not fitted (their residual is then what the fit predicts).
    std::vector<int> dropped, keep;
    for (const auto& e : excluded)
      if (e.first == static_cast<int>(c)) dropped.push_back(e.second);
    for (int i = 0; i < rows; ++i)
      if (std::find(dropped.begin(), dropped.end(), i) == dropped.end()) keep.push_back(i);
    const Eigen::MatrixXd As = Au(keep, Eigen::all) * scale.cwiseInverse().asDiagonal();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(As, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto& sv = svd.singularValues();
    if (sv.size() == 0 || sv[sv.size() - 1] < 1e-8 * sv[0])
      throw std::invalid_argument(fmt::format(
          "rtest: the plan cannot separate the six errors at every tilt (condition {:.3g}); use at least 3 C angles "
          "and a nest off the C axis",
          sv[0] / std::max(sv[sv.size() - 1], 1e-300)));
    const Eigen::VectorXd xs = svd.solve(Eigen::VectorXd(y(keep)));
    const Eigen::VectorXd xu = scale.cwiseInverse().asDiagonal() * xs;
    const Eigen::MatrixXd Ns_inv = svd.matrixV() * sv.cwiseInverse().cwiseAbs2().asDiagonal() * svd.matrixV().transpose();
    const Eigen::MatrixXd N_inv = scale.cwiseInverse().asDiagonal() * Ns_inv * scale.cwiseInverse().asDiagonal();
    const Eigen::VectorXd r = y - Au * xu;
    // Without a reset reading of its own the first cycle's reset pose defines the zero: 0 = 0.
    const int zero_rows = first && !own ? 3 : 0;
    const int kept = static_cast<int>(keep.size());
    const int dof = kept - static_cast<int>(cols.size()) - zero_rows;
    const double r2 = r(keep).squaredNorm();
    const double s_res = dof > 0 ? mmToUm(std::sqrt(r2 / dof)) : 0.0;
    RtestCycleFit f;
    f.t_s = cyc.t_s();
    f.sigma_um = std::max(opt.sensor_sigma_um, s_res);
    f.residual_sd_um = s_res;
    f.dof = dof;
    f.residual_rms_um = mmToUm(std::sqrt(r2 / (kept - zero_rows)));
    f.dz_reference_fixed = referred;
    f.own_reset = own;
    if (own) {
      f.reset_checked = true;
      f.reread_minus_reset_mm = cyc.reread->dq_w_mm - cyc.reset->dq_w_mm;
      const double s_um = opt.sensor_sigma_um;
      f.reset_chi2 = mmToUm(mmToUm(f.reread_minus_reset_mm.squaredNorm())) / (2.0 * s_um * s_um);
      f.reset_p = chiSquareSurvival(f.reset_chi2, 3.0);
    }
    Eigen::MatrixXd cov_u = umToMm(f.sigma_um) * umToMm(f.sigma_um) * N_inv;
    if (!referred) {
      // The reference term J_ref omega_0 carries the first cycle's uncertainty into every row.
      Eigen::MatrixXd S(rows, 3);
      for (int j = 0; j < rows / 3; ++j) S.block<3, 3>(3 * j, 0).setIdentity();
      const Eigen::MatrixXd G = N_inv * Au(keep, Eigen::all).transpose() * S(keep, Eigen::all);
      cov_u += G * ref_cov * G.transpose();
    }
    Eigen::VectorXd x = Eigen::VectorXd::Zero(ncol);
    Eigen::MatrixXd cov_full = Eigen::MatrixXd::Zero(ncol, ncol);
    for (size_t a = 0; a < cols.size(); ++a) {
      x[cols[a]] = xu[a];
      for (size_t b = 0; b < cols.size(); ++b) cov_full(cols[a], cols[b]) = cov_u(a, b);
    }
    f.cov = cov_full.topLeftCorner(n, n);
    f.value = Eigen::Map<const Eigen::MatrixXd>(x.data(), kRtestParams, nt);
    f.u = Eigen::MatrixXd(kRtestParams, nt);
    for (int i = 0; i < nt; ++i)
      for (int p = 0; p < kRtestParams; ++p) f.u(p, i) = std::sqrt(std::max(0.0, f.cov(kRtestParams * i + p, kRtestParams * i + p)));
    for (size_t j = 0; j < plan.points.size(); ++j) f.residual_w_mm.push_back(r.segment<3>(3 * j));
    // Linearisation: the exact model at the estimate against the linear one, both referred to
    // the reset pose.
    const Eigen::VectorXd lin = A * x;
    const Eigen::Vector3d lin_ref = own ? Eigen::Vector3d(lin.segment<3>(m)) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d ref_exact =
        referred ? Eigen::Vector3d(exactW(plan, f.value, L.ref_tilt, plan.points[L.ref_point].pose) - nest) : ref_dev;
    for (size_t j = 0; j < plan.points.size(); ++j) {
      const Eigen::Vector3d ex = exactW(plan, f.value, L.tilt_of_point[j], plan.points[j].pose) - nest - ref_exact;
      const Eigen::Vector3d li = lin.segment<3>(3 * j) - lin_ref - (referred ? Eigen::Vector3d::Zero() : ref_dev);
      f.linearisation_um = std::max(f.linearisation_um, mmToUm((ex - li).cwiseAbs().maxCoeff()));
    }
    if (first) {
      out.location = fitLocation(plan, cyc, opt.sensor_sigma_um, dropped);
      const Eigen::VectorXd x_ref = x.segment<kRtestParams>(kRtestParams * L.ref_tilt);
      ref_dev = Jref * x_ref;
      ref_cov = Jref * f.cov.block<kRtestParams, kRtestParams>(kRtestParams * L.ref_tilt, kRtestParams * L.ref_tilt) *
                Jref.transpose();
      if (own) {
        // Later cycles without a reset of their own read against this cycle's zero: the offset.
        ref_dev = -x.segment<3>(n);
        ref_cov = cov_full.block<3, 3>(n, n);
      }
    }
    out.cycles.push_back(std::move(f));
  }
  for (const auto& f : out.cycles) out.reset_checks += f.reset_checked ? 1 : 0;
  out.reset_level = out.reset_checks > 0 ? opt.reset_alpha / out.reset_checks : 0.0;
  for (auto& f : out.cycles) f.sensor_step = f.reset_checked && f.reset_p < out.reset_level;
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
      {"reset", a.reset_checks > 0
                    ? fmt::format("002 Eq. (4): the reset pose {} = C = 0 is read before the first pose of every cycle and "
                                  "each cycle's readings are referred to it (dz and c at {} = 0 are fixed to 0 in every "
                                  "cycle: their drift is not observed); it is re-read at the end of the cycle and "
                                  "compared with the declared sensor noise (reset_checks)",
                                  ax, ax)
                    : fmt::format("002 Eq. (4): sensors zeroed once at {} = C = 0 in the first cycle; the results have no "
                                  "reset / re-read rows, so the reset could not be checked",
                                  ax)},
      {"tool_length", fmt::format("002 Sec. 4.3: {} at {} = 0 is not observable in the first cycle and is set to 0; a "
                                  "tool-length error appears as a fixed pattern in the translations at the other "
                                  "tilts; changes with time are free of it",
                                  rtestParameterName(k, 2), ax)},
      {"c_zero", fmt::format("{} at {} = 0 (a rotation about the C axis) is the C zero, defined by the reset at C = 0: "
                             "{}",
                             rtestParameterName(k, 5), ax,
                             a.reset_checks > 0 ? "set to 0 in every cycle (each is referred to its own reset): its "
                                                  "change with time is not observed, and the other tilts' rotations "
                                                  "carry minus that change about their C axis"
                                                : "set to 0 in the first cycle, its change with time is observed")},
      {"u", "the fit's standard uncertainty (k = 1) from max(sensor repeatability, residual), later cycles include the "
            "first cycle's reference; analyze replaces it by u_c once the budget is evaluated"}};
  size_t used = 0, values = 0;
  double rss = 0;
  const std::vector<std::pair<int, int>> screened_out = a.screen.excluded();
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
    Json rc = {{"checked", f.reset_checked}};
    if (f.reset_checked) {
      const Eigen::Vector3d d = f.reread_minus_reset_mm * 1000.0;
      rc["reread_minus_reset_um"] = {d.x(), d.y(), d.z()};
      rc["chi2"] = f.reset_chi2;
      rc["dof"] = 3;
      rc["p_value"] = f.reset_p;
      rc["sensor_step"] = f.sensor_step;
    }
    cj.push_back({{"index", c + 1},
                  {"t_h", f.t_s / 3600.0},
                  {"residual_rms_um", f.residual_rms_um},
                  {"linearisation_um", f.linearisation_um},
                  {"sigma_um", f.sigma_um},
                  {"own_reset", f.own_reset},
                  {"reset_check", rc},
                  {"errors", e}});
    // The values the screen left out are not fitted: their residual is the glitch itself.
    for (size_t jj = 0; jj < f.residual_w_mm.size(); ++jj)
      for (int ax = 0; ax < 3; ++ax)
        if (!std::binary_search(screened_out.begin(), screened_out.end(), std::make_pair(static_cast<int>(c), 3 * static_cast<int>(jj) + ax))) {
          rss += std::pow(mmToUm(f.residual_w_mm[jj][ax]), 2);
          ++values;
        }
    used += f.residual_w_mm.size();
  }
  j["outliers"] = rtestScreenJson(plan, a.screen);
  j["cycles"] = cj;
  // The re-read check: a difference beyond what the declared noise allows is a
  // sensor step (a knock, a lost count) inside that cycle.
  Json flagged = Json::array(), findings = Json::array();
  for (size_t c = 0; c < a.cycles.size(); ++c) {
    const auto& f = a.cycles[c];
    if (!f.sensor_step) continue;
    flagged.push_back(c + 1);
    const Eigen::Vector3d d = f.reread_minus_reset_mm * 1000.0;
    const double u = std::sqrt(2.0) * a.cycles[c].sigma_um;
    findings.push_back(
        {{"cause", "sensor_step"},
         {"cycle", c + 1},
         {"summary", fmt::format("cycle {}: the reset pose read {:.2f} um ({:.2f}, {:.2f}, {:.2f}) off at the end of the "
                                 "cycle (p = {:.2g}, the declared noise allows {:.2f} um per axis): the sensors stepped "
                                 "or lost a count during the cycle; its readings after the step are off, repeat it",
                                 c + 1, d.norm(), d.x(), d.y(), d.z(), f.reset_p, u)},
         {"parameters", {{"dx", {{"value", d.x()}, {"unit", "um"}, {"u", u}}},
                         {"dy", {{"value", d.y()}, {"unit", "um"}, {"u", u}}},
                         {"dz", {{"value", d.z()}, {"unit", "um"}, {"u", u}}}}}});
  }
  j["reset_checks"] = {{"cycles_checked", a.reset_checks},
                       {"cycles", a.cycles.size()},
                       {"level_per_cycle", a.reset_level},
                       {"sensor_step_cycles", flagged},
                       {"note", a.reset_checks > 0
                                    ? "re-read minus reset against the declared sensor noise, chi-square with 3 dof; the "
                                      "level is alpha over the cycles checked"
                                    : "the reset could not be checked: the results have no reset / re-read rows (pose 0)"}};
  j["findings"] = findings;
  j["points_used"] = used;
  j["residual_rms_um"] = std::sqrt(rss / std::max<size_t>(1, values));
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
  // ISO 230-7 location errors of both axes, separated by the constant-error fit (no
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

std::string rtestReportText(const ProbePlan& plan, const RtestAnalysis& a, const RtestSignedU& su) {
  const Kinematics k = a.kinematics;
  const char ax = tiltAxis(k);
  std::string s = fmt::format("rotacal rtest (002): {} poses, {} cycle(s), machine {}\n", plan.points.size(),
                              a.cycles.size(), plan.machine.name);
  s += a.reset_checks > 0
           ? fmt::format("reset re-read checked in {} of {} cycle(s): {} sensor step(s)\n", a.reset_checks, a.cycles.size(),
                         std::count_if(a.cycles.begin(), a.cycles.end(), [](const RtestCycleFit& f) { return f.sensor_step; }))
           : std::string("the reset could not be checked (no reset / re-read rows in the results)\n");
  for (size_t c = 0; c < a.cycles.size(); ++c) {
    const auto& f = a.cycles[c];
    s += fmt::format("cycle {} at t = {:.2f} h: residual {:.3f} um rms, linearisation {:.2g} um, sigma {:.3f} um\n",
                     c + 1, f.t_s / 3600.0, f.residual_rms_um, f.linearisation_um, f.sigma_um);
    if (f.sensor_step)
      s += fmt::format("  SENSOR STEP: the reset pose re-read {:.2f} um off its reading before the first pose (p = {:.2g}): "
                       "repeat this cycle\n",
                       mmToUm(f.reread_minus_reset_mm.norm()), f.reset_p);
    if (c != 0 && c + 1 != a.cycles.size()) continue;
    const bool tilt_signed = su.tilt_u_c.rows() == kRtestParams && su.tilt_u_c.cols() == static_cast<Eigen::Index>(a.tilt_deg.size());
    s += fmt::format("  ({})\n", tilt_signed ? "value +- u_c, k = 1" : "value +- the fit's u, k = 1");
    s += fmt::format("  {:>8}", std::string(1, ax) + " deg");
    for (int p = 0; p < kRtestParams; ++p) s += fmt::format(" {:>16}", rtestParameterName(k, p) + " " + unitOf(p));
    s += "\n";
    for (size_t i = 0; i < a.tilt_deg.size(); ++i) {
      s += fmt::format("  {:>8g}", a.tilt_deg[i]);
      for (int p = 0; p < kRtestParams; ++p)
        s += fmt::format(" {:>8.3f} +-{:<6.3f}", toReport(p, f.value(p, static_cast<int>(i))),
                         !tilt_signed ? toReport(p, f.u(p, static_cast<int>(i)))
                         : c == 0     ? su.tilt_u_c(p, static_cast<Eigen::Index>(i))
                                      : std::hypot(toReport(p, f.u(p, static_cast<int>(i))),
                                                   su.tilt_u_b(p, static_cast<Eigen::Index>(i))));
      s += "\n";
    }
  }
  if (a.location.identifiable) {
    s += fmt::format("location errors (ISO 230-7, constant over the tilt, first cycle; fit residual {:.3f} um rms; {}):\n",
                     a.location.residual_rms_um, su.location ? "+- u_c, k = 1" : "+- the fit's u, k = 1");
    const auto& info = locationParameters(k);
    for (int q = 0; q < kNumLocationErrors; ++q) {
      const bool len = info[static_cast<size_t>(q)].kind == ParamKind::Length;
      s += fmt::format("  {:<8} {:>8} {:>9.3f} +-{:<6.3f} {}\n", info[static_cast<size_t>(q)].name,
                       info[static_cast<size_t>(q)].iso, len ? mmToUm(a.location.value[q]) : radToMdeg(a.location.value[q]),
                       su.location ? su.location->uCOr(info[static_cast<size_t>(q)].name,
                                                       len ? mmToUm(a.location.u[q]) : radToMdeg(a.location.u[q]))
                                   : len ? mmToUm(a.location.u[q]) : radToMdeg(a.location.u[q]),
                       len ? "um" : "mdeg");
    }
  } else {
    s += "location errors: " + a.location.why + "\n";
  }
  if (a.cycles.size() >= 3) {
    const bool drift_signed = su.drift_u_c.rows() == kRtestParams && su.drift_u_c.cols() == static_cast<Eigen::Index>(a.tilt_deg.size());
    s += fmt::format("drift (straight line across cycles), per hour ({}):\n", drift_signed ? "+- u_c, k = 1" : "+- the fit's u, k = 1");
    for (size_t i = 0; i < a.tilt_deg.size(); ++i) {
      s += fmt::format("  {:>8g}", a.tilt_deg[i]);
      for (int p = 0; p < kRtestParams; ++p)
        s += fmt::format(" {:>8.3f} +-{:<6.3f}", toReport(p, a.rate(p, static_cast<int>(i))) * 3600.0,
                         drift_signed ? su.drift_u_c(p, static_cast<Eigen::Index>(i))
                                      : toReport(p, a.rate_u(p, static_cast<int>(i))) * 3600.0);
      s += "\n";
    }
  }
  return s;
}

}  // namespace rotacal
