#pragma once
// What a plan can and cannot separate, read off its Jacobian (a pose design states its
// identifiability). A direction v of the parameters with J v = 0 changes no reading: no data of
// this plan can tell those parameters apart, whatever the noise. Each such direction is named by
// the parameter held at nominal for it (the last one involved, so that set-up and tool terms are
// held before the axes' own errors) and the parameters that move with it.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/error_model.hpp"
#include "core/least_squares.hpp"

namespace rotacal {

struct IdentifiabilityParameter {
  std::string name;
  ParamKind kind;
};

struct UnseparableCombination {
  int held = -1;  // the parameter held at nominal for this direction
  /// The direction, in report units (um, mdeg): the held parameter moves by 1, each other by its
  /// coefficient. Terms below 1e-9 in the scaled parameters (unit column norms) are dropped.
  std::vector<std::pair<int, double>> terms;
  std::string text;  // e.g. "X0B +1 um with X0C +1 um changes no reading"
};

struct Identifiability {
  int rank = 0;
  std::vector<UnseparableCombination> combinations;
  /// Per parameter: held at nominal (one per combination).
  std::vector<bool> held;
  /// Per parameter: involved in no combination: the plan measures it by itself.
  std::vector<bool> separable;
  /// Per parameter: its standard uncertainty, in report units, for whitened residuals of unit
  /// variance, with the held parameters fixed (0 for those). Multiply by the noise whitening
  /// divided out (e.g. the probe's sigma when J is in mm per unit) to get um / mdeg.
  Eigen::VectorXd u_report;
};

/// J_r_p: residuals (whitened) by parameters (mm, rad). hold_first: parameters to hold before
/// the others where a direction involves them (e.g. a table's C zero, which a sphere reads as
/// its own place on the table); then the last involved. rank_tolerance as LeastSquaresOptions.
Identifiability identifiability(const Eigen::MatrixXd& J_r_p, const std::vector<IdentifiabilityParameter>& parameters,
                                const std::vector<int>& hold_first = {},
                                double rank_tolerance = LeastSquaresOptions{}.rank_tolerance);

}  // namespace rotacal
