#include "core/contributor_draw.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/probe_plan.hpp"
#include "core/rng.hpp"
#include "core/units.hpp"

namespace rotacal {

double pretravelAlong(const std::array<double, 6>& v, const Eigen::Vector3d& u) {
  double s = 0.0;
  for (int k = 0; k < 3; ++k)
    s += u[k] * u[k] * (u[k] >= 0 ? v[static_cast<size_t>(2 * k)] : v[static_cast<size_t>(2 * k + 1)]);
  return s;
}

std::uint64_t contributorStream(const ContributorInfo& info, int run) {
  return (static_cast<std::uint64_t>(run) << 7) | static_cast<std::uint64_t>(&info - contributorCatalog().data());
}

bool isLinearAxisContributor(const ContributorInfo& c) {
  return c.kind == ContributorKind::LinearScale || c.kind == ContributorKind::LinearRandom ||
         c.kind == ContributorKind::Squareness;
}

bool isPerTouchContributor(const ContributorInfo& c) {
  return c.kind == ContributorKind::ProbeRepeatability || c.kind == ContributorKind::SurfaceRoughness;
}

bool isProbeAxesContributor(const ContributorInfo& c) {
  return c.kind == ContributorKind::ProbePretravel || isLinearAxisContributor(c);
}

ContributorSplit splitContributors(const ContributorSet& declared, const std::function<bool(const ContributorInfo&)>& type_a,
                                   const std::function<bool(const ContributorInfo&)>& type_b) {
  ContributorSplit s;
  s.type_b.file = declared.file;
  s.type_b.node_spacing_min_mm = declared.node_spacing_min_mm;
  s.type_b.node_spacing_max_mm = declared.node_spacing_max_mm;
  for (const auto& c : declared.items) {
    if (type_a(*c.info)) s.per_reading_mm2 += c.u[0] * c.u[0];
    else if (type_b(*c.info)) s.type_b.items.push_back(c);
    else s.left_out.emplace_back(c.info->id);
  }
  return s;
}

bool drawLinearAxes(const ContributorSet& set, int only, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                    std::uint64_t seed, int run, LinearAxisErrors* out) {
  ContributorSet linear;
  for (size_t i = 0; i < set.items.size(); ++i)
    if ((only < 0 || static_cast<size_t>(only) == i) && isLinearAxisContributor(*set.items[i].info))
      linear.items.push_back(set.items[i]);
  if (linear.items.empty()) return false;
  linear.node_spacing_min_mm = set.node_spacing_min_mm;
  linear.node_spacing_max_mm = set.node_spacing_max_mm;
  // Streams 120..123: beyond every catalog index (the catalog has fewer than 120 ids).
  const std::uint64_t base = static_cast<std::uint64_t>(run) << 7;
  Rng fixed(seed, base | 120), ax(seed, base | 121), ay(seed, base | 122), az(seed, base | 123);
  drawLinearAxisErrors(linear.linearAxisModel(), lo, hi, fixed, {&ax, &ay, &az}, out);
  return true;
}

Eigen::VectorXd triggersAlong(const ProbePlan& plan, const Truth& truth) {
  const MeasurementRun run = simulate(plan, truth, {1});
  Eigen::VectorXd s(static_cast<Eigen::Index>(plan.points.size()));
  for (size_t i = 0; i < plan.points.size(); ++i)
    s[static_cast<Eigen::Index>(i)] = alongApproach(plan.points[i], run.points[i]);
  return s;
}

void triggerSpan(const ProbePlan& plan, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  *lo = Eigen::Vector3d::Constant(1e300);
  *hi = Eigen::Vector3d::Constant(-1e300);
  for (const auto& p : plan.points) {
    *lo = lo->cwiseMin(p.trigger_m_mm);
    *hi = hi->cwiseMax(p.trigger_m_mm);
  }
}

void drawProbeAxes(const ProbePlan& plan, const ContributorSet& set, const std::function<bool(const ContributorInfo&)>& acts,
                   std::uint64_t seed, int run, int only, ProbeAxesDraw* d) {
  d->pretravel_mm.fill(0.0);
  ContributorSet drawn;  // the accepted ones; `only` keeps its index in `set`
  int drawn_only = -1;
  for (size_t i = 0; i < set.items.size(); ++i) {
    const Contributor& c = set.items[i];
    if (!acts(*c.info)) continue;
    if (!isProbeAxesContributor(*c.info))
      throw std::logic_error("drawProbeAxes: contributor " + std::string(c.info->id) + " is neither probe nor axis");
    if (only >= 0 && static_cast<size_t>(only) == i) drawn_only = static_cast<int>(drawn.items.size());
    if ((only < 0 || static_cast<size_t>(only) == i) && c.info->kind == ContributorKind::ProbePretravel) {
      Rng rng(seed, contributorStream(*c.info, run));
      for (auto& v : d->pretravel_mm) v = c.u[0] * rng.normal();
    }
    drawn.items.push_back(c);
  }
  drawn.node_spacing_min_mm = set.node_spacing_min_mm;
  drawn.node_spacing_max_mm = set.node_spacing_max_mm;
  Eigen::Vector3d lo, hi;
  triggerSpan(plan, &lo, &hi);
  d->linear = (only < 0 || drawn_only >= 0) &&
              drawLinearAxes(drawn, only < 0 ? -1 : drawn_only, lo, hi, seed, run, &d->linear_errors);
}

void applyProbeAxesDraw(const ProbeAxesDraw& d, Truth* truth) {
  if (d.linear) {
    auto drawn = d.linear_errors.asFunction();
    auto before = truth->linear_axis_error;
    if (before)
      truth->linear_axis_error = [drawn, before](const Eigen::Vector3d& c) { return Eigen::Vector3d(drawn(c) + before(c)); };
    else
      truth->linear_axis_error = drawn;
  }
  if (std::any_of(d.pretravel_mm.begin(), d.pretravel_mm.end(), [](double x) { return x != 0.0; })) {
    auto before = truth->pretravel_by_direction_um;
    truth->pretravel_by_direction_um = [v = d.pretravel_mm, before](const Eigen::Vector3d& u) {
      return mmToUm(pretravelAlong(v, u)) + (before ? before(u) : 0.0);
    };
  }
}

Eigen::MatrixXd probeAxesCovariance(const ContributorSet& set, const std::function<bool(const ContributorInfo&)>& acts,
                                    const std::vector<Eigen::Vector3d>& t, const std::vector<Eigen::Vector3d>& u) {
  if (t.size() != u.size()) throw std::invalid_argument("probeAxesCovariance: as many approaches as triggers needed");
  const auto n = static_cast<Eigen::Index>(t.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
  ContributorSet linear;
  linear.node_spacing_min_mm = set.node_spacing_min_mm;
  linear.node_spacing_max_mm = set.node_spacing_max_mm;
  double pretravel_mm = 0.0, per_touch_mm2 = 0.0;
  for (const Contributor& c : set.items) {
    if (!acts(*c.info)) continue;
    if (c.info->kind == ContributorKind::ProbePretravel) pretravel_mm = c.u[0];
    else if (isPerTouchContributor(*c.info)) per_touch_mm2 += c.u[0] * c.u[0];
    else if (isLinearAxisContributor(*c.info)) linear.items.push_back(c);
    else throw std::logic_error("probeAxesCovariance: contributor " + std::string(c.info->id) + " is neither probe nor axis");
  }
  C.diagonal().array() += per_touch_mm2;
  if (pretravel_mm > 0) {
    // pretravelAlong's weight of each of the six directional values, per touch.
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, 6);
    for (Eigen::Index i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) W(i, 2 * k + (u[static_cast<size_t>(i)][k] < 0 ? 1 : 0)) = u[static_cast<size_t>(i)][k] * u[static_cast<size_t>(i)][k];
    C += pretravel_mm * pretravel_mm * W * W.transpose();
  }
  if (linear.items.empty()) return C;
  const LinearAxisModel m = linear.linearAxisModel();
  // e(c) = scale . c + (S_xy c_y + S_xz c_z, S_yz c_z, 0) + sum_a nodes_a(c_a), read along u.
  Eigen::MatrixXd G(n, 6);  // the slopes' coefficients per touch
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d& c = t[static_cast<size_t>(i)];
    const Eigen::Vector3d& a = u[static_cast<size_t>(i)];
    G.row(i) << m.u_scale.x() * c.x() * a.x(), m.u_scale.y() * c.y() * a.y(), m.u_scale.z() * c.z() * a.z(),
        m.u_S_xy * c.y() * a.x(), m.u_S_xz * c.z() * a.x(), m.u_S_yz * c.z() * a.y();
  }
  C += G * G.transpose();
  for (int ax = 0; ax < 3; ++ax) {
    if (m.u_rand.col(ax).maxCoeff() <= 0) continue;
    const Eigen::Vector3d var = m.u_rand.col(ax).cwiseAbs2();
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = i; j < n; ++j) {
        const double w = (u[static_cast<size_t>(i)].cwiseProduct(var)).dot(u[static_cast<size_t>(j)]);
        if (w == 0.0) continue;
        const double k = nodeCorrelation(t[static_cast<size_t>(i)][ax], t[static_cast<size_t>(j)][ax], m.spacing_min_mm,
                                         m.spacing_max_mm);
        C(i, j) += w * k;
        if (j != i) C(j, i) += w * k;
      }
  }
  return C;
}

