#include "cycles/touch154/design.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/limits.hpp"

#include "cycles/touch154/closed_form_map.hpp"
#include "cycles/touch154/uncertainty.hpp"
#include "core/units.hpp"
#include "cycles/touch154/targets.hpp"
#include "core/require_valid.hpp"

namespace rotacal {

bool DesignOptions::validate(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (points < 12 || points > kMaxPlanPoints)
    return fail(fmt::format("the probe budget must be from 12 to {} touches (got {})", kMaxPlanPoints, points));
  if (a_deg.size() > static_cast<size_t>(kMaxListValues) || c_deg.size() > static_cast<size_t>(kMaxListValues))
    return fail(fmt::format("at most {} candidate angles per axis", kMaxListValues));
  if (a_deg.empty() || c_deg.empty()) return fail("at least one A and one C angle are needed");
  if (side_offsets_mm.empty() && top_offsets_mm.empty()) return fail("no target offsets given");
  for (double d : side_depths_mm)
    if (!(d > 0)) return fail("side depths must be > 0 mm below the top");
  if (exchange_passes < 0 || exchange_passes > kMaxExchangePasses)
    return fail(fmt::format("exchange_passes must be from 0 to {}", kMaxExchangePasses));
  return true;
}

namespace {

using touch154::Target;

std::vector<Target> designTargets(const SquareColumn& col, const DesignOptions& o) {
  touch154::Targets t(col);
  for (double d : o.side_depths_mm) {
    if (d >= col.size_mm.z()) throw std::invalid_argument(fmt::format("side depth {:g} mm lies below the piece", d));
    t.addSides(d, o.side_offsets_mm);
  }
  for (double oy : o.top_offsets_mm)
    for (double ox : o.top_offsets_mm) t.addTop(ox, oy);
  return t.list;
}

std::string poseName(const Pose& p) { return fmt::format("A{:g}_C{:g}", p.A, p.C); }

/// A plan of the given poses and (pose index, target) touches, in that order.
ProbePlan assemble(const MachineModel& machine, const std::vector<Pose>& poses,
                   const std::vector<std::pair<int, Target>>& touches, const DesignOptions& o) {
  const SquareColumn& col = *machine.artefact;
  const double r = machine.probe.ball_radius_mm();
  ProbePlan plan;
  plan.cycle = "touch_designed";
  plan.machine = machine;
  plan.options = {{"points", std::to_string(o.points)},
                  {"criterion", o.criterion == DesignOptions::Criterion::A ? "A" : "D"}};
  double sweep = machine.table_diameter_mm / 2;
  for (const auto& corner : col.corners_w()) sweep = std::max(sweep, corner.norm());
  plan.index_z_mm = sweep + r + machine.clearance_mm;
  std::set<int> used;
  for (const auto& t : touches) used.insert(t.first);
  for (int pi = 0; pi < static_cast<int>(poses.size()); ++pi) {
    if (!used.count(pi)) continue;
    const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, poses[static_cast<size_t>(pi)]);
    double top_z = -1e300;
    for (const auto& corner : col.corners_w()) top_z = std::max(top_z, (T * corner).z());
    plan.poses.push_back({poseName(poses[static_cast<size_t>(pi)]), poses[static_cast<size_t>(pi)], top_z + r + machine.clearance_mm});
  }
  int id = 1;
  for (const auto& [pi, t] : touches) {
    const Pose& pose = poses[static_cast<size_t>(pi)];
    const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
    plan.points.push_back(touch154::touchPoint(id++, poseName(pose), pose, T, t, r));
  }
  return plan;
}

/// Whether a vertical stylus reaches the target at the pose (the rule of core/touch154.cpp).
bool reachable(const MachineModel& machine, const Pose& pose, const Target& t) {
  const Eigen::Isometry3d T = T_m_w_nominal(machine.kinematics, pose);
  double top_z = -1e300;
  for (const auto& corner : machine.artefact->corners_w()) top_z = std::max(top_z, (T * corner).z());
  const Eigen::Vector3d n_m = T.linear() * faceNormal_w(t.face);
  if (n_m.z() < -0.05) return false;  // facing down
  const bool from_above = n_m.z() > 0.95;
  const double depth = top_z - (T * t.contact_w).z();
  return from_above || depth <= machine.probe.stylus_length_mm - machine.probe.body_clearance_mm;
}

struct Candidates {
  std::vector<Pose> poses;
  std::vector<std::pair<int, Target>> touches;  // (pose index, target)
};

Candidates candidateTouches(const MachineModel& machine, const DesignOptions& o, std::vector<std::string>* notes) {
  if (machine.kinematics != Kinematics::TableAC)
    throw std::invalid_argument("plan design needs an A/C tilting table (kinematics table_ac)");
  if (!machine.artefact) throw std::invalid_argument("plan design needs a square_column artefact in the machine file");
  requireValid(o, "design options");
  const auto targets = designTargets(*machine.artefact, o);
  Candidates c;
  for (double a : o.a_deg)
    for (double cc : o.c_deg) {
      const Pose pose{a, 0.0, cc};
      const RotaryAxis& ax = machine.rotaryAxis('A');
      if (!ax.continuous && !ax.stroke_deg.contains(a)) {
        if (notes) notes->push_back(fmt::format("pose {}: A is outside its stroke", poseName(pose)));
        continue;
      }
      const int pi = static_cast<int>(c.poses.size());
      c.poses.push_back(pose);
      int reach = 0, fit = 0;
      std::string first_violation;
      for (const auto& t : targets) {
        if (!reachable(machine, pose, t)) continue;
        ++reach;
        // The touch's own moves (index height, safe height, approach, overtravel) within the strokes.
        const auto bad = strokeViolations(assemble(machine, {pose}, {{0, t}}, o));
        if (!bad.empty()) {
          if (first_violation.empty()) first_violation = bad.front();
          continue;
        }
        ++fit;
        c.touches.push_back({pi, t});
      }
      if (notes && fit < reach)
        notes->push_back(fmt::format("pose {}: {} of {} reachable touches leave the strokes ({})", poseName(pose),
                                     reach - fit, reach, first_violation));
    }
  return c;
}

/// The design problem over the candidates: scaled Jacobian (location errors + squareness), the
/// per-target elimination, the trigger covariance, and the criterion of a subset.
class Problem {
 public:
  static constexpr int kP = kNumLocationErrors + 3;

