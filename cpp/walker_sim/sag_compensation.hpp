// Seed 003 §4.1's Moses Lake lesson, shown in simulation: a swing planned against the rigid
// kinematic pose clears a rock on paper but hits it on the compliant robot (the chassis sags when
// the leg unloads), while the same planner given the pose the sag model predicts for the stance
// during the step (cpp/statics solve_sag, §5.1.1 eqs 1–12) clears it. Both plans pick the lowest
// compliance-waypoint height (§3.3) whose swing keeps `planned_clearance` to the rock on paper.
// The simulator's measured sag is also compared with the model's prediction (a check of both).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "ernest/statics/sag.hpp"
#include "ernest/walker_sim/swing.hpp"

namespace ernest::walker_sim {

struct SagScenarioOptions {
  int leg = 0;                   ///< the stepping leg
  /// Step of the wheel in the body frame [m]: sideways (along the axle) by default, so that a rock
  /// fits between the 0.7 m wheel's start and goal footprints.
  Eigen::Vector3d step = Eigen::Vector3d(0.0, 0.55, 0.0);
  Eigen::Vector3d rock_half_extents = Eigen::Vector3d(0.25, 0.05, 0.14);  ///< [m], mid-step on the ground
  double planned_clearance = 0.03;   ///< wheel over rock on paper [m], [0, 1]
  double min_lift = 0.1;             ///< lowest compliance waypoint [m], [0, 2]
  double lift_resolution = 0.002;    ///< the lift search's resolution [m], (0, 0.1]
  /// Tangential spring constants of the sag model, k_xx = k_yy = this × k_zz: the simulator's
  /// wheels stick (Coulomb friction), eq 3's k_xx, k_yy -> inf, (0, 1e6].
  double tangential_ratio = 1e3;
  double settle_time = 1.5;          ///< settling on all six wheels before the step [s], [0, 60]
  WalkerSimOptions sim;
  ExecutionOptions execution;
  void validate() const;
};

/// One plan: the body pose it assumes while the leg swings, the path and its paper clearance.
struct SwingPlan {
  Eigen::Isometry3d assumed_body = Eigen::Isometry3d::Identity();
  std::vector<Eigen::VectorXd> path;
  double lift_height = 0.0;       ///< compliance waypoints above start and goal [m]
  double planned_clearance = 0.0; ///< wheel to rock along the path with the body at assumed_body [m]
};

struct SagScenarioResult {
  std::vector<Rock> rocks;
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), goal = Eigen::Vector3d::Zero();  ///< wheel contacts (world)
  SwingPlan rigid, compensated;
  ExecutionTrace rigid_run, compensated_run;
  /// Sag model (statics::solve_sag) vs simulator: chassis corners (the hip mounts) heights [m]
  /// with all six wheels down and with the leg at its first compliance waypoint.
  statics::SagResult predicted_six, predicted_lifted;
  Eigen::VectorXd rigid_corners, predicted_six_corners, measured_six_corners;
  Eigen::VectorXd predicted_lifted_corners, measured_lifted_corners;
  double six_error = 0.0, lifted_error = 0.0;  ///< largest |predicted − measured| corner height [m]
};

/// Runs the scenario on the model's standard stance over flat ground with one rock between the
/// stepping wheel's start and goal. Throws std::invalid_argument for bad options or an
/// unreachable step, WalkerSimDiverged on a blow-up.
SagScenarioResult run_sag_scenario(const walker::WalkerModel& model, const SagScenarioOptions& options = {});

/// The planner of both plans: the lowest lift (from min_lift, by lift_resolution) whose swing
/// path from q_start to `goal` keeps `planned_clearance` to the rocks with the body at `body`.
SwingPlan plan_swing_over_rocks(const walker::WalkerModel& model, const Eigen::Isometry3d& body, int leg,
                                const Eigen::Ref<const Eigen::VectorXd>& q_start, const Eigen::Vector3d& goal,
                                const std::vector<Rock>& rocks, const SagScenarioOptions& options);

}  // namespace ernest::walker_sim
