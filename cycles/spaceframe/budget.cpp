#include "cycles/spaceframe/budget.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/error_model.hpp"
#include "core/probe_plan.hpp"
#include "core/rng.hpp"
#include "core/sphere_centre_fit.hpp"
#include "core/units.hpp"

namespace rotacal {

bool spaceframeTypeA(const ContributorInfo& c) { return isPerTouchContributor(c); }

bool spaceframeTypeB(const ContributorInfo& c) { return isProbeAxesContributor(c); }

namespace {

// The frame calibration's random stream: beyond the catalog's and the linear axes' (120..123).
constexpr std::uint64_t kFrameStream = 124;
constexpr int kScaleEntry = kNumLocationErrors;       // FrameModel::toVector(): scale X Y Z
constexpr int kSetupEntry = kNumLocationErrors + 3;   // translation X Y Z, rotation X Y Z

bool frameFree(const ProbePlan& plan) { return SpaceframeLayout::fromOptions(plan.options).nominal_from == "initial"; }

/// The budget's parameters: location errors, scale (X Y Z; X Y relative to Z when self-calibrated)
/// and the set-up (calibrated frame only). Their FrameModel entries, names and report units.
void budgetParameters(const ProbePlan& plan, SpaceframeLinearMap* out) {
  const auto& params = locationParameters(plan.machine.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    out->entries.push_back(i);
    out->names.emplace_back(params[i].name);
    out->units.emplace_back(reportUnit(params[i].kind));
  }
  const char* axis[3] = {"X", "Y", "Z"};
  const bool free = frameFree(plan);
  for (int i = 0; i < (free ? 2 : 3); ++i) {
    out->entries.push_back(kScaleEntry + i);
    out->names.push_back(std::string("scale_") + axis[i]);
    out->units.emplace_back("um/m");
  }
  if (free) return;
  for (int i = 0; i < 6; ++i) {
    out->entries.push_back(kSetupEntry + i);
    out->names.push_back(std::string(i < 3 ? "translation_" : "rotation_") + axis[i % 3]);
    out->units.emplace_back(i < 3 ? "um" : "mdeg");
  }
}

}  // namespace

Truth spaceframeIdentifiedTruth(const ProbePlan& plan, const SpaceframeAnalysis& a) {
  Truth t;
  t.errors = a.model.errors;
  const Eigen::Vector3d s = a.model.scale;
  const Eigen::Matrix3d shear = a.model.shear;
  if (!s.isZero() || !shear.isZero())
    t.linear_axis_error = [s, shear](const Eigen::Vector3d& c) { return Eigen::Vector3d(s.cwiseProduct(c) + shear * c); };
  const Eigen::Vector3d origin = SpaceframeLayout::fromOptions(plan.options).origin_w_mm;
  for (const auto& p : plan.points)
    if (p.sphere && !t.sphere_center_error_w_mm.count(p.sphere->id))
      t.sphere_center_error_w_mm[p.sphere->id] =
          a.model.placedCentre_w(p.sphere->center_w_mm, p.sphere->id, origin) - p.sphere->center_w_mm;
  return t;
}

SpaceframeLinearMap linearSpaceframe(const ProbePlan& plan, const SpaceframeAnalysis& a) {
  SpaceframeLinearMap out;
  budgetParameters(plan, &out);
  const int np_points = static_cast<int>(plan.points.size());
  const MeasurementRun ideal = simulate(plan, spaceframeIdentifiedTruth(plan, a), {1});
  out.ideal_s_mm.resize(np_points);
  std::map<int, int> index_of;  // point id -> plan index
  for (int i = 0; i < np_points; ++i) {
    out.ideal_s_mm[i] = alongApproach(plan.points[static_cast<size_t>(i)], ideal.points[static_cast<size_t>(i)]);
    index_of[plan.points[static_cast<size_t>(i)].id] = i;
  }

  // Stage 1: each sphere fit linearised at its solution (core/sphere_centre_fit.hpp).
  const int n = static_cast<int>(a.points.size());
  Eigen::MatrixXd centre_map = Eigen::MatrixXd::Zero(3 * n, np_points);
  out.residual = Eigen::MatrixXd::Zero(np_points, np_points);
  for (int f = 0; f < n; ++f) {
    const FramePoint& fp = a.points[static_cast<size_t>(f)];
    std::vector<int> idx;
    std::vector<Eigen::Vector3d> pts, approaches;
    for (int id : fp.point_ids) {
      const int i = index_of.at(id);
      idx.push_back(i);
      pts.push_back(ideal.points[static_cast<size_t>(i)].position_m_mm);
      approaches.push_back(plan.points[static_cast<size_t>(i)].approach_m);
    }
    const ProbePoint& first = plan.points[static_cast<size_t>(idx.front())];
    SphereFitOptions fo;
    fo.rho_mm = first.sphere->radius_mm + plan.machine.probe.ball_radius_mm();
    const SphereFit fit = fitSphereCentre(pts, fp.nominal_m_mm, fo);
    const SphereFitMap sm = linearSphereFit(pts, approaches, fit);
    for (size_t j = 0; j < idx.size(); ++j) {
      centre_map.block(3 * f, idx[j], 3, 1) = sm.centre.col(static_cast<Eigen::Index>(j));
      for (size_t k = 0; k < idx.size(); ++k)
        out.residual(idx[k], idx[j]) = sm.residual(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j));
    }
    out.stage1_dof += fit.dof;
  }

