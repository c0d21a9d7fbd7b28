// The onboard loop's view of the rover: one sensor frame per tick (400 Hz, the force–torque
// sensor rate of seed 004 §4.2) and actuator set-points. The simulator implementation is
// SimRoverInterface (sim_interface.hpp); a hardware implementation (EtherCAT drives and FTS,
// visual–inertial odometry, stereo elevation map, §2.1.3 and §5) implements the same class.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "ernest/perception/raycaster.hpp"
#include "ernest/sensing/elevation_sampler.hpp"
#include "ernest/sensing/fts_processor.hpp"
#include "ernest/sensing/path_reward.hpp"

namespace ernest::runtime {

/// Everything the loop reads in one tick. Each group carries the time it was measured, so the
/// watchdog can tell fresh data from a frozen bus or a stalled estimator.
struct SensorFrame {
  double fts_stamp = 0.0;   ///< time of the force–torque samples [s]
  double pose_stamp = 0.0;  ///< time of the pose/attitude estimate [s]
  double joint_stamp = 0.0; ///< time of the joint encoders [s]
  sensing::Wrenches fts = sensing::Wrenches::Zero();  ///< raw wrenches, rows FL, FR, RL, RR
  Eigen::Vector3d position = Eigen::Vector3d::Zero(); ///< chassis origin, world [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< chassis to world
  double roll = 0.0, pitch = 0.0, yaw = 0.0;          ///< chassis attitude (Z-Y-X) [rad]
  Eigen::Vector3d body_angular_velocity = Eigen::Vector3d::Zero();  ///< IMU, chassis frame [rad/s]
  double gimbal_yaw = 0.0, gimbal_roll = 0.0;         ///< AGS joints [rad]
  std::array<double, 4> wheel_speed{};                ///< measured [rad/s]
  std::array<double, 4> wheel_load{};                 ///< normal load estimate [N] (telemetry)
  double power = 0.0;                                 ///< electrical power of the six actuators [W]
  double energy = 0.0;                                ///< integral of positive power [J]
  double roll_torque = 0.0;                           ///< roll actuator torque [N m] (telemetry)
};

/// Actuator set-points (velocity mode on all six drives, as in §2.3 and §4.2).
struct ActuatorCommand {
  std::array<double, 4> wheel_speed{};  ///< [rad/s], positive rolls forward
  double yaw_rate = 0.0, roll_rate = 0.0;  ///< gimbal psi_dot, phi_dot [rad/s]
  bool gimbal_enabled = true;   ///< false = brakes hold (passive bogie)
  bool clutch_engage = true;    ///< roll clutch request (§2.2)
};

/// One rectified stereo pair of the masthead cameras (§2.1.2) and the left camera's pose
/// (camera -> world, from the odometry) when it was taken.
struct StereoPair {
  double stamp = 0.0;  ///< [s]
  perception::GrayImage left, right;
  Eigen::Isometry3d left_pose = Eigen::Isometry3d::Identity();
};

class RoverInterface {
 public:
  virtual ~RoverInterface() = default;
  /// Loop clock [s] (same time base as the stamps).
  virtual double now() const = 0;
  /// The latest sensor frame.
  virtual const SensorFrame& read() = 0;
  /// Send set-points (held by the drives until the next call).
  virtual void command(const ActuatorCommand& command) = 0;
  /// Block until the next sensor tick (hardware: the bus cycle; simulator: advance the physics).
  virtual void wait_next_tick() = 0;
  /// The terrain heights the elevation samples read when the loop builds no map itself.
  virtual const sensing::HeightSource& heights() const = 0;
  /// A new stereo pair since the last call, or false (the default: no cameras). With
  /// LoopOptions::stereo_map the loop matches and fuses the pairs into its own elevation map
  /// (§2.4) and samples that instead of heights().
  virtual bool stereo(StereoPair& /*out*/) { return false; }
};

}  // namespace ernest::runtime
