#pragma once
// The Haas MRZP settings the offsets file asks the operator to change; the tests read them
// directly.
#include <string>
#include <utility>
#include <vector>

#include "core/error_model.hpp"

namespace rotacal {

/// Changes (mm) of the Haas MRZP settings 255, 256, 257 (X, Y, Z of the rotary centre): the
/// tilting axis's pivot, A/C: (dx_AY, dy_AY, dz_AY), B/C: (dx_BY, dy_CB, dz_BY). dy_CA / dx_CB
/// (offset between the axes) has no setting. Mapping UNVERIFIED on a machine.
std::vector<std::pair<std::string, double>> haasMrzpChanges(const LocationErrors& identified);

}  // namespace rotacal