Eigen::MatrixXd probeAxesDraws(const ContributorSet& set, const std::function<bool(const ContributorInfo&)>& acts,
                               const std::vector<Eigen::Vector3d>& t, const std::vector<Eigen::Vector3d>& u, int draws,
                               std::uint64_t seed) {
  if (t.size() != u.size()) throw std::invalid_argument("probeAxesDraws: as many approaches as triggers needed");
  if (draws < 0) throw std::invalid_argument("probeAxesDraws: a negative number of draws");
  const auto n = static_cast<Eigen::Index>(t.size());
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n, draws);
  ContributorSet linear;
  linear.node_spacing_min_mm = set.node_spacing_min_mm;
  linear.node_spacing_max_mm = set.node_spacing_max_mm;
  const Contributor* pretravel = nullptr;
  double per_touch_mm2 = 0.0;
  for (const Contributor& c : set.items) {
    if (!acts(*c.info)) continue;
    if (c.info->kind == ContributorKind::ProbePretravel) pretravel = &c;
    else if (isPerTouchContributor(*c.info)) per_touch_mm2 += c.u[0] * c.u[0];
    else if (isLinearAxisContributor(*c.info)) linear.items.push_back(c);
    else throw std::logic_error("probeAxesDraws: contributor " + std::string(c.info->id) + " is neither probe nor axis");
  }
  if (n == 0) return D;
  Eigen::Vector3d lo = t.front(), hi = t.front();
  for (const auto& c : t) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  LinearAxisErrors e;
  const double per_touch_mm = std::sqrt(per_touch_mm2);
  for (int d = 0; d < draws; ++d) {
    if (pretravel && pretravel->u[0] > 0) {
      Rng rng(seed, contributorStream(*pretravel->info, d));
      std::array<double, 6> v{};
      for (auto& x : v) x = pretravel->u[0] * rng.normal();
      for (Eigen::Index i = 0; i < n; ++i) D(i, d) += pretravelAlong(v, u[static_cast<size_t>(i)]);
    }
    if (per_touch_mm > 0) {
      // Stream 124: beyond the catalog and drawLinearAxes' 120..123.
      Rng rng(seed, (static_cast<std::uint64_t>(d) << 7) | 124);
      for (Eigen::Index i = 0; i < n; ++i) D(i, d) += per_touch_mm * rng.normal();
    }
    if (!linear.items.empty() && drawLinearAxes(linear, -1, lo, hi, seed, d, &e))
      for (Eigen::Index i = 0; i < n; ++i) D(i, d) += e.error(t[static_cast<size_t>(i)]).dot(u[static_cast<size_t>(i)]);
  }
  return D;
}

