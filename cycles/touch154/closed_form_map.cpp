#include "cycles/touch154/closed_form_map.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <stdexcept>

#include "cycles/touch154/closed_form.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/simulation.hpp"

namespace rotacal {

const TiltPairs& tiltPairsPooled() {
  static const TiltPairs p = {{"II", "V"}, {"III", "VI"}, {"IV", "VII"}};
  return p;
}

const TiltPairs& tiltPairs000() {
  static const TiltPairs p = {{"III", "VI"}};
  return p;
}

Eigen::MatrixXd J_s_e(const ProbePlan& plan, const LocationErrors& at) {
  const long n = static_cast<long>(plan.points.size());
  Eigen::MatrixXd J(n, kNumLocationErrors);
  const auto& params = locationParameters(at.kinematics);
  auto along = [&](const Truth& t) {
    const MeasurementRun r = simulate(plan, t, {1});
    Eigen::VectorXd s(n);
    for (long i = 0; i < n; ++i) s[i] = alongApproach(plan.points[static_cast<size_t>(i)], r.points[static_cast<size_t>(i)]);
    return s;
  };
  for (int j = 0; j < kNumLocationErrors; ++j) {
    const double h = params[static_cast<size_t>(j)].kind == ParamKind::Length ? 1e-4 : 1e-6;
    Truth tp, tm;
    tp.errors = at;
    tm.errors = at;
    tp.errors.values[j] += h;
    tm.errors.values[j] -= h;
    J.col(j) = (along(tp) - along(tm)) / (2.0 * h);
  }
  return J;
}

Eigen::RowVectorXd pattern3Map(const ProbePlan& plan, const std::string& pattern, const TiltPairs& pairs, int* count) {
  const long n = static_cast<long>(plan.points.size());
  const Kinematics kin = plan.machine.kinematics;
  std::map<std::pair<std::string, int>, long> at;
  for (long i = 0; i < n; ++i) at[{plan.points[static_cast<size_t>(i)].pose_name, plan.points[static_cast<size_t>(i)].target}] = i;
  auto find = [&](const std::string& pose, int target) {
    const auto it = at.find({pose, target});
    return it == at.end() ? -1L : it->second;
  };
  auto R = [&](long i) -> Eigen::Matrix3d { return T_m_w_nominal(kin, plan.points[static_cast<size_t>(i)].pose).linear(); };
  auto normal = [&](long i) -> Eigen::Vector3d { return R(i) * plan.points[static_cast<size_t>(i)].normal_w; };
  // d(dp_comp(i)) / ds: dp(i) = p(i) - R(i) p(ref), p = trigger + s u.
  Eigen::RowVectorXd v = Eigen::RowVectorXd::Zero(n);
  auto add = [&](double c, long i, long ref, int comp) {
    v[i] += c * plan.points[static_cast<size_t>(i)].approach_m[comp];
    v[ref] -= c * (R(i) * plan.points[static_cast<size_t>(ref)].approach_m)[comp];
  };
  int cnt = 0;
  for (const auto& [pi, pii] : pairs) {
    for (long j = 0; j < n; ++j) {
      const ProbePoint& p = plan.points[static_cast<size_t>(j)];
      if (p.pose_name != pii) continue;
      const long i = find(pi, p.target), ref = find("I", p.target);
      if (i < 0 || ref < 0) continue;
      const Eigen::Vector3d ni = normal(i), nii = normal(j);
      if (pattern == "3-a") {  // x(ii) - x(i), faces facing +-X at both
        if (std::abs(ni.x()) <= 0.99 || std::abs(nii.x()) <= 0.99) continue;
        add(1.0, j, ref, 0);
        add(-1.0, i, ref, 0);
      } else if (pattern == "3-b") {  // z(ii) - y(i): facing +Y at A = 0, +Z at A = -90
        if (ni.y() <= 0.99 || nii.z() <= 0.99) continue;
        add(1.0, j, ref, 2);
        add(-1.0, i, ref, 1);
      } else if (pattern == "3-c") {  // y(ii) + z(i): the top, facing -Y at A = -90
        if (ni.z() <= 0.99 || nii.y() >= -0.99) continue;
        add(1.0, j, ref, 1);
        add(1.0, i, ref, 2);
      } else {
        throw std::invalid_argument("pattern3Map: unknown pattern '" + pattern + "'");
      }
      ++cnt;
    }
  }
  if (cnt > 0) v /= cnt;
  if (count) *count = cnt;
  return v;
}

ClosedFormMatrix closedFormMap(const ProbePlan& plan, const TiltPairs& pairs) {
  const long n = static_cast<long>(plan.points.size());
  MeasurementRun nominal;
  nominal.source = "nominal triggers";
  for (const auto& p : plan.points) nominal.points.push_back({p.id, p.trigger_m_mm, 0.0});
  const std::vector<PatternEquation> eq0 = touch154Patterns(plan, nominal);
  const long np = static_cast<long>(eq0.size());
  Eigen::MatrixXd A(np, kNumLocationErrors), V(np, n);
  for (long k = 0; k < np; ++k) A.row(k) = eq0[static_cast<size_t>(k)].row.transpose();
  const double h = 1e-3;  // the values are linear in the coordinates: any step gives the same map
  MeasurementRun pert = nominal;
  for (long i = 0; i < n; ++i) {
    const size_t si = static_cast<size_t>(i);
    pert.points[si].position_m_mm += h * plan.points[si].approach_m;
    const auto eq = touch154Patterns(plan, pert);
    for (long k = 0; k < np; ++k) V(k, i) = (eq[static_cast<size_t>(k)].value_mm - eq0[static_cast<size_t>(k)].value_mm) / h;
    pert.points[si].position_m_mm = nominal.points[si].position_m_mm;
  }
  if (pairs != tiltPairsPooled()) {
    LocationErrors zero;
    zero.kinematics = plan.machine.kinematics;
    const Eigen::MatrixXd J = J_s_e(plan, zero);
    for (long k = 0; k < np; ++k) {
      const std::string& name = eq0[static_cast<size_t>(k)].name;
      if (name != "3-a" && name != "3-b" && name != "3-c") continue;
      int cnt = 0;
      const Eigen::RowVectorXd m = pattern3Map(plan, name, pairs, &cnt);
      if (cnt == 0) throw std::invalid_argument("closed form: no points for pattern " + name + " at the chosen pose pairs");
      V.row(k) = m;
      A.row(k) = m * J;
    }
  }
  return A.colPivHouseholderQr().solve(V);
}

}  // namespace rotacal
