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

Eigen::MatrixXd spaceframeCentreCovariance(const ProbePlan& plan, const std::vector<FramePoint>& points,
                                           const SpaceframeNoise& noise, int runs) {
  if (runs < 1) throw std::invalid_argument("spaceframe declared noise: no repeats");
  std::vector<int> idx;  // plan index of every touch, point by point
  std::vector<Eigen::Index> first;
  for (const auto& f : points) {
    first.push_back(static_cast<Eigen::Index>(idx.size()));
    for (int id : f.point_ids) idx.push_back(noise.index_of_id.at(id));
  }
  const auto T = static_cast<Eigen::Index>(idx.size());
  const auto n = static_cast<Eigen::Index>(points.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(T, T);
  if (noise.touch.structured_um2.size() > 0)
    for (Eigen::Index a = 0; a < T; ++a)
      for (Eigen::Index b = 0; b < T; ++b) C(a, b) = noise.touch.structured_um2(idx[static_cast<size_t>(a)], idx[static_cast<size_t>(b)]);
  // The mean of the repeats: the same machine in each (the structured part once), the white part
  // independent in each.
  C.diagonal().array() += noise.touch.white_um2 / runs;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(3 * n, T);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::MatrixXd m = spaceframeCentreMap(plan, points[static_cast<size_t>(i)]);
    M.block(3 * i, first[static_cast<size_t>(i)], 3, m.cols()) = m;
  }
  return M * C * M.transpose();
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