  // Stage 2: the analysis' unweighted least squares on the centres, at the identified model.
  const std::vector<int> active = activeParameters(frameFree(plan));
  const Eigen::MatrixXd J = frameJacobian(plan, a.points, SpaceframeLayout::fromOptions(plan.options).origin_w_mm, a.model,
                                          active, 1e-3);
  const Eigen::MatrixXd P = J.completeOrthogonalDecomposition().pseudoInverse();  // report units per mm
  out.G.resize(static_cast<Eigen::Index>(out.entries.size()), np_points);
  for (size_t r = 0; r < out.entries.size(); ++r) {
    const auto it = std::find(active.begin(), active.end(), out.entries[r]);
    out.G.row(static_cast<Eigen::Index>(r)) = P.row(it - active.begin()) * centre_map;
  }
  return out;
}

UncertaintyBudget spaceframeBudget(const ProbePlan& plan, const SpaceframeAnalysis& a,
                                   const std::vector<SpaceframeAnalysis>& per_run, const ContributorSet* contributors,
                                   const SpaceframeBudgetOptions& options) {
  options.validateOrThrow();
  const SpaceframeLinearMap lin = linearSpaceframe(plan, a);
  const int n = static_cast<int>(lin.entries.size());
  const double repeats = static_cast<double>(std::max<size_t>(1, per_run.size()));
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  const bool free = layout.nominal_from == "initial";
  const Eigen::Matrix<double, FrameModel::kSize, 1> unit = FrameModel::reportUnits(plan.machine.kinematics);

  UncertaintyBudget b;
  b.names = lin.names;
  b.units = lin.units;

  // The split of the declared contributors; the frame's calibration is Type B when it is the
  // nominal (calibrated frame) and carries a u.
  const ContributorSplit split =
      contributors ? splitContributors(*contributors, spaceframeTypeA, spaceframeTypeB) : ContributorSplit{};
  const double declared_mm2 =
      contributors ? split.per_reading_mm2 : std::pow(umToMm(plan.machine.probe.repeatability_um), 2);
  const ContributorSet& type_b = split.type_b;
  const std::vector<std::string>& left_out = split.left_out;
  const bool frame_term = !free && layout.frame.u_um > 0;
  const Truth base = spaceframeIdentifiedTruth(plan, a);
  std::vector<int> sphere_ids;
  for (const auto& [id, e] : base.sphere_center_error_w_mm) sphere_ids.push_back(id);
  const int nb = static_cast<int>(type_b.items.size());

  // One run's drawn machine: contributor c alone (0..nb-1: the declared, nb: the frame), or all (-1).
  struct Drawn {
    Truth truth;
    Eigen::Vector3d scale = Eigen::Vector3d::Zero();  // the drawn linear scale: the truth of the fitted one
  };
  auto draw = [&](std::uint64_t seed, int run, int c) {
    Drawn d{base, Eigen::Vector3d::Zero()};
    if (c < nb) {
      ProbeAxesDraw pa;
      drawProbeAxes(plan, type_b, spaceframeTypeB, seed, run, c, &pa);
      applyProbeAxesDraw(pa, &d.truth);
      if (pa.linear) d.scale = pa.linear_errors.scale;
    }
    if (frame_term && (c < 0 || c == nb)) {
      Rng rng(seed, (static_cast<std::uint64_t>(run) << 7) | kFrameStream);
      for (int id : sphere_ids)
        for (int k = 0; k < 3; ++k) d.truth.sphere_center_error_w_mm[id][k] += umToMm(layout.frame.u_um) * rng.normal();
    }
    return d;
  };
  auto triggerShift = [&](const Truth& t) { return Eigen::VectorXd(triggersAlong(plan, t) - lin.ideal_s_mm); };

  // Type A: the per-touch scatter through G, its estimate freed of what the Type B contributors
  // leave in the sphere fits' residual, floored at the declared scatter.
  double rss = 0.0;
  int dof = 0;
  for (const auto& f : a.fits) {
    rss += f.rss_mm2;
    dof += f.dof;
  }
  const double s_obs2 = dof > 0 ? rss / dof : 0.0;
  // Type A (readingScatter): the sphere fits' residual also holds what the Type B contributors
  // leave in it, which u_B counts.
  std::vector<double> sys_um2;
  if ((nb > 0 || frame_term) && lin.stage1_dof > 0)
    sys_um2 = contributorResidualVariances(100, options.seed, [&](std::uint64_t seed, int k) {
      return mmToUm(1.0) * mmToUm(1.0) * (lin.residual * triggerShift(draw(seed, k, -1).truth)).squaredNorm() /
             lin.stage1_dof;
    });
  const ReadingScatter scatter =
      readingScatter(mmToUm(1.0) * mmToUm(1.0) * declared_mm2, mmToUm(1.0) * mmToUm(1.0) * s_obs2, dof, sys_um2);
  const double sigma2 = umToMm(1.0) * umToMm(1.0) * scatter.variance_um2;
  Eigen::MatrixXd cov_a = sigma2 / repeats * lin.G * lin.G.transpose();
  b.type_a_source = fmt::format(
      "the per-touch scatter {:.3f} um ({}) through the estimator (sphere fits, then the least squares on the centres), "
      "{} run(s)",
      std::sqrt(scatter.variance_um2), scatter.why, per_run.size() > 1 ? per_run.size() : 1);
  if (!contributors) {
    // Nothing declared: what the centres' misfit says (a-posteriori u) is the larger claim where
    // it is larger; correlations kept by scaling.
    int raised = 0;
    for (int i = 0; i < n; ++i) {
      const double post = a.u[lin.entries[static_cast<size_t>(i)]] * unit[lin.entries[static_cast<size_t>(i)]];
      const double have = cov_a(i, i);
      if (post * post > have && have > 0) {
        const double f = std::sqrt(post * post / have);
        cov_a.row(i) *= f;
        cov_a.col(i) *= f;
        ++raised;
      }
    }
    if (raised > 0)
      b.type_a_source += fmt::format("; {} parameter(s) raised to the centres' a-posteriori u (their misfit is larger)", raised);
  }
  {
    std::vector<Eigen::VectorXd> each;
    for (const auto& r : per_run) each.push_back(spaceframeBudgetValues(plan, r));
    b.type_a_source += raiseToRepeatScatter(&cov_a, each);
  }
  b.cov_a = cov_a;
  b.cov_b = Eigen::MatrixXd::Zero(n, n);
  b.terms.push_back({"data", b.uA()});

  const std::string left_out_text = leftOutNote("the frame's spheres", left_out);
  if (!typeBToRun(&b, contributors || frame_term, nb > 0 || frame_term, "the space frame", left_out_text)) return b;
  MonteCarloProblem p;
  p.parameters = n;
  for (const auto& c : type_b.items) p.contributors.emplace_back(c.info->id);
  if (frame_term) p.contributors.emplace_back(kFrameCalibrationContributor);
  p.deviation = [&](std::uint64_t seed, int run, int c) -> Eigen::VectorXd {
    const Drawn d = draw(seed, run, c);
    Eigen::VectorXd dev = lin.G * triggerShift(d.truth);
    // The fitted scale's truth is the drawn one (relative to Z when self-calibrated).
    for (int i = 0; i < n; ++i) {
      const int e = lin.entries[static_cast<size_t>(i)];
      if (e >= kScaleEntry && e < kScaleEntry + 3)
        dev[i] -= 1e6 * (d.scale[e - kScaleEntry] - (free ? d.scale.z() : 0.0));
    }
    return dev;
  };
  const MonteCarloResult mc = runMonteCarlo(p, options.runs, options.alone_runs, options.seed, options.threads);
  setTypeB(&b, mc, p.contributors);
  b.seed = options.seed;
  b.type_b_source = fmt::format(
      "{} declared contributors (from {}){} drawn on the exact simulator (full HTMs, exact ball-on-sphere contact) around "
      "the identified model, the triggers' deviation run through the estimator linearised there (sphere fits and least "
      "squares), {} runs, seed {}{}",
      nb, contributors ? contributorsSource(*contributors) : std::string("none"),
      frame_term ? fmt::format(" and the frame's calibration ({:g} um per coordinate, {})", layout.frame.u_um,
                               layout.frame.source)
                 : std::string(),
      options.runs, options.seed, left_out_text);
  return b;
}

