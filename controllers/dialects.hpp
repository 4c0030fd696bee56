#pragma once
// The few free functions of the dialects that tests and tools need directly
// (controllers/dialect.hpp stays the fixed interface; controllers/registry.cpp lists the dialects).
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "controllers/dialect.hpp"

namespace rotacal {

/// Changes (mm) of the Haas MRZP settings 255, 256, 257 (X, Y, Z of the rotary centre): the
/// tilting axis's pivot, A/C: (dx_AY, dy_AY, dz_AY), B/C: (dx_BY, dy_CB, dz_BY). dy_CA / dx_CB
/// (offset between the axes) has no setting. Mapping UNVERIFIED on a machine.
std::vector<std::pair<std::string, double>> haasMrzpChanges(const LocationErrors& identified);

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

/// The FN 16 format files the heidenhain program prints through (file name, text): they must be
/// saved in TNC:\ROTACAL\ on the control; the program lists them in its header comments.
std::vector<std::pair<std::string, std::string>> heidenhainFormatFiles(const std::string& cycle, int points);

/// LinuxCNC kinematics component of a table machine: "xyzac-trt-kins", "xyzbc-trt-kins" or "xyzab_tdr_kins".
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

/// A number as Fanuc DPRNT prints #v[ab] (a integer digits, b decimals), in rotacal's chosen
/// form: the sign (only when negative) directly before the digits, the whole right-aligned in
/// a + (b > 0 ? b + 1 : 0) characters (leading spaces; wider when it does not fit), no decimal
/// point when b == 0. E.g. [44]: 123.456 -> " 123.4560", -200 -> "-200.0000"; [90]: 12345 ->
/// "    12345". UNVERIFIED against a real control (parameter 6001 changes padding and sign).
std::string fanucDprntNumber(double value, int integer_digits, int decimals);

}  // namespace rotacal