  Problem(const ProbePlan& cand, const ContributorSet& cs, DesignOptions::Criterion criterion) : criterion_(criterion) {
    LocationErrors zero;
    zero.kinematics = cand.machine.kinematics;
    const LinearChain chain = lineariseChain(cand, zero);
    C_ = triggerCovariance(chain, cs);
    const long n = chain.points;
    J_.resize(n, kP);
    J_.leftCols<kNumLocationErrors>() = J_s_e(cand, zero);
    J_.rightCols<3>() = chain.S.middleCols<3>(fixed_var::kSquareness);
    // Scale: one unit of a scaled parameter is its reference uncertainty (000 Table 6 when the
    // contributors file has it; else 1 um / 1 mdeg), squareness in 10 um/m.
    const auto& params = locationParameters(cand.machine.kinematics);
    for (int j = 0; j < kNumLocationErrors; ++j) {
      const bool length = params[static_cast<size_t>(j)].kind == ParamKind::Length;
      double r = length ? umToMm(1.0) : mdegToRad(1.0);
      if (cs.reference) {
        const auto it = cs.reference->combined.find(std::string(params[static_cast<size_t>(j)].name));
        if (it != cs.reference->combined.end() && it->second > 0) r = length ? umToMm(it->second) : mdegToRad(it->second);
      }
      ref_[j] = r;
      prior_[j] = length ? 1.0 : 0.01;  // 1 mm, 10 mrad
    }
    for (int j = kNumLocationErrors; j < kP; ++j) {
      ref_[j] = 1e-5;
      prior_[j] = 1e-3;
    }
    J_ = J_ * ref_.asDiagonal();
    // A vanishing ridge keeps M invertible before the subset identifies everything; the bias it
    // causes, ridge * prior covariance * ridge, is what an unidentified parameter costs: its
    // prior variance.
    const double ridge = 1e-9 * (J_.transpose() * J_).diagonal().maxCoeff() / static_cast<double>(J_.rows());
    L_ = Eigen::Matrix<double, kP, 1>::Constant(ridge).asDiagonal();
    prior_cov_ = (prior_.array() / ref_.array()).square().matrix().asDiagonal();
    a_.resize(n);
    for (long i = 0; i < n; ++i) {
      const ProbePoint& p = cand.points[static_cast<size_t>(i)];
      a_[i] = 1.0 / (T_m_w_nominal(cand.machine.kinematics, p.pose).linear() * p.normal_w).dot(p.approach_m);
      target_.push_back(p.target);
    }
  }