namespace {

Json roundedArray(const Eigen::Vector3d& v, double factor) {
  return Json::array({std::round(v.x() * factor * 1e6) / 1e6, std::round(v.y() * factor * 1e6) / 1e6,
                      std::round(v.z() * factor * 1e6) / 1e6});
}

}  // namespace

Json linearAxesRecord(const LinearAxisErrors& e) {
  const auto r6 = [](double v) { return std::round(v * 1e6) / 1e6; };
  Json lin = {{"scale_um_per_m", {r6(e.scale.x() * 1e6), r6(e.scale.y() * 1e6), r6(e.scale.z() * 1e6)}},
              {"squareness_um_per_m", {{"S_xy", r6(e.S_xy * 1e6)}, {"S_xz", r6(e.S_xz * 1e6)}, {"S_yz", r6(e.S_yz * 1e6)}}}};
  Json nodes = Json::object();
  for (int a = 0; a < 3; ++a) {
    const AxisNodes& n = e.nodes[static_cast<size_t>(a)];
    if (n.spacing_mm <= 0) continue;
    Json values = Json::array();
    for (size_t k = 0; k < n.mm[0].size(); ++k)
      values.push_back({r6(mmToUm(n.mm[0][k])), r6(mmToUm(n.mm[1][k])), r6(mmToUm(n.mm[2][k]))});
    nodes[std::string(1, "XYZ"[a])] = {{"spacing_mm", n.spacing_mm}, {"first_node_mm", n.spacing_mm * n.first},
                                       {"values_um_xyz", values}};
  }
  lin["random_nodes"] = nodes;
  return lin;
}

