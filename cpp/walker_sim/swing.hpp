// One leg's swing: a joint-space path (any planner's: here the straight one through FootFall's
// compliance waypoints, seed 003 §3.3; OMPL SBL paths plug into the same std::vector<VectorXd>),
// its clearance on paper against an assumed body pose, and its execution in WalkerSim with the
// clearance the wheel actually keeps to rocks and ground.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "ernest/walker_sim/walker_sim.hpp"

namespace ernest::walker_sim {

/// Joint path of `leg` from q_start: the waypoint `lift_height` straight up (world z) from the
/// start contact, the one above the world contact `goal`, and the goal; solved by IK with the body
/// at `body` (the pose the planner assumes). Throws std::invalid_argument when a waypoint is
/// unreachable.
std::vector<Eigen::VectorXd> swing_path(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                                        int leg, const Eigen::Ref<const Eigen::VectorXd>& q_start,
                                        const Eigen::Vector3d& goal, double lift_height);

/// Smallest wheel clearance to the rocks along the path (straight segments in joint space,
/// `samples` per segment) with the body held at `body`: the clearance the plan has on paper [m].
double planned_clearance(const walker::WalkerModel& model, const Eigen::Isometry3d& body, int leg,
                         const std::vector<Eigen::VectorXd>& path, const std::vector<Rock>& rocks,
                         int samples = 40);

struct ExecutionOptions {
  double joint_speed = 0.5;   ///< fastest joint along each segment [rad/s], (0, 10]
  double pause = 0.6;         ///< hold at every waypoint (the robot settles) [s], [0, 60]
  /// Record the whole robot (body pose, joint angles) every this many seconds for animations,
  /// (0, 60]; unset: never.
  std::optional<double> frame_interval;
  void validate() const;
};

struct ExecutionTrace {
  Eigen::VectorXd time;              ///< [s] from the start of the path
  Eigen::VectorXd rock_clearance;    ///< swing wheel to the nearest rock [m]
  Eigen::VectorXd ground_clearance;  ///< swing wheel's lowest point over z = 0 [m]
  Eigen::VectorXd body_height;       ///< chassis origin z [m]
  /// Segment index: i while moving from waypoint i to i + 1 and while pausing at waypoint i + 1
  /// (-1 in the first pause).
  Eigen::VectorXi phase;
  double min_rock_clearance = 0.0;   ///< over the whole motion [m] (< 0: the wheel hit a rock)
  /// Every wheel (the stance wheels too) to the nearest rock over the whole motion [m].
  double min_any_rock_clearance = 0.0;
  Eigen::Matrix3Xd wheel_path;       ///< the traced wheel's centre at every step (world) [m]
  /// Over the transfer (after the first lift waypoint is reached, before the last one is left),
  /// when the wheel should be in the air [m].
  double min_ground_clearance = 0.0;
  std::vector<Eigen::Isometry3d> waypoint_body;  ///< body pose at the end of each waypoint's pause
  Eigen::MatrixXd final_q;           ///< measured joints at the end
  /// Frames every options.frame_interval: time [s] from the start, body pose, joints × legs.
  Eigen::VectorXd frame_time;
  std::vector<Eigen::Isometry3d> frame_body;
  std::vector<Eigen::MatrixXd> frame_q;
  double simulated_seconds = 0.0, wall_seconds = 0.0;
};

/// Executes `path` (waypoints of `leg`, the first its current target) in the simulator with the
/// other legs held at `stance` (joints × legs; its column `leg` is ignored): a pause at each
/// waypoint, then a straight joint-space move to the next at options.joint_speed with the path's
/// rate fed forward. Throws std::invalid_argument for bad input, WalkerSimDiverged on a blow-up.
ExecutionTrace execute_joint_path(WalkerSim& sim, int leg, const Eigen::Ref<const Eigen::MatrixXd>& stance,
                                  const std::vector<Eigen::VectorXd>& path, const ExecutionOptions& options = {});

/// The same for whole-robot configurations (joints × legs each): every leg moves at once (a body
/// shift with all feet down); `leg` is the wheel whose clearances are traced (unset: none).
ExecutionTrace execute_configuration_path(WalkerSim& sim, std::optional<int> leg,
                                          const std::vector<Eigen::MatrixXd>& path,
                                          const ExecutionOptions& options = {});

}  // namespace ernest::walker_sim
