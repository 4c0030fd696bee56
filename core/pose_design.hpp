#pragma once
// A pose design for a sphere read at rotary poses (issue 19 item 2): which n of the candidate
// poses make the kinematic model's parameters best known. D-optimal (the largest determinant of
// the information of the parameters the poses can separate), by greedy forward selection then
// Fedorov exchange passes. It states what no candidate set separates (held, as identifiability
// names them) and, for the chosen poses, u per parameter for the declared reading noise: the
// figure KinematicsOpt's valuation number stands for, in um and mdeg.
#include <Eigen/Core>
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
  std::string validate() const;
};

struct PoseDesign {
  std::vector<int> chosen;      // indices into the candidates, in the order chosen
  double log_det = 0.0;         // of the free parameters' information, scaled columns
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

}  // namespace rotacal
