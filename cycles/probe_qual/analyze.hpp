#pragma once
// The probe's qualification from the touches of a probe_qual plan (ISO 230-10's idea). One fit
// of every touch: the sphere's centre c and the probe's pretravel p_a per approach direction a
// (late triggers positive: the ball centre p_a further along the approach u):
//   |t_j - c| = R + r + (n_j . u_j) p_a(j),
// each row weighted by 1 / |n_j . u_j| so that it reads in um along the approach, where the probe
// scatters. The sphere's calibrated radius R and the nominal ball radius r are taken as exact.
// A pretravel pattern proportional to the horizontal approaches' cos and sin (the first
// harmonic) is a centre offset in X and Y: the fit puts it in the centre and reads the rest (the
// mean and the harmonics from the second on; the top's pretravel is told from the sphere's
// height by the contacts above the equator). The repeatability is the pooled scatter of each
// touch's repeats about their mean, in um along the approach, with its dof and 95 % interval
// (chi-square). u from it through the fit's covariance (Type A).
#include <string>
#include <vector>

#include "core/json_io.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct DirectionPretravel {
  std::string name;
  Eigen::Vector3d approach = Eigen::Vector3d::Zero();  // unit, toward the sphere
  double pretravel_um = 0.0;  // along the approach, late positive
  double u_um = 0.0;          // standard uncertainty (Type A)
  int touches = 0;
};

struct ProbeQualification {
  int touches = 0;
  int directions = 0;
  double repeatability_um = 0.0;       // pooled sd of the repeats about each direction's mean
  int dof = 0;                         // touches - directions
  double repeatability_lo_um = 0.0, repeatability_hi_um = 0.0;  // 95 % interval (chi-square)
  double mean_pretravel_um = 0.0;      // over the horizontal approaches: the effective radius's deficit
  double u_mean_pretravel_um = 0.0;
  double effective_ball_diameter_mm = 0.0;  // nominal less twice the horizontal mean pretravel
  Eigen::Vector3d centre_m_mm = Eigen::Vector3d::Zero();
  std::vector<DirectionPretravel> by_direction;
  double lobing_range_um = 0.0;        // max - min of the horizontal approaches' pretravel
  double lobing_rms_um = 0.0;          // their rms about their mean
  /// What of that rms the noise alone gives (its expectation for a probe without lobing), and the
  /// rms less it (in quadrature, 0 when the noise explains it all): the probe_pretravel contributor.
  double lobing_rms_noise_um = 0.0;
  double lobing_rms_net_um = 0.0;
  // Per touch (weighted: um along the approach): the fit's residual and its row of J (the
  // diagnosis's baseline), the touch of the repeat, the repeat.
  std::vector<double> residuals_um;
  Eigen::MatrixXd J_weighted;          // um per fitted parameter (c in um, pretravel basis in um)
  std::vector<std::string> parameter_names;
  std::vector<int> touch_of, repeat_of;
  std::vector<double> t_s;             // per touch: the controller's clock, else the plan's time
  std::vector<Eigen::Vector3d> normals;
};

/// Throws InputError naming the results file when a trigger is missing or the fit fails.
ProbeQualification qualifyProbe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs);

Json probeQualReportJson(const ProbePlan& plan, const ProbeQualification& q, const std::vector<std::string>& files);
std::string probeQualText(const ProbeQualification& q);

}  // namespace rotacal
