#include "cycles/tooltip/noise.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/units.hpp"
#include "cycles/tooltip/budget.hpp"

namespace rotacal {

namespace {

std::string fromOf(const ContributorSet& set) {
  return set.file.empty() ? std::string("the machine's contributors") : set.file;
}

}  // namespace

std::vector<std::pair<int, int>> tooltipReadValues(const ProbePlan& plan, const std::vector<TooltipRun>& runs) {
  const std::vector<int> refs = tooltipReferences(plan);
  std::vector<std::pair<int, int>> kept;
  for (size_t r = 0; r < runs.size(); ++r)
    for (size_t k = 0; k < runs[r].size() && k < refs.size(); ++k) {
      if (refs[k] == static_cast<int>(k)) continue;
      if (std::isfinite(runs[r][k].t_um)) kept.emplace_back(static_cast<int>(r), static_cast<int>(2 * k));
      if (std::isfinite(runs[r][k].z_um)) kept.emplace_back(static_cast<int>(r), static_cast<int>(2 * k + 1));
    }
  return kept;
}

Eigen::MatrixXd tooltipPerRunUm2(const ProbePlan& plan, double white_um2) {
  if (!(white_um2 >= 0) || !std::isfinite(white_um2))
    throw std::invalid_argument(fmt::format("tooltip declared noise: per-reading variance {} um^2 (expected >= 0)", white_um2));
  const std::vector<int> refs = tooltipReferences(plan);
  const auto n = 2 * static_cast<Eigen::Index>(refs.size());
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, n);
  for (size_t a = 0; a < refs.size(); ++a)
    for (size_t b = 0; b < refs.size(); ++b) {
      if (refs[a] == static_cast<int>(a) || refs[b] == static_cast<int>(b) || refs[a] != refs[b]) continue;
      for (Eigen::Index c = 0; c < 2; ++c) P(2 * static_cast<Eigen::Index>(a) + c, 2 * static_cast<Eigen::Index>(b) + c) = white_um2;
    }
  return P;
}

Eigen::MatrixXd tooltipStructuredUm2(const std::vector<const ProbePlan*>& plans, const ContributorSet& set,
                                     const std::vector<const TooltipRun*>& about) {
  if (about.size() != plans.size()) throw std::invalid_argument("tooltip declared noise: one deviation run per plan");
  std::vector<Eigen::Index> first;  // each plan's first value
  Eigen::Index n = 0;
  for (const ProbePlan* p : plans) {
    first.push_back(n);
    n += 2 * static_cast<Eigen::Index>(p->points.size());
  }
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
  ContributorSet linear;
  linear.node_spacing_min_mm = set.node_spacing_min_mm;
  linear.node_spacing_max_mm = set.node_spacing_max_mm;
  double tilt_rad = 0.0;
  for (const Contributor& c : set.items) {
    if (isLinearAxisContributor(*c.info) && c.u.cwiseAbs().maxCoeff() > 0) linear.items.push_back(c);
    if (c.info->kind == ContributorKind::LaserAlignment) tilt_rad = c.u[0];
  }
  if (!linear.items.empty()) {
    // The linear axes' error at each value's pivot command along its beam (probeAxesCovariance,
    // the model drawLinearAxes draws), then each value less its zero reading's.
    std::vector<Eigen::Vector3d> t, u;
    Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n, n);
    for (size_t p = 0; p < plans.size(); ++p) {
      const ProbePlan& plan = *plans[p];
      const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
      const std::vector<int> refs = tooltipReferences(plan);
      for (size_t k = 0; k < plan.points.size(); ++k)
        for (int c = 0; c < 2; ++c) {
          Eigen::Vector3d beam = Eigen::Vector3d::Zero();
          beam[c == 0 ? (o.axis == 'A' ? 1 : 0) : 2] = 1.0;
          t.push_back(plan.points[k].trigger_m_mm);
          u.push_back(beam);
          const Eigen::Index row = first[p] + 2 * static_cast<Eigen::Index>(k) + c;
          if (refs[k] == static_cast<int>(k)) continue;
          D(row, row) = 1.0;
          D(row, first[p] + 2 * refs[k] + c) = -1.0;
        }
    }
    const Eigen::MatrixXd C = probeAxesCovariance(linear, isLinearAxisContributor, t, u);
    S += kUmPerMm * kUmPerMm * D * C * D.transpose();
  }
  if (tilt_rad > 0) {
    // A beam tilted by tau in the read plane reads tau x the other in-plane component; out of
    // it, the unread component, which only the linear axes move (second order with the tilt).
    // The tilts of the two beams are independent: no term between components.
    for (size_t p = 0; p < plans.size(); ++p) {
      if (!about[p]) continue;
      const TooltipRun& dev = *about[p];
      if (dev.size() != plans[p]->points.size()) throw std::invalid_argument("tooltip declared noise: a deviation run does not match its plan");
      const auto m = static_cast<Eigen::Index>(dev.size());
      Eigen::VectorXd rt(m), rz(m);
      for (Eigen::Index k = 0; k < m; ++k) {
        rt[k] = std::isfinite(dev[static_cast<size_t>(k)].t_um) ? dev[static_cast<size_t>(k)].t_um : 0.0;
        rz[k] = std::isfinite(dev[static_cast<size_t>(k)].z_um) ? dev[static_cast<size_t>(k)].z_um : 0.0;
      }
      const double v = tilt_rad * tilt_rad;
      for (Eigen::Index a = 0; a < m; ++a)
        for (Eigen::Index b = 0; b < m; ++b) {
          S(first[p] + 2 * a, first[p] + 2 * b) += v * rz[a] * rz[b];
          S(first[p] + 2 * a + 1, first[p] + 2 * b + 1) += v * rt[a] * rt[b];
        }
    }
  }
  return S;
}