Eigen::VectorXd spaceframeBudgetValues(const ProbePlan& plan, const SpaceframeAnalysis& a) {
  SpaceframeLinearMap names;
  budgetParameters(plan, &names);
  const Eigen::Matrix<double, FrameModel::kSize, 1> v = a.model.toVector(), unit = FrameModel::reportUnits(plan.machine.kinematics);
  Eigen::VectorXd out(static_cast<Eigen::Index>(names.entries.size()));
  for (size_t i = 0; i < names.entries.size(); ++i) out[static_cast<Eigen::Index>(i)] = v[names.entries[i]] * unit[names.entries[i]];
  return out;
}

void addSpaceframeBudget(Json* report, const UncertaintyBudget& b, const Eigen::VectorXd& values) {
  addBudgetFields(&(*report)["location_errors"], b.slice(0, kNumLocationErrors));
  int first = kNumLocationErrors;
  int scales = 0;
  while (first + scales < b.size() && b.names[static_cast<size_t>(first + scales)].rfind("scale_", 0) == 0) ++scales;
  UncertaintyBudget sc = b.slice(first, scales);
  for (auto& name : sc.names) name = name.substr(6);  // REPORT.json's linear_axis_scale: X, Y, Z
  if (report->contains("linear_axis_scale")) addBudgetFields(&(*report)["linear_axis_scale"], sc);
  if (report->contains("frame_setup")) addBudgetFields(&(*report)["frame_setup"], b);
  (*report)["uncertainty"] = budgetJson(b, values);
}

}  // namespace rotacal
