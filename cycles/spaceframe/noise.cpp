#include "cycles/spaceframe/noise.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "core/sphere_centre_fit.hpp"
#include "core/units.hpp"

namespace rotacal {

SpaceframeNoise spaceframeDeclaredNoise(const ProbePlan& plan, const ContributorSet* declared) {
  SpaceframeNoise out;
  out.touch = perTouchDeclaration(declared, plan.machine.probe.repeatability_um);
  std::vector<Eigen::Vector3d> t, u;
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const ProbePoint& p = plan.points[i];
    if (!p.sphere) throw std::invalid_argument(fmt::format("point {} is not a touch on a sphere", p.id));
    out.index_of_id[p.id] = static_cast<int>(i);
    t.push_back(p.trigger_m_mm);
    u.push_back(p.approach_m);
  }
  // The touches' displacements along their approaches: n . u = -1 on every touch (each approaches
  // the centre along an axis), so the reading's variance is the displacement's.
  if (declared) addProbeAxesPart(*declared, t, u, Eigen::VectorXd(), &out.touch);
  return out;
}

Eigen::MatrixXd spaceframeCentreMap(const ProbePlan& plan, const FramePoint& p) {
  std::vector<Eigen::Vector3d> t, u;
  for (int id : p.point_ids) {
    const ProbePoint& q = *plan.findPoint(id);
    t.push_back(q.trigger_m_mm);
    u.push_back(q.approach_m);
  }
  SphereFit at;  // the nominal sphere: what linearSphereFit reads of a fit
  at.centre_mm = p.nominal_m_mm;
  at.radius_fitted = true;
  return linearSphereFit(t, u, at).centre;
}

namespace {

/// The centres' maps side by side (3 x centres rows, one column per touch, point by point) and
/// each touch's plan index.
struct CentreMaps {
  Eigen::MatrixXd M;
  std::vector<int> index;
};

CentreMaps centreMaps(const ProbePlan& plan, const std::vector<FramePoint>& points, const SpaceframeNoise& noise) {
  CentreMaps c;
  std::vector<Eigen::Index> first;
  for (const auto& f : points) {
    first.push_back(static_cast<Eigen::Index>(c.index.size()));
    for (int id : f.point_ids) c.index.push_back(noise.index_of_id.at(id));
  }
  const auto n = static_cast<Eigen::Index>(points.size());
  c.M = Eigen::MatrixXd::Zero(3 * n, static_cast<Eigen::Index>(c.index.size()));
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::MatrixXd m = spaceframeCentreMap(plan, points[static_cast<size_t>(i)]);
    c.M.block(3 * i, first[static_cast<size_t>(i)], 3, m.cols()) = m;
  }
  return c;
}

}  // namespace

Eigen::MatrixXd spaceframeCentreCovariance(const ProbePlan& plan, const std::vector<FramePoint>& points,
                                           const SpaceframeNoise& noise, int runs) {
  if (runs < 1) throw std::invalid_argument("spaceframe declared noise: no repeats");
  const CentreMaps maps = centreMaps(plan, points, noise);
  const auto T = static_cast<Eigen::Index>(maps.index.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(T, T);
  if (noise.touch.structured_um2.size() > 0)
    for (Eigen::Index a = 0; a < T; ++a)
      for (Eigen::Index b = 0; b < T; ++b)
        C(a, b) = noise.touch.structured_um2(maps.index[static_cast<size_t>(a)], maps.index[static_cast<size_t>(b)]);
  // The mean of the repeats: the same machine in each (the structured part once), the white part
  // independent in each.
  C.diagonal().array() += noise.touch.white_um2 / runs;
  return maps.M * C * maps.M.transpose();
}

Eigen::MatrixXd spaceframeCentreNullDraws(const ProbePlan& plan, const std::vector<FramePoint>& points,
                                          const SpaceframeNoise& noise, int runs, std::uint64_t seed) {
  if (runs < 1) throw std::invalid_argument("spaceframe declared noise: no repeats");
  const CentreMaps maps = centreMaps(plan, points, noise);
  const auto T = static_cast<Eigen::Index>(maps.index.size());
  std::vector<std::pair<int, int>> kept;
  for (int r = 0; r < runs; ++r)
    for (int i : maps.index) kept.emplace_back(r, i);
  const Eigen::MatrixXd D = noise.touch.nullDraws(kept, seed);
  if (D.cols() == 0) return Eigen::MatrixXd(maps.M.rows(), 0);
  // Each centre is fitted to the repeats' mean touch: the draws' mean over the runs.
  Eigen::MatrixXd mean = Eigen::MatrixXd::Zero(T, D.cols());
  for (int r = 0; r < runs; ++r) mean += D.middleRows(static_cast<Eigen::Index>(r) * T, T);
  mean /= runs;
  return maps.M * mean;
}

SpaceframeCentreProblem spaceframeCentreProblem(const ProbePlan& plan, const SpaceframeAnalysis& a,
                                                const SpaceframeNoise& noise) {
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  SpaceframeCentreProblem p;
  const auto n = static_cast<Eigen::Index>(a.points.size());
  p.residual_um.resize(3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    p.residual_um.segment<3>(3 * i) =
        mmToUm(1.0) * (a.measured_m_mm[static_cast<size_t>(i)] -
                       a.model.fittedCentre_m(plan, a.points[static_cast<size_t>(i)], layout.origin_w_mm));
  p.J = mmToUm(1.0) * frameJacobian(plan, a.points, layout.origin_w_mm, a.model,
                                    activeParameters(layout.nominal_from == "initial"), 1e-3);
  p.covariance_um2 = spaceframeCentreCovariance(plan, a.points, noise, std::max(1, a.runs));
  p.null_draws_um = spaceframeCentreNullDraws(plan, a.points, noise, std::max(1, a.runs), kDeclaredNullSeed + 2);
  return p;
}

Json spaceframeDeclaredNoiseJson(const SpaceframeNoise& noise, const DeclaredNoiseTest& test) {
  Json j = declaredNoiseJson(noise.touch, test);
  j["level"] = "centres";
  j["test"] = "the identification's residual on the sphere centres, whitened by their declared covariance (the touches' "
              "declared covariance carried through each sphere fit): chi2 on 3 x centres - rank";
  return j;
}

}  // namespace rotacal
