#pragma once
// Lost motion (backlash) of the rotary axes: an axis stops short of its command by half its lost
// motion b, in the direction it last moved: actual = commanded - d b / 2, d = +1 or -1. Which
// way each axis last moved at each plan point is read from the plan's order of points, each
// probing pose reached straight from the one before (the programs' path: index, then probe).
// The simulator (core/simulation.hpp), the touch cycles' backlash cause and the one-sphere
// cycle's backlash fit all take it from here.
#include <Eigen/Core>
#include <vector>

#include "core/probe_plan.hpp"

namespace rotacal {

/// Per plan point, the direction (+1 / -1) each rotary axis A, B, C last moved before it.
/// `from_start`: the program starts at A = B = C = 0 reached in + (the simulator's rule), so
/// every axis has a direction from the first point on. Otherwise an axis the plan has not yet
/// moved has direction 0: it arrived from wherever the machine stood before the program, which
/// the plan does not know.
std::vector<Eigen::Vector3d> rotaryApproachDirections(const ProbePlan& plan, bool from_start);

}  // namespace rotacal
