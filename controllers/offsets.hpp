#pragma once
// What every offsets writer shares: the plausibility limit of a written correction (also the
// limit of `rotacal compensate`), the identified errors as the comment lines each file carries,
// and the pivot, second-axis offset and zero error a table A/C or B/C machine's offsets start from.
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "controllers/dialect.hpp"

namespace rotacal::ctl {

/// Plausibility limits of a written correction (request.force overrides them).
constexpr double kMaxLengthCorrectionMm = 0.5;     // a larger pivot error is a setup blunder, not drift
constexpr double kMaxAngleCorrectionMdeg = 100.0;  // 0.1 deg: likewise

/// Why location error `index` of `kinematics` with value `v` (mm / rad) is no plausible
/// correction: not finite, or beyond kMaxLengthCorrectionMm / kMaxAngleCorrectionMdeg (with the
/// parameter, its value and the limit); "" when it is plausible. The one limit of everything
/// that writes a correction: the offsets writers and `rotacal compensate`.
std::string implausibility(Kinematics kinematics, int index, double v);

/// Throws std::invalid_argument with the reason when the request is a head_cb machine's: its
/// parameters are its model's (request.parameters), which only LinuxCNC's writer takes.
void requireNotHeadCb(const OffsetRequest& request);

/// Throws std::invalid_argument naming the parameter, its value and the limit when any
/// identified location error exceeds the plausibility limits and !request.force. Also throws
/// when request.plan is null or a value is not finite.
void requirePlausible(const OffsetRequest& request);

/// A head machine's (request.parameters, ISO 230-7 names): its parameter `name`, or nullptr.
const ParameterEstimate* kinematicParameter(const OffsetRequest& request, std::string_view name);

/// Why no writer but LinuxCNC's takes a head_table machine's parameters (the dialects' refusal).
std::string headTableOffsetsRefusal(std::string_view dialect);

/// "value +- u unit" lines of the identified errors, e.g. "dx_AY (X0A)  14.600 um +- 0.900 um".
/// A head machine's: its parameters by ISO name, the held ones marked.
std::vector<std::string> identifiedLines(const OffsetRequest& request);

/// What the offsets writers of a table A/C or B/C machine start from, the request checked by
/// requirePlausible first.
struct OffsetBasis {
  /// Refuses a head_table request, naming `dialect` (headTableOffsetsRefusal).
  OffsetBasis(const OffsetRequest& request, std::string_view dialect);
  const ProbePlan& plan;
  const MachineModel& machine;
  const LocationErrors& e;
  bool ac;   // table A/C, else B/C
  bool inch;
  double k;  // mm -> the machine's unit
  char tilt;  // the tilting axis, 'A' or 'B'
  /// The tilting axis' pivot error: (dx_AY, dy_AY, dz_AY), or (dx_BY, dy_CB, dz_BY).
  Eigen::Vector3d pivot() const;
  /// The C axis' offset from the tilting axis: (0, dy_CA, 0), or (dx_CB, 0, 0).
  Eigen::Vector3d second() const;
  /// The tilting axis' zero error in `dialect`'s sign of that axis (+1 without it), degrees.
  double zeroDeg(std::string_view dialect) const;
};

}  // namespace rotacal::ctl
