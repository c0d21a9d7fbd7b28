// Load measurements for the mass-model fit (seed 004 §3.2, Fig. 6) taken from the simulator: the
// rover is set down in many static poses (gimbal yaw, blocks under single wheels that roll the
// bogie and the chassis, flat and sloped rigid ground), settles with the AGS off and the clutch
// open, and each wheel's vertical ground force is read from its force–torque sensor.
#pragma once

#include <vector>

#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/statics/mass_model.hpp"

namespace ernest::statics {

struct SurveyOptions {
  std::vector<double> yaws_deg{-40.0, -20.0, 0.0, 20.0, 40.0};  ///< gimbal yaw of each pose
  /// Slopes [deg] of the rigid ground; 0 is flat. The ground rises along world +x.
  std::vector<double> slopes_deg{0.0, 12.0, 20.0};
  /// Headings of the rover relative to uphill [deg], used on the slopes (flat: heading 0 only).
  std::vector<double> headings_deg{0.0, 90.0, 180.0, 270.0};
  /// Height [m] of a block set under one wheel at a time (Fig. 6), on flat ground; 0: no blocks.
  double block_height = 0.08;
  double settle_time = 4.0;  ///< [s] simulated before reading the sensors
  double average_time = 0.5; ///< [s] the sensor readings are averaged over the last this long
  double friction = 0.8;     ///< Coulomb friction of the rigid ground (holds 20 deg with margin)
  void validate() const;
};

/// Poses and measured ground forces: the FTS force in the world plus the wheel assembly's weight
/// (which the sensor's bias calibration removes on the rover, §4.2), its vertical part as `loads`
/// and its horizontal part as `horizontal_forces` (zero them for eq 11 as printed). roll_torque is
/// the simulator's roll-joint torque on the bogie (zero with the clutch open).
/// The pose and ground forces of one simulator state: chassis attitude, gimbal angles, roll
/// torque, each wheel's ground force from its FTS plus the assembly's weight (static assembly);
/// ground_normal is set to `ground_normal`.
LoadPose pose_from_state(const dynamics::RoverParameters& params,
                         const dynamics::RoverState& state, double gravity,
                         const Eigen::Vector3d& ground_normal = Eigen::Vector3d::UnitZ());

std::vector<LoadPose> survey_loads(const dynamics::RoverParameters& params,
                                   const SurveyOptions& options = {});

}  // namespace ernest::statics
