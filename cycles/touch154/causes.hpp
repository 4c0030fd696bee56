#pragma once
// The catalog of physical causes touch154 (and touch_designed plans) can add to its model
// (issues 6 and 16). Each is a ModelExtension of the identification engine; `catalogFor` lists
// the ones that apply to a plan and its data. Which of them this plan can tell apart is never
// written here: the judge (core/judge.hpp) computes it from their Jacobian columns.
//  thermal_drift/linear      the table moves against the spindle at a constant rate:
//                            dx_AY, dy_AY, dz_AY change linearly with time (um/h)
//  thermal_drift/per_repeat  the same translation, free per repeat (heating / cooling phases)
//  probe_pretravel           trigger travel that depends on the approach direction (um),
//                            relative to the -Z approach (a uniform pretravel is absorbed by the
//                            per-point offsets and is harmless)
//  linear_axis_squareness    S_xy, S_xz, S_yz of 000 Eq. (23) (um/m)
//  linear_axis_scale         E_xx,lin E_yy,lin E_zz,lin of 000 Eq. (22): positioning error
//                            proportional to the read position (um/m)
//  probe_length              the ball centre sits dL below where the controller thinks (um)
//  rotary_error_motion       the C axis's centre moves with C: second-order radial error motion
//  tilt_axis_positioning     the tilt axis (A, or B on a B/C table) stands off its command by an
//                            angle that differs per tilt (EAA of ISO 230-7), relative to the first
//                            tilt; on plans that visit two tilts or more
//  tilt_axis_backlash        the tilt axis stops short by half its lost motion in the direction
//                            it last moved (from the plan's order); on a plan that reaches each
//                            tilt from one side, the judge finds it the same signal as the above
//  pivot_length              fixed-tool-tip cycle (004) only, not a touch-cycle extension: the tool tip
//                            is R + dR from the pivot; that cycle diagnoses it
#include <string>
#include <vector>

#include "cycles/touch154/model_extension.hpp"

namespace rotacal {

ExtensionPtr thermalDriftLinear();
ExtensionPtr thermalDriftPerRepeat(int runs);
ExtensionPtr probePretravel();
ExtensionPtr linearAxisSquareness();
ExtensionPtr linearAxisScale();
ExtensionPtr probeLength();
/// rotary_error_motion: second-order radial error motion of the C axis, EXC = r_x cos 2C,
/// EYC = r_y cos 2C (um). Its first order is a location error, and with C at 0/90/180/270 deg
/// only the cos 2C terms are visible.
ExtensionPtr rotaryErrorMotionC2();
/// tilt_axis_positioning: one angle per tilt of the plan after its first (mdeg).
ExtensionPtr tiltAxisPositioning(const ProbePlan& plan);
/// tilt_axis_backlash: the tilt axis's lost motion (mdeg), the direction read from the plan's order.
ExtensionPtr tiltAxisBacklash(const ProbePlan& plan);

/// The candidate extensions for a plan with `runs` repeats.
std::vector<ExtensionPtr> catalogFor(const ProbePlan& plan, int runs);

/// How two causes could be told apart when a plan cannot (a sentence for DIAGNOSIS.json).
std::string separationHint(const std::string& cause, const std::vector<std::string>& confounded_with);

}  // namespace rotacal