DrawnMachine drawMachine(const ProbePlan& plan, const ContributorSet& set, std::uint64_t seed, Truth* truth) {
  DrawnMachine out;
  Json& rec = out.record;
  rec["seed"] = seed;
  rec["contributors"] = set.file.empty() ? std::string("the machine's") : set.file;
  ProbeAxesDraw axes;
  drawProbeAxes(plan, set, isProbeAxesContributor, seed, 0, -1, &axes);
  applyProbeAxesDraw(axes, truth);
  if (std::any_of(axes.pretravel_mm.begin(), axes.pretravel_mm.end(), [](double v) { return v != 0.0; })) {
    Json p = Json::object();
    const char* dir[6] = {"+X", "-X", "+Y", "-Y", "+Z", "-Z"};
    for (size_t k = 0; k < 6; ++k) p[dir[k]] = std::round(mmToUm(axes.pretravel_mm[k]) * 1e6) / 1e6;
    rec["pretravel_um"] = p;
  }
  if (axes.linear) rec["linear_axes"] = linearAxesRecord(axes.linear_errors);
  double per_touch_mm2 = 0.0;
  for (const Contributor& c : set.items) {
    Rng rng(seed, contributorStream(*c.info, 0));
    switch (c.info->kind) {
      case ContributorKind::ProbeRepeatability:
      case ContributorKind::SurfaceRoughness:
        per_touch_mm2 += c.u[0] * c.u[0];
        break;
      case ContributorKind::SetupPosition:
        for (int k = 0; k < 3; ++k) truth->artefact.setup.translation_mm[k] += c.u[k] * rng.normal();
        break;
      case ContributorKind::SetupOrientation:
        for (int k = 0; k < 3; ++k) truth->artefact.setup.rotation_rad[k] += c.u[k] * rng.normal();
        break;
      case ContributorKind::FormError:
        for (auto& f : truth->artefact.form) {
          f.offset_mm += c.u[0] * rng.normal();
          f.tilt_u_rad += c.u[1] * rng.normal();
          f.tilt_v_rad += c.u[1] * rng.normal();
        }
        break;
      default:
        if (!isProbeAxesContributor(*c.info)) out.left_out.emplace_back(c.info->id);
        break;
    }
  }
  // The declared per-touch scatter replaces the truth file's noise: one declaration, not two.
  if (per_touch_mm2 > 0) truth->noise_um = mmToUm(std::sqrt(per_touch_mm2));
  rec["per_touch_um"] = std::round(truth->noise_um * 1e6) / 1e6;
  rec["setup"] = {{"translation_um", roundedArray(truth->artefact.setup.translation_mm, 1e3)},
                  {"rotation_urad", roundedArray(truth->artefact.setup.rotation_rad, 1e6)}};
  Json form = Json::array();
  for (const auto& f : truth->artefact.form)
    form.push_back({{"offset_um", std::round(mmToUm(f.offset_mm) * 1e6) / 1e6},
                    {"tilt_u_urad", std::round(f.tilt_u_rad * 1e12) / 1e6},
                    {"tilt_v_urad", std::round(f.tilt_v_rad * 1e12) / 1e6}});
  rec["form"] = form;
  if (!out.left_out.empty()) rec["left_out"] = out.left_out;
  return out;
}

}  // namespace rotacal
