#pragma once
// A pose design for a sphere read at rotary poses: which n of the candidate
// poses make the kinematic model's parameters best known. D-optimal (the largest determinant of
// the information of the parameters the poses can separate), by greedy forward selection then
// Fedorov exchange passes. It states what no candidate set separates (held, as identifiability
// names them) and, for the chosen poses, u per parameter for the declared reading noise: the
// figure KinematicsOpt's valuation number stands for, in um and mdeg.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/identifiability.hpp"
#include "core/kinematic_model.hpp"

namespace rotacal {

struct PoseDesignOptions {
  int poses = 12;
  int exchange_passes = 3;
  /// Standard deviation of a sphere centre's reading in the machine's X, Y, Z (mm).
  Eigen::Vector3d centre_sd_mm = Eigen::Vector3d::Constant(0.0005);
  std::vector<int> hold_first;  // as identifiability()
  /// Empty when valid; otherwise what is wrong, naming the field.
  bool validate(std::string* why) const;
};

struct PoseDesign {
  std::vector<int> chosen;      // indices into the candidates, in the order chosen
  double log_det = 0.0;         // of the free parameters' information, scaled columns
  double budget = 0.0;          // refinePosesForBudget's criterion at the chosen poses (0 for designPoses)
  Identifiability identifiability;  // of the chosen poses (u_report: um / mdeg for the declared noise)
};

/// Any model: candidate k's rows of the whitened Jacobian (residual per its sd, per parameter, in
/// the model's units), over the named parameters (centre_sd_mm is then unused).
///
/// log det of the information of the parameters the candidates can separate, at the subset of
/// the candidates (indices), with the columns scaled by their norms over all candidates (mm and
/// rad weigh alike; D-optimality does not depend on the scale): what designPoses maximises.
/// -inf when the subset does not fix them.
double poseSetLogDet(const std::vector<Eigen::MatrixXd>& candidate_rows, const std::vector<IdentifiabilityParameter>& names,
                     const std::vector<int>& subset, const PoseDesignOptions& options);
double poseSetLogDet(const KinematicModel& model, const std::vector<Pose>& candidates, const std::vector<int>& subset,
                     const PoseDesignOptions& options);

/// Throws std::invalid_argument for invalid options or fewer candidates than poses.
PoseDesign designPoses(const std::vector<Eigen::MatrixXd>& candidate_rows, const std::vector<IdentifiabilityParameter>& names,
                       const PoseDesignOptions& options);
/// The same for centre readings of the kinematic model (rows: J_X_p whitened by centre_sd_mm).
PoseDesign designPoses(const KinematicModel& model, const std::vector<Pose>& candidates, const PoseDesignOptions& options);

/// The A-optimal design for the declared errors: D-optimality weighs every parameter alike and
/// every touch by the probe alone, while the linear axes' random errors are shared by the touches
/// of nearby poses and the reference of one parameter may be far tighter than another's (000
/// Table 6: a_AY 0.3 mdeg). The criterion is sum_k weight_k Var(p_k) of the unweighted least
/// squares (every touch alike, as the fits do) under the touches' covariance C:
/// Var = (J^T J)^-1 J^T C J (J^T J)^-1 over the parameters the candidates separate (the others
/// held, as designPoses holds them).
struct PoseBudgetOptions {
  int exchange_passes = 3;
  Eigen::VectorXd weight;  // per parameter, 1 / its reference u^2 (model units); 0: not counted
  std::vector<int> hold_first;
  /// Empty when valid; otherwise what is wrong, naming the field.
  bool validate(Eigen::Index parameters, std::string* why) const;
};

/// rows_mm: candidate k's rows of J_r_p (mm per model unit, not whitened); covariance: of every
/// candidate's touches (mm^2), stacked in candidate order. The parameters' covariance (model
/// units; held ones 0) for the subset, and the criterion (+inf when the subset does not fix the
/// parameters the candidates separate).
Eigen::MatrixXd poseSetCovariance(const std::vector<Eigen::MatrixXd>& rows_mm, const std::vector<IdentifiabilityParameter>& names,
                                  const Eigen::MatrixXd& covariance, const std::vector<int>& subset,
                                  const PoseBudgetOptions& options);
double poseSetBudget(const std::vector<Eigen::MatrixXd>& rows_mm, const std::vector<IdentifiabilityParameter>& names,
                     const Eigen::MatrixXd& covariance, const std::vector<int>& subset, const PoseBudgetOptions& options);

/// Exchange passes from `start` (designPoses' choice, which fixes every parameter): a chosen pose
/// is swapped for another candidate whenever that lowers poseSetBudget. The same number of poses.
PoseDesign refinePosesForBudget(const std::vector<Eigen::MatrixXd>& rows_mm, const std::vector<IdentifiabilityParameter>& names,
                                const Eigen::MatrixXd& covariance, const std::vector<int>& start,
                                const PoseBudgetOptions& options);

}  // namespace rotacal
