// Safety layer of the onboard loop: velocity and joint limits on the policy's command (the §4.2
// bounds are "conservatively set for testing safety"), and the watchdog that stops the rover on
// stale or non-finite sensor data or a failed inference while the loop keeps running.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/runtime/rover_interface.hpp"
#include "ernest/sensing/observation.hpp"

namespace ernest::runtime {

struct LimitOptions {
  sensing::ActionLimits velocity{};  ///< Vx in [0, vx_max], |yaw rate|, |roll rate| (§4.2)
  /// A gimbal rate that drives a joint further is zeroed once the joint is within this margin
  /// of its stop (RoverParameters::yaw_limit / roll_limit) [rad], [0, 0.5]; unset: no joint
  /// limiting.
  std::optional<double> joint_margin = 0.035;  // 2 deg
  /// Largest wheel speed sent to the drives [rad/s]: the synchroniser may ask more than Vx / r
  /// while the bogie swings; 3x the top speed of a 0.17 m wheel at 0.2 m/s.
  double max_wheel_speed = 3.5;
  void validate() const;
};

/// Clamp (Vx, yaw rate, roll rate) to the velocity limits, then zero the gimbal rates that push
/// a joint into its stop. Non-finite input gives zero.
Eigen::Vector3d limit_command(const Eigen::Vector3d& command, double gimbal_yaw, double gimbal_roll,
                              const dynamics::RoverParameters& params, const LimitOptions& options);

enum class Fault : int {
  None = 0,
  StaleFts = 1,       ///< force–torque samples older than the limit
  StalePose = 2,      ///< pose/attitude estimate older than the limit
  StaleJoints = 3,    ///< gimbal encoders older than the limit
  NonFinite = 4,      ///< a NaN or infinite value in the frame
  Inference = 5,      ///< the policy failed or returned a non-finite command
  Observation = 6,    ///< the observation could not be built
};
const char* to_string(Fault fault);

struct WatchdogOptions {
  double max_age = 0.05;         ///< [s], 20 sensor periods at 400 Hz
  /// Healthy data needed after a fault before the policy may drive again [s].
  double recovery_time = 0.5;
  void validate() const;
};

/// Checks one frame; the first problem found, with a message naming it.
Fault check_frame(const SensorFrame& frame, double now, const WatchdogOptions& options, std::string& why);

/// Latching watchdog: trip() stops the rover; it re-arms after recovery_time of uninterrupted
/// healthy ticks (counted from the first one).
class Watchdog {
 public:
  explicit Watchdog(const WatchdogOptions& options = {});
  /// Report a fault at time `now` [s]; returns true if it newly tripped (for logging).
  bool trip(Fault fault, double now, const std::string& why);
  /// Report a healthy tick; returns true when the watchdog re-arms.
  bool healthy(double now);
  bool tripped() const { return fault_ != Fault::None; }
  Fault fault() const { return fault_; }
  const std::string& reason() const { return reason_; }
  int trips() const { return trips_; }

 private:
  WatchdogOptions options_;
  Fault fault_ = Fault::None;
  std::string reason_;
  double healthy_since_ = -1.0;  // first healthy tick since the last fault
  int trips_ = 0;
};

}  // namespace ernest::runtime