  /// Covariance of the location errors and the squareness (scaled units) for the subset.
  Eigen::Matrix<double, kP, kP> covariance(const std::vector<int>& S) const {
    const long m = static_cast<long>(S.size());
    Eigen::MatrixXd Jt(m, kP);
    for (long r = 0; r < m; ++r) Jt.row(r) = J_.row(S[static_cast<size_t>(r)]);
    // Eliminate the per-target offsets: project each target's rows off its offset column a.
    std::map<int, std::vector<long>> by_target;
    for (long r = 0; r < m; ++r) by_target[target_[static_cast<size_t>(S[static_cast<size_t>(r)])]].push_back(r);
    for (const auto& [t, rows] : by_target) {
      double aa = 0.0;
      Eigen::Matrix<double, 1, kP> aJ = Eigen::Matrix<double, 1, kP>::Zero();
      for (long r : rows) {
        const double a = a_[S[static_cast<size_t>(r)]];
        aa += a * a;
        aJ += a * Jt.row(r);
      }
      for (long r : rows) Jt.row(r) -= a_[S[static_cast<size_t>(r)]] / aa * aJ;
    }
    Eigen::MatrixXd Css(m, m);
    for (long r = 0; r < m; ++r)
      for (long q = 0; q < m; ++q) Css(r, q) = C_(S[static_cast<size_t>(r)], S[static_cast<size_t>(q)]);
    const Eigen::Matrix<double, kP, kP> M = Jt.transpose() * Jt + L_;
    const Eigen::Matrix<double, kP, kP> B = Jt.transpose() * Css * Jt + L_ * prior_cov_ * L_;
    const Eigen::Matrix<double, kP, kP> Minv = M.ldlt().solve(Eigen::Matrix<double, kP, kP>::Identity());
    return Minv * B * Minv;
  }

  /// A: the location errors' variances in reference units, plus the squareness's with a small
  /// weight: enough that a subset leaving it unidentified (charged its prior variance) loses,
  /// since least_squares fits it (identify() refuses a rank-deficient model). D: log det of all
  /// eleven, which is unbounded when any is unidentified.
  double criterion(const std::vector<int>& S) const {
    const auto cov = covariance(S);
    if (criterion_ == DesignOptions::Criterion::A)
      return cov.diagonal().head<kNumLocationErrors>().sum() + kSquarenessWeight * cov.diagonal().tail<3>().sum();
    return cov.ldlt().vectorD().array().log().sum();
  }

  ErrorVector unscaledU(const std::vector<int>& S) const {
    return covariance(S).diagonal().head<kNumLocationErrors>().cwiseMax(0.0).cwiseSqrt().cwiseProduct(
        ref_.head<kNumLocationErrors>());
  }

  static constexpr double kSquarenessWeight = 0.01;

  int target(int i) const { return target_[static_cast<size_t>(i)]; }

 private:
  DesignOptions::Criterion criterion_;
  Eigen::MatrixXd J_;  // scaled
  Eigen::MatrixXd C_;
  Eigen::VectorXd a_;
  std::vector<int> target_;
  Eigen::Matrix<double, kP, 1> ref_, prior_;
  Eigen::Matrix<double, kP, kP> L_, prior_cov_;
};

}  // namespace

ProbePlan designCandidates(const MachineModel& machine, const DesignOptions& options, std::vector<std::string>* notes) {
  const Candidates c = candidateTouches(machine, options, notes);
  return assemble(machine, c.poses, c.touches, options);
}

