// Executing FootFall's skeleton gait (cpp/walker/gait_planner, seed 003 §5.3.1) in WalkerSim: each
// step as the leg's straight joint path through the compliance waypoints (§3.3), each body shift
// as every leg moving at once with the feet down; open loop, as FootFall executed its plans.
#pragma once

#include "ernest/walker/gait_planner.hpp"
#include "ernest/walker_sim/swing.hpp"

namespace ernest::walker_sim {

struct GaitExecution {
  int steps = 0, shifts = 0;
  double min_ground_clearance = 0.0;  ///< swing wheels over the ground during their transfers [m]
  Eigen::Vector3d body_start = Eigen::Vector3d::Zero(), body_end = Eigen::Vector3d::Zero();  ///< world [m]
  double planned_advance = 0.0;       ///< the plan's body travel over the executed events [m]
  double simulated_seconds = 0.0, wall_seconds = 0.0;
};

/// Executes the events of gait cycle `cycle` of `plan` (the simulator must stand in the plan's
/// configuration at the start of that cycle). Throws std::invalid_argument for a bad cycle,
/// WalkerSimDiverged on a blow-up.
GaitExecution execute_gait_cycle(WalkerSim& sim, const walker::GaitPlan& plan, int cycle,
                                 const ExecutionOptions& options = {});

}  // namespace ernest::walker_sim
