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

#include "core/contributors.hpp"
#include "core/json_io.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

struct DirectionPretravel {
  std::string name;
  Eigen::Vector3d approach = Eigen::Vector3d::Zero();  // unit, toward the sphere
  double pretravel_um = 0.0;  // along the approach, late positive
  double u_um = 0.0;          // combined standard uncertainty u_c
  double u_a_um = 0.0;        // Type A: the repeats' scatter through the fit
  double u_b_um = 0.0;        // Type B: the declared linear axes through the fit (0 when none declared)
  int touches = 0;
};

/// A touch left out of the qualification by the outlier screen.
struct ProbeQualExcluded {
  int run = 0;            // results file, 0-based
  int repeat = 0;         // repeat within the plan, 0-based
  int point_id = 0;
  std::string direction;  // the touch's approach (plan touch name)
  double deviation_um = 0.0;  // from the mean of the same touch's other repeats, along the approach
  double t = 0.0;             // externally studentized, in the screen's step that left it out
};

/// The screen on the repeats (a chip or dirt under one touch): each touch's deviation from the
/// mean of its own repeats, externally studentized by the pooled scatter of every OTHER touch
/// (the leave-one-out repeatability, which the touch under test cannot inflate):
///   t_j = e_j / (s_(j) sqrt(1 - 1/n_g)),  s_(j)^2 = (SS - e_j^2 / (1 - 1/n_g)) / (dof - 1),
/// e_j the touch's residual from its n_g repeats' mean, SS and dof the pooled ones. Under a
/// probe that scatters normally t_j is Student's t with dof - 1 degrees of freedom, whatever the
/// probe's repeatability: no declared value is assumed, which is what this cycle measures.
/// Threshold: the two-sided t quantile at alpha / N (Bonferroni over the N touches). Worst
/// first, recomputed after each; a touch is a candidate only among at least 3 repeats (of 2,
/// both deviate alike and neither can be named). Beyond max_fraction of the touches the data
/// are not a few chips: nothing is excluded and the screen says so (too_many).
struct ProbeQualScreen {
  double alpha = 0.01;
  double max_fraction = 0.05;
  double threshold_t = 0.0;
  int dof = 0;  // of the t distribution at the start (pooled dof - 1)
  int touches = 0;
  bool too_many = false;
  int beyond = 0;  // touches beyond the threshold with the most a few chips can be left out
  std::vector<ProbeQualExcluded> excluded;
  std::string text() const;  // one line for the report
};

struct ProbeQualOptions {
  double alpha = 0.01;         // family-wise rate of a clean qualification losing a touch
  double max_fraction = 0.05;  // of the touches; beyond it nothing is left out
  /// The machine's declared contributors: its linear axes move each touch by their error where
  /// it is read, the same in every repeat, which the repeats cannot see (Type B). Null: none.
  const ContributorSet* declared = nullptr;
};

struct ProbeQualification {
  int touches = 0;
  int directions = 0;
  double repeatability_um = 0.0;       // pooled sd of the repeats about each direction's mean
  int dof = 0;                         // touches - directions
  double repeatability_lo_um = 0.0, repeatability_hi_um = 0.0;  // 95 % interval (chi-square)
  double mean_pretravel_um = 0.0;      // over the horizontal approaches: the effective radius's deficit
  double u_mean_pretravel_um = 0.0;    // u_c
  double u_a_mean_pretravel_um = 0.0, u_b_mean_pretravel_um = 0.0;
  /// The Type B source in words, empty when the declaration holds no linear axis.
  std::string type_b_source;
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
  std::vector<int> point_index;        // per touch: its plan point
  /// The screen; the per-touch vectors above, the fit and the repeatability hold the touches it
  /// kept (all of them when it excluded none).
  ProbeQualScreen screen;
};

/// Throws InputError naming the results file when a trigger is missing or the fit fails.
ProbeQualification qualifyProbe(const ProbePlan& plan, const std::vector<MeasurementRun>& runs,
                                const ProbeQualOptions& options = {});

Json probeQualReportJson(const ProbePlan& plan, const ProbeQualification& q, const std::vector<std::string>& files);
/// REPORT.json's figures: the horizontal pretravel against the contact azimuth (with u_c and the
/// mean), and each touch's deviation from the mean of its repeats by repeat (the kept and the left out).
Json probeQualFiguresJson(const ProbePlan& plan, const ProbeQualification& q);
/// REPORT.json's verdict block (core/verdict.hpp's shape): whether MACHINE.json's probe section
/// should change: its repeatability against the measured one's 95 % interval, the ball diameter
/// where the mean pretravel exceeds its U.
Json probeQualVerdictJson(const ProbeQualification& q, double declared_repeatability_um);
std::string probeQualText(const ProbeQualification& q);

}  // namespace rotacal
