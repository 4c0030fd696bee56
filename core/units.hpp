#pragma once
// Units used inside rotacal: lengths in mm, angles in rad. Reports convert to um and mdeg at the
// boundary; programs and plans carry angles in degrees.

namespace rotacal {

constexpr double kPi = 3.14159265358979323846;
constexpr double kUmPerMm = 1000.0;
constexpr double kRadPerDeg = kPi / 180.0;
constexpr double kDegPerRad = 180.0 / kPi;
constexpr double kMdegPerRad = 1000.0 * kDegPerRad;
constexpr double kMmPerInch = 25.4;

constexpr double degToRad(double deg) { return deg * kRadPerDeg; }
constexpr double radToDeg(double rad) { return rad * kDegPerRad; }
constexpr double mdegToRad(double mdeg) { return mdeg / kMdegPerRad; }
constexpr double radToMdeg(double rad) { return rad * kMdegPerRad; }
constexpr double umToMm(double um) { return um / kUmPerMm; }
constexpr double mmToUm(double mm) { return mm * kUmPerMm; }

}  // namespace rotacal
