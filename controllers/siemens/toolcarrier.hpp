#pragma once
// The Siemens toolcarrier values the offsets file corrects.
#include <string>
#include <utility>
#include <vector>

#include "core/error_model.hpp"

namespace rotacal {

/// Siemens toolcarrier 1 corrections (mapping UNVERIFIED on a machine): fine offsets added
/// (mm; l2 fine $TC_CARR44-46 = pivot of the tilting axis, l3 fine $TC_CARR55-57 = second axis
/// relative to the first), axis vectors v1 ($TC_CARR7-9, tilting axis) and v2 ($TC_CARR10-12, C)
/// set to the identified unit directions, angle offset $TC_CARR24 of the tilting axis added (deg).
struct SiemensToolcarrierChanges {
  std::vector<std::pair<std::string, double>> add_length;
  std::vector<std::pair<std::string, double>> set_vector;
  double add_angle_deg = 0.0;
};
SiemensToolcarrierChanges siemensToolcarrierChanges(const LocationErrors& identified);

}  // namespace rotacal