DeclaredNoise tooltipDeclaredNoise(const ProbePlan& plan, const ContributorSet* declared, const TooltipRun* about) {
  const TooltipOptions o = tooltipOptionsFrom(plan.options, plan.machine);
  DeclaredNoise d;
  const std::string plan_noise = fmt::format("laser_noise_um {:.3f} um (PLAN.json)", o.noise_um);
  if (!declared) {
    d.white_um2 = o.noise_um * o.noise_um;
    d.declaration = fmt::format("declared: {} only", plan_noise);
    d.repeatability_only = true;
    d.per_run_um2 = tooltipPerRunUm2(plan, d.white_um2);
    return d;
  }
  // The budget's split: the per-reading part it measures by the residual, the Type B part it
  // draws, the rest that does not act on the readings.
  std::string parts;
  bool resolution = false;
  for (const Contributor& c : declared->items) {
    if (!tooltipTypeA(*c.info)) continue;
    d.white_um2 += mmToUm(c.u[0]) * mmToUm(c.u[0]);
    parts += fmt::format("{}{} {:.3f} um", parts.empty() ? "" : " + ", c.info->id, mmToUm(c.u[0]));
    resolution = resolution || c.info->kind == ContributorKind::LaserResolution;
  }
  if (!resolution) {
    d.white_um2 += o.noise_um * o.noise_um;
    parts = parts.empty() ? plan_noise : plan_noise + " + " + parts;
  }
  std::string shared, left_out;
  for (const Contributor& c : declared->items) {
    if (tooltipTypeA(*c.info)) continue;
    std::string& list = tooltipTypeB(*c.info) ? shared : left_out;
    if (c.u.cwiseAbs().maxCoeff() > 0) list += fmt::format("{}{}", list.empty() ? "" : ", ", c.info->id);
  }
  d.declaration = fmt::format("declared per reading: {} = {:.3f} um (from {})", parts, std::sqrt(d.white_um2),
                              fromOf(*declared));
  d.repeatability_only = shared.empty();
  if (!shared.empty()) {
    d.structured_um2 = tooltipStructuredUm2({&plan}, *declared, {about});
    const std::vector<int> refs = tooltipReferences(plan);
    double sum = 0.0;
    int count = 0;
    for (size_t k = 0; k < refs.size(); ++k)
      if (refs[k] != static_cast<int>(k)) {
        sum += d.structured_um2(2 * static_cast<Eigen::Index>(k), 2 * static_cast<Eigen::Index>(k)) +
               d.structured_um2(2 * static_cast<Eigen::Index>(k) + 1, 2 * static_cast<Eigen::Index>(k) + 1);
        count += 2;
      }
    d.declaration += fmt::format("; shared between readings, to first order: {} ({:.2f} um rms per reading)", shared,
                                 count > 0 ? std::sqrt(sum / count) : 0.0);
  }
  if (!left_out.empty()) d.declaration += fmt::format("; not acting on the tool-tip readings: {}", left_out);
  if (parts == plan_noise && shared.empty())
    d.declaration = fmt::format("declared: {} only ({} declares no laser or axis contributor{})", plan_noise,
                                fromOf(*declared), left_out.empty() ? "" : "; " + left_out + " do not act here");
  else
    d.declaration += "; each sweep's laser zero read with the same per-reading scatter, shared by the sweep's readings of one run";
  d.per_run_um2 = tooltipPerRunUm2(plan, d.white_um2);
  return d;
}

}  // namespace rotacal