DesignResult designPlan(const MachineModel& machine, const ContributorSet& cs, const DesignOptions& o) {
  DesignResult res;
  const Candidates cand = candidateTouches(machine, o, &res.notes);
  const int n = static_cast<int>(cand.touches.size());
  res.candidates = n;
  if (n < o.points)
    throw std::invalid_argument(fmt::format("only {} reachable candidate touches for a budget of {}", n, o.points));
  const ProbePlan all = assemble(machine, cand.poses, cand.touches, o);
  const Problem P(all, cs, o.criterion);

  // Greedy forward selection. A touch on a target not yet probed carries no information alone
  // (its offset absorbs it), so a new target enters as a pair: its touch at the first pose that
  // reaches it, and one more.
  std::vector<int> S;
  std::vector<bool> in(static_cast<size_t>(n), false);
  std::map<int, int> count;  // touches per target in S
  std::map<int, std::vector<int>> by_target;
  for (int i = 0; i < n; ++i) by_target[P.target(i)].push_back(i);
  double f = P.criterion(S);
  while (static_cast<int>(S.size()) < o.points) {
    double best_gain = -std::numeric_limits<double>::infinity();
    std::vector<int> best;
    auto consider = [&](const std::vector<int>& add) {
      std::vector<int> T = S;
      T.insert(T.end(), add.begin(), add.end());
      const double gain = (f - P.criterion(T)) / static_cast<double>(add.size());
      if (gain > best_gain) {
        best_gain = gain;
        best = add;
      }
    };
    const bool room_for_pair = static_cast<int>(S.size()) + 2 <= o.points;
    for (int i = 0; i < n; ++i) {
      if (in[static_cast<size_t>(i)]) continue;
      if (count[P.target(i)] > 0) consider({i});
    }
    if (room_for_pair)
      for (const auto& [t, pts] : by_target) {
        if (count[t] > 0) continue;
        for (size_t q = 1; q < pts.size(); ++q) consider({pts.front(), pts[q]});
      }
    if (best.empty())  // one touch left and no probed target to add it to
      for (int i = 0; i < n; ++i)
        if (!in[static_cast<size_t>(i)]) consider({i});
    for (int i : best) {
      S.push_back(i);
      in[static_cast<size_t>(i)] = true;
      ++count[P.target(i)];
    }
    f = P.criterion(S);
  }
  // Exchange passes: swap a chosen touch for a candidate while the criterion improves.
  for (int pass = 0; pass < o.exchange_passes; ++pass) {
    int swaps = 0;
    for (size_t s = 0; s < S.size(); ++s) {
      if (o.progress)
        o.progress(pass * static_cast<int>(S.size()) + static_cast<int>(s), o.exchange_passes * static_cast<int>(S.size()));
      int best_i = -1;
      double best_f = f * (1.0 - 1e-9);
      for (int i = 0; i < n; ++i) {
        if (in[static_cast<size_t>(i)]) continue;
        std::vector<int> T = S;
        T[s] = i;
        const double g = P.criterion(T);
        if (g < best_f) {
          best_f = g;
          best_i = i;
        }
      }
      if (best_i >= 0) {
        in[static_cast<size_t>(S[s])] = false;
        S[s] = best_i;
        in[static_cast<size_t>(best_i)] = true;
        f = best_f;
        ++swaps;
      }
    }
    res.exchanges += swaps;
    if (swaps == 0) break;
  }
  res.criterion = f;
  res.predicted_u = P.unscaledU(S);

  // The plan: candidate order (pose by pose, targets in order) keeps the rotary moves few.
  std::sort(S.begin(), S.end());
  std::vector<std::pair<int, Target>> touches;
  for (int i : S) touches.push_back(cand.touches[static_cast<size_t>(i)]);
  res.plan = assemble(machine, cand.poses, touches, o);
  const auto bad = strokeViolations(res.plan);
  if (!bad.empty()) throw std::invalid_argument("designed plan does not fit the machine: " + bad.front());
  estimateTimes(res.plan);
  return res;
}

}  // namespace rotacal
