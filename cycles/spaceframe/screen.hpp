#pragma once
// The outlier screen of the space-frame cycle (core/outliers.hpp): a touch that hit a chip or dirt
// on a sphere, found against the declared noise of the touches (cycles/spaceframe/noise.hpp).
//
// The screen reads the touches, not the centres: a centre fitted from 4 touches (every tilted
// sphere) has no residual of its own, so a chip there only moves the centre, and which touch
// moved it is a question about touches. Each touch's statistic is the generalized least squares
// deletion residual (core/declared_noise.hpp deletionStatistics) of the identification seen touch
// by touch: the reading along the approach against the identified model's exact reading, the
// span that of the model's parameters (each touch through its sphere's centre) beside one radius
// per sphere fit and repeat; N(0, 1) under the declaration for every touch. Bonferroni over the
// touches at 1 % (clean data lose a touch in 1 % of the runs), worst first and refitted after
// each, at most 5 % of the touches; beyond that nothing is left out and the screen says so
// (too_many): the data are then no longer a few chips, and analyze holds its results back.
// A touch left out is left out of every repeat; a sphere whose touches left fix no centre and
// radius at a pose (fewer than 4, or 4 on its equator) leaves the fit there
// (SpaceframeOptions::held_out_ids).
#include <Eigen/Core>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/outliers.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/spaceframe/noise.hpp"

namespace rotacal {

/// The identification touch by touch. Rows: every fitted touch of every run (point by point, run
/// by run). residual_um: the reading minus the model's (nominal radius), less the mean of its
/// sphere fit's touches (their radius fitted about the model's centre): what the report shows;
/// J (um per report unit, then one column per sphere fit and repeat: its radius); the touches'
/// declared covariance (um^2).
struct SpaceframeTouchProblem {
  Eigen::VectorXd residual_um;
  Eigen::MatrixXd J;
  Eigen::MatrixXd covariance_um2;
  std::vector<std::pair<int, int>> touches;                   // (run, point id) per row
  std::vector<std::pair<int, int>> readings;                  // (run, plan index) per row: the declaration's keys
  std::vector<std::pair<std::pair<int, int>, double>> held;   // touches not fitted: (run, id), residual
};
SpaceframeTouchProblem spaceframeTouchProblem(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                              const SpaceframeAnalysis& analysis, const SpaceframeNoise& noise);

struct SpaceframeScreen {
  OutlierOptions options;
  OutlierScreen screen;
  SpaceframeAnalysis fit;  // the analysis without the excluded touches (all of them when too_many)
  /// The plan point ids the analysis left out (the screen's excluded touches, every run).
  std::set<int> heldOutIds() const;
  std::string text() const;  // the screen's line, and the centres it took out of the fit
  Json json() const;         // REPORT.json's `outliers`
};
SpaceframeScreen screenSpaceframeTouches(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                         const SpaceframeNoise& noise, const SpaceframeOptions& options = {});

}  // namespace rotacal
