// A full FootFall gait cycle around rocks, planned and executed (seed 003 §6, Fig. 19: D-RATS
// 2010; executing it in simulation is beyond the paper). For each leg in the reverse-wave order
// (§5.3.1) with the body still: the leg's stability map (§3.3), the foothold (the gait's nominal
// one — the leg's starting foot plus the stride — moved to the nearest stable, reachable,
// rock-free cell), the swing planned by plan_step (sag predicted with the leg in the air, §4.1 and
// §5.1; SBL between the compliance waypoints, §3.4.1; Dijkstra–bisection smoothing, §3.4.2), its
// execution in WalkerSim under joint position control, then a body shift of stride / legs with
// every foot down. Open loop, as FootFall executed its plans: each plan is made on the planned
// stance, the simulator only executes. The planner's terrain is a parameter (any HeightMap: the
// rocks rasterised by rock_height_map, or a perceived map), the simulator collides with the boxes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "ernest/footfall/step_planner.hpp"
#include "ernest/walker_sim/swing.hpp"

namespace ernest::walker_sim {

struct FootfallCycleOptions {
  double stride = 0.4;            ///< nominal step of every foot = the body's advance over the cycle [m], (0, 2]
  double heading = 0.0;           ///< direction of travel [rad]
  /// A foothold is rock-free when the terrain within this radius of it is flat (below
  /// flat_tolerance): SDM-B's wheel radius, the reach of the upright rim's footprint [m], [0, 2].
  double foothold_radius = 0.35;
  double flat_tolerance = 1e-3;   ///< [m], [0, 1]
  int max_candidates = 12;        ///< stable rock-free cells tried nearest-first per step, [1, 10000]
  /// Candidates at least this far apart [m], [0, 2]: neighbouring cells fail for the same reason.
  double candidate_spacing = 0.06;
  double settle_time = 1.0;       ///< settling on six wheels before the cycle [s], [0, 60]
  /// Torque-aware foothold choice (seed 003 §7.1): candidates ordered by their distance to the
  /// nominal foothold plus this × the cell's peak joint torque (fraction of its limit) [m], [0, 100];
  /// 0 orders by distance alone. Needs the map's torques (step.map.torques or max_saturation).
  double torque_preference = 0.0;
  /// false: plan the cycle without executing it (no simulator; executed fields are NaN, the
  /// cycle's min_rock_clearance infinite).
  bool execute = true;
  /// Steps to take, the first ones of the cycle, [1, legs]; unset: one per leg (the whole cycle).
  std::optional<int> steps;
  footfall::StepOptions step;     ///< stability map, SBL, smoothing, sag model, sag_compensation
  WalkerSimOptions sim;
  ExecutionOptions execution;
  void validate(int joints) const;
};

struct FootfallStepRecord {
  int leg = -1;
  footfall::StabilityMap map;                   ///< the leg's map in the stance before the step
  double map_seconds = 0.0;
  Eigen::Vector2d nominal_goal = Eigen::Vector2d::Zero();  ///< the gait's foothold (world xy)
  int candidates_tried = 0;
  footfall::StepPlan plan;                      ///< the solved plan (or the last failure)
  /// The wheel centre along the executed joint path (plan.path) with the body at the pose the
  /// plan assumed (planned), and as measured in the simulator (executed) [m].
  Eigen::Matrix3Xd planned_wheel, executed_wheel;
  double planned_clearance = 0.0;       ///< swing wheel to the boxes along the plan, assumed pose [m]
  double swing_rock_clearance = 0.0;    ///< swing wheel to the nearest rock, executed [m]
  double min_rock_clearance = 0.0;      ///< every wheel, during the step and the shift after it [m]
  double transfer_ground_clearance = 0.0;  ///< swing wheel over z = 0 between the waypoints [m]
  Eigen::Vector3d body_before = Eigen::Vector3d::Zero(), body_after = Eigen::Vector3d::Zero();  ///< planned
};

struct FootfallCycleResult {
  bool completed = false;
  std::string reason;                    ///< why the cycle stopped early ("" when completed)
  std::vector<FootfallStepRecord> steps;
  Eigen::Vector3d body_start = Eigen::Vector3d::Zero(), body_end = Eigen::Vector3d::Zero();  ///< measured
  double planned_advance = 0.0;          ///< of the body along the heading [m]
  double min_rock_clearance = 0.0;       ///< every wheel to every rock over the executed cycle [m]
  /// Frames every execution.frame_interval: time [s], body pose, joints × legs.
  Eigen::VectorXd frame_time;
  std::vector<Eigen::Isometry3d> frame_body;
  std::vector<Eigen::MatrixXd> frame_q;
  double planning_seconds = 0.0, simulated_seconds = 0.0, simulation_wall_seconds = 0.0;
};

/// Plans and executes one gait cycle from the model's standard stance: the planner on `terrain`,
/// the simulator with `rocks` over z = 0. Throws std::invalid_argument for bad options or input,
/// WalkerSimDiverged on a blow-up; a step without a plan ends the cycle with completed = false.
FootfallCycleResult run_footfall_cycle(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                                       const std::vector<Rock>& rocks, const FootfallCycleOptions& options = {});

}  // namespace ernest::walker_sim
