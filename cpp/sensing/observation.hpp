// The policy's observation (seed 004 §4.2, 45 values) and action (3 values) with their scaling:
// one table of maximum expected values, one layout, used by the environments and the onboard
// runtime alike.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ernest/sensing/elevation_sampler.hpp"
#include "ernest/sensing/fts_processor.hpp"

namespace ernest::sensing {

/// Bumped whenever the order, size or scaling convention of the observation changes; exported
/// policies record it and the runtime refuses a mismatch. 2: ObservationScales is the only scale
/// table (bound to Python; version 1 files may carry a second one). The order, size and
/// this table are those of version 1; a version 1 file is read when its obs_scale is this table.
inline constexpr int kObservationLayoutVersion = 2;
inline constexpr int kObservationSize = 45;  // 1 + 1 + 2 + 2 + 24 + 12 + 3 (§4.2)
inline constexpr int kActionSize = 3;

/// Index of each block in the observation vector (§4.2 order).
enum ObservationIndex : int {
  kHeadingDeviation = 0,
  kLateralDeviation = 1,
  kRoll = 2,
  kPitch = 3,
  kGimbalYaw = 4,
  kGimbalRoll = 5,
  kFtsBegin = 6,         ///< 24 values: sensor-major (FL, FR, RL, RR) x (Fx, Fy, Fz, Tx, Ty, Tz)
  kElevationBegin = 30,  ///< 12 values, sample order of ElevationSampler
  kActionBegin = 42,     ///< 3 values: the current (normalised) action
};

using ObservationVector = Eigen::Matrix<double, kObservationSize, 1>;
using ActionVector = Eigen::Vector3d;

/// Physical inputs of one observation, in SI units.
struct ObservationInputs {
  double heading_deviation = 0.0;  ///< chassis yaw minus path heading, wrapped to (-pi, pi] [rad]
  double lateral_deviation = 0.0;  ///< signed distance to the path, eq 37 [m]
  double roll = 0.0, pitch = 0.0;  ///< chassis attitude w.r.t. gravity [rad]
  double gimbal_yaw = 0.0, gimbal_roll = 0.0;  ///< AGS joint positions [rad]
  Wrenches fts = Wrenches::Zero();              ///< processed force–torque values [N, N m]
  ElevationVector elevation = ElevationVector::Zero();  ///< [m]
  ActionVector action = ActionVector::Zero();   ///< current action, already in [-1, 1]
};

/// Maximum expected value of each input: the observation is input / scale. These are ours (the
/// paper says only "normalised by maximum expected values"); see observation.cpp for reasons.
struct ObservationScales {
  double heading = 3.14159265358979;  ///< [rad]
  double lateral = 2.0;               ///< [m], Table 3 lateral offsets up to 2 m
  double attitude = 0.5235987756;     ///< [rad] (30 deg)
  double gimbal_yaw = 0.7853981634;   ///< [rad] (45 deg, joint range)
  double gimbal_roll = 0.5235987756;  ///< [rad] (30 deg, joint range)
  double force = 200.0;               ///< [N], mean-removed wheel forces of a 75 kg rover
  double torque = 40.0;               ///< [N m]
  double elevation = 0.5;             ///< [m]
  double action = 1.0;                ///< actions are already normalised
  void validate() const;
  /// The 45 divisors in observation order.
  ObservationVector divisors() const;
};

/// Observations are clipped to +-kObservationClip (ten times the maximum expected value) so that
/// the policy's input space is bounded; nothing physical reaches that.
inline constexpr double kObservationClip = 10.0;

/// obs = clip(inputs / scales) in the §4.2 order. Throws std::invalid_argument on non-finite input.
ObservationVector build_observation(const ObservationInputs& inputs,
                                    const ObservationScales& scales = {});

/// Names of the 45 entries ("heading_deviation", ..., "fts_FL_Fx", ..., "elev_RR_2", "action_vx").
std::vector<std::string> observation_names();

/// Action limits of §4.2: Vx in [0, 0.2] m/s, yaw rate +-20 deg/s, roll rate +-10 deg/s.
struct ActionLimits {
  double vx_max = 0.2;                 ///< [m/s]
  double yaw_rate_max = 0.3490658504;  ///< [rad/s] (20 deg/s)
  double roll_rate_max = 0.1745329252; ///< [rad/s] (10 deg/s)
  void validate() const;
};

/// Physical command from a normalised action in [-1, 1]^3 (clamped): Vx = (a0 + 1) / 2 vx_max,
/// yaw rate = a1 yaw_rate_max, roll rate = a2 roll_rate_max. Non-finite actions throw.
Eigen::Vector3d action_to_command(const ActionVector& action, const ActionLimits& limits = {});
/// Inverse of action_to_command (for scripted controllers that think in physical units).
ActionVector command_to_action(const Eigen::Vector3d& command, const ActionLimits& limits = {});

}  // namespace ernest::sensing
