#pragma once
// The HAL side of LinuxCNC's offsets: the trt-kins component of a table machine, the changes of
// its pins, and the setp lines of a HAL file read back.
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "controllers/dialect.hpp"
#include "core/error_model.hpp"

namespace rotacal {

/// LinuxCNC kinematics component of a table machine: "xyzac-trt-kins", "xyzbc-trt-kins" or "xyzab_tdr_kins";
/// of a B head over a C table (head_table): "maxkins"; of the C/B head machine (head_cb): "5axiskins".
std::string linuxcncKinsComponent(Kinematics kinematics);

/// Changes (mm) of the trt-kins HAL pins that apply the identified location errors (added to
/// the pins' previous values), in the order they are written:
///  A/C: x-rot-point += dx_AY, y-rot-point += dy_AY + dy_CA, z-rot-point += dz_AY,
///       y-offset += -dy_CA, z-offset += 0
///       (A pivot = rot-point + offset = (dx_AY, dy_AY, dz_AY); the C axis passes through rot-point)
///  B/C: x-rot-point += dx_BY + dx_CB, y-rot-point += dy_CB, z-rot-point += dz_BY,
///       x-offset += -dx_CB, z-offset += 0
///       (B pivot = rot-point + offset = (dx_BY, dy_CB, dz_BY); the C axis passes through rot-point)
///  A/B (xyzab_tdr_kins): x-rot-point += dx_BY, y-rot-point += dy_AB, z-rot-point += dz_BY,
///       z-offset += dz_AB (the B axis through rot-point, the A axis through rot-point + offset)
std::vector<std::pair<std::string, double>> linuxcncKinsChanges(const LocationErrors& identified);

/// The `setp <component>.<pin> <value>` lines of a HAL file: pin -> value. '#' starts a comment.
/// Throws std::invalid_argument("line N: ...") when such a line's value is not a number.
std::map<std::string, double> parseHalSetp(const std::string& text, const std::string& component);

/// The axis values of the `G10 L2 P1` line of a previous work-offset file (an offsets file named
/// *.ngc), so that the new file accumulates: axis -> value, every one of `axes` (e.g. "XYZB")
/// present, 0 where the line does not set it; all zero when `text` is empty. Comments in
/// parentheses are ignored. Throws std::invalid_argument naming the line when a word is not one of
/// `axes` with a number, or when a non-empty file has no such line.
std::map<char, double> previousWorkOffset(const std::string& text, std::string_view axes);

/// What a work-offset file states for each of `axes`, in that order: a step "<axis>: previous P
/// change C new N" (for the caller's comment form) and the `G10 L2 P1` line setting previous +
/// change; `decimals(axis)` digits. `previous` holds every axis (previousWorkOffset's), `change` too.
struct WorkOffsetChange {
  std::vector<std::string> steps;
  std::string g10;
};
WorkOffsetChange workOffsetChange(std::string_view axes, const std::map<char, double>& previous,
                                  const std::map<char, double>& change, const std::function<int(char)>& decimals);

/// A head_cb machine's offsets (request.parameters, its model's): the HAL file that moves
/// 5axiskins.pivot-length by dL (previous + change = new, MACHINE.json's pivot_to_ball_mm when
/// no previous file sets it), the other parameters listed with their route
/// (controllers/linuxcnc/head_cb_offsets.cpp). Throws std::invalid_argument as requirePlausible does.
std::string linuxcncHeadCbHal(const OffsetRequest& request);
/// The same as a G10 L2 P1 program (an offsets file named *.ngc): G54's B and C move by the
/// controller's sign times -B0B and -C0C (deg); X Y Z stay (the head's place reads as the sphere's).
std::string linuxcncHeadCbWorkOffsets(const OffsetRequest& request);

}  // namespace rotacal
