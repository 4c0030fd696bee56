#include "cycles/spaceframe/screen.hpp"

#include <fmt/format.h>

#include <map>
#include <memory>
#include <stdexcept>
#include <utility>

#include "core/units.hpp"

namespace rotacal {

SpaceframeTouchProblem spaceframeTouchProblem(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                              const SpaceframeAnalysis& a, const SpaceframeNoise& noise) {
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  const Eigen::Vector3d& origin = layout.origin_w_mm;
  const Kinematics kin = plan.machine.kinematics;
  const std::vector<int> active = activeParameters(layout.nominal_from == "initial");
  const auto np = static_cast<Eigen::Index>(active.size());
  const Eigen::Matrix<double, FrameModel::kSize, 1> unit = FrameModel::reportUnits(kin);
  const std::set<int> held(a.held_out_ids.begin(), a.held_out_ids.end());
  std::map<std::pair<std::string, int>, int> kept;  // (pose, sphere) -> index in a.points
  for (size_t i = 0; i < a.points.size(); ++i) kept[{a.points[i].pose_name, a.points[i].sphere}] = static_cast<int>(i);
  std::vector<std::map<int, Eigen::Vector3d>> trigger(runs.size());
  for (size_t k = 0; k < runs.size(); ++k)
    for (const auto& t : runs[k].points) trigger[k][t.point_id] = t.position_m_mm;

  // Every touch of the plan, point by point: the model's reading and its derivatives (central
  // differences of 1e-3 report units, as the identification's own Jacobian).
  const std::vector<FramePoint> all = framePoints(plan);
  const double step = 1e-3;
  std::vector<std::vector<double>> model(all.size());
  std::vector<Eigen::MatrixXd> D(all.size());  // touches x parameters, um per report unit
  for (size_t i = 0; i < all.size(); ++i) {
    model[i] = a.model.readingsAlong(plan, all[i], origin);
    D[i].resize(static_cast<Eigen::Index>(all[i].point_ids.size()), np);
  }
  const auto x = a.model.toVector();
  for (Eigen::Index c = 0; c < np; ++c) {
    auto xp = x, xm = x;
    xp[active[static_cast<size_t>(c)]] += step / unit[active[static_cast<size_t>(c)]];
    xm[active[static_cast<size_t>(c)]] -= step / unit[active[static_cast<size_t>(c)]];
    const FrameModel mp = FrameModel::fromVector(kin, xp), mm = FrameModel::fromVector(kin, xm);
    for (size_t i = 0; i < all.size(); ++i) {
      const std::vector<double> sp = mp.readingsAlong(plan, all[i], origin), sm = mm.readingsAlong(plan, all[i], origin);
      for (size_t j = 0; j < sp.size(); ++j) D[i](static_cast<Eigen::Index>(j), c) = mmToUm(sp[j] - sm[j]) / (2.0 * step);
    }
  }

  SpaceframeTouchProblem out;
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> res;
  std::vector<std::pair<int, int>> readings;  // (run, plan index) per row
  const Eigen::Index cols = np + static_cast<Eigen::Index>(a.points.size() * runs.size());
  for (size_t i = 0; i < all.size(); ++i) {
    const FramePoint& f = all[i];
    const auto it = kept.find({f.pose_name, f.sphere});
    for (size_t k = 0; k < runs.size(); ++k) {
      std::vector<double> r;
      double mean = 0.0;
      int fitted = 0;
      for (size_t j = 0; j < f.point_ids.size(); ++j) {
        const int id = f.point_ids[j];
        const ProbePoint& q = *plan.findPoint(id);
        const auto t = trigger[k].find(id);
        if (t == trigger[k].end()) throw std::invalid_argument(fmt::format("{}: no trigger for point {}", runs[k].source, id));
        r.push_back(mmToUm(q.approach_m.dot(t->second - q.trigger_m_mm) - model[i][j]));
        if (!held.count(id)) {
          mean += r.back();
          ++fitted;
        }
      }
      // The sphere fit's radius about the model's centre: what moves all its touches alike.
      if (fitted > 0) mean /= fitted;
      for (size_t j = 0; j < f.point_ids.size(); ++j) {
        const int id = f.point_ids[j];
        if (it == kept.end() || held.count(id)) {
          out.held.push_back({{static_cast<int>(k), id}, r[j] - mean});
          continue;
        }
        Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(cols);
        row.head(np) = D[i].row(static_cast<Eigen::Index>(j));
        row[np + static_cast<Eigen::Index>(static_cast<size_t>(it->second) * runs.size() + k)] = -1.0;
        rows.push_back(row);
        res.push_back(r[j] - mean);
        out.touches.emplace_back(static_cast<int>(k), id);
        readings.emplace_back(static_cast<int>(k), noise.index_of_id.at(id));
      }
    }
  }
  const auto m = static_cast<Eigen::Index>(rows.size());
  out.residual_um = Eigen::Map<const Eigen::VectorXd>(res.data(), m);
  out.J.resize(m, cols);
  for (Eigen::Index j = 0; j < m; ++j) out.J.row(j) = rows[static_cast<size_t>(j)];
  out.covariance_um2 = noise.touch.covariance(readings);
  out.readings = std::move(readings);
  return out;
}

std::set<int> SpaceframeScreen::heldOutIds() const {
  std::set<int> ids;
  for (const auto& e : screen.excluded) ids.insert(e.point_id);
  return ids;
}

std::string SpaceframeScreen::text() const {
  std::string s = screen.text();
  if (!fit.points_left_out.empty()) {
    std::string list;
    for (const auto& p : fit.points_left_out) list += (list.empty() ? "" : "; ") + p;
    s += fmt::format("; {} centre{} left out of the fit (the touches left fix no centre and radius): {}", fit.points_left_out.size(),
                     fit.points_left_out.size() == 1 ? "" : "s", list);
  }
  return s;
}

Json SpaceframeScreen::json() const {
  Json j = outlierScreenJson(screen, options);
  j["centres_left_out"] = fit.points_left_out;
  j["repeats"] = "a touch left out is left out of every repeat (each sphere is fitted from the same touches in each)";
  return j;
}

SpaceframeScreen screenSpaceframeTouches(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                         const SpaceframeNoise& noise, const SpaceframeOptions& options) {
  // Each fit the screen asks for, by the touches it holds out: the statistic reads its problem.
  using Key = std::vector<std::pair<int, int>>;
  const auto problems = std::make_shared<std::map<Key, SpaceframeTouchProblem>>();
  std::map<std::set<int>, SpaceframeAnalysis> fits;
  const auto keyOf = [](const std::vector<PointResidual>& residuals) { return heldOutTouches(residuals); };
  bool base_rank_deficient = false;
  const auto fit = [&](const std::function<bool(int, const ProbePoint&)>& hold) {
    ScreenedFit out;
    SpaceframeOptions o = options;
    if (hold)
      for (size_t k = 0; k < runs.size(); ++k)
        for (const auto& p : plan.points)
          if (hold(static_cast<int>(k), p)) o.held_out_ids.insert(p.id);
    SpaceframeAnalysis a;
    try {
      a = analyzeSpaceframe(plan, runs, o);
    } catch (const std::invalid_argument& e) {
      if (!hold) throw;
      // Without this touch the analysis has no fit (a pose's initial centre lost, too few
      // centres): the screen keeps it.
      out.summary.termination = Termination::RankDeficient;
      out.summary.message = e.what();
      return out;
    }
    // A plan whose identification is rank deficient as a whole is screened as it is; one that
    // loses a parameter without a touch keeps that touch.
    if (!hold) base_rank_deficient = a.summary.termination == Termination::RankDeficient;
    if (hold && a.summary.termination == Termination::RankDeficient && !base_rank_deficient) {
      out.summary.termination = Termination::RankDeficient;
      out.summary.message = "the identification lost a parameter";
      return out;
    }
    SpaceframeTouchProblem p = spaceframeTouchProblem(plan, runs, a, noise);
    out.summary.termination = Termination::Converged;
    for (Eigen::Index j = 0; j < p.residual_um.size(); ++j)
      out.residuals.push_back({p.touches[static_cast<size_t>(j)].first, p.touches[static_cast<size_t>(j)].second,
                               p.residual_um[j], 0.0, false});
    for (const auto& [touch, e] : p.held) out.residuals.push_back({touch.first, touch.second, e, 0.0, true});
    (*problems)[keyOf(out.residuals)] = std::move(p);
    fits[o.held_out_ids] = std::move(a);
    return out;
  };
  SpaceframeScreen s;
  s.options.sigma_um = std::sqrt(noise.touch.white_um2);
  s.options.declaration = noise.touch.declaration;
  s.options.statistic = [problems, keyOf](const ScreenedFit& f) {
    const auto it = problems->find(keyOf(f.residuals));
    if (it == problems->end()) throw std::logic_error("spaceframe outlier screen: a statistic asked of a fit never made");
    return deletionStatistics(it->second.residual_um, it->second.J, it->second.covariance_um2);
  };
  s.options.null_maxima = [problems, keyOf, &noise](const ScreenedFit& f) {
    const SpaceframeTouchProblem& p = problems->at(keyOf(f.residuals));
    const Eigen::MatrixXd draws = noise.touch.nullDraws(p.readings, kDeclaredNullSeed + 1);
    if (draws.cols() == 0) return Eigen::VectorXd();
    return screenNullMaxima(deletionStatisticsColumns(draws, p.J, p.covariance_um2));
  };
  s.options.sensitivity = [problems, keyOf](const ScreenedFit& f) {
    const SpaceframeTouchProblem& p = problems->at(keyOf(f.residuals));
    return deletionSensitivity(p.J, p.covariance_um2);
  };
  s.screen = screenOutliers(fit, s.options);
  s.options.null_maxima = nullptr;  // it reads this call's declaration
  s.options.sensitivity = nullptr;
  std::set<int> ids = options.held_out_ids;
  for (int id : s.heldOutIds()) ids.insert(id);
  const auto it = fits.find(ids);
  if (it != fits.end()) {
    s.fit = it->second;
  } else {
    SpaceframeOptions o = options;
    o.held_out_ids = ids;
    s.fit = analyzeSpaceframe(plan, runs, o);
  }
  return s;
}

}  // namespace rotacal
