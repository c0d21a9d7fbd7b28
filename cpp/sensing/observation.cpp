#include "ernest/sensing/observation.hpp"

#include <algorithm>

#include "ernest/common/validation.hpp"

namespace ernest::sensing {

// Scale choices: heading up to +-180 deg (rock-field initial yaw, Table 3); lateral offsets up to
// 2 m (Table 3); roll/pitch: slopes up to 30 deg (Table 3); gimbal angles: their joint ranges;
// forces: after mean removal the wheels differ by at most about a quarter of the 736 N weight
// plus traction (~200 N); torques: that force at the 0.2 m sensor-to-contact lever; elevations: the
// largest obstacles (0.6 m rocks, 0.3 m steps, 0.3 m ripples).
void ObservationScales::validate() const {
  const char* o = "ObservationScales";
  require_positive(o, "heading", heading);
  require_positive(o, "lateral", lateral);
  require_positive(o, "attitude", attitude);
  require_positive(o, "gimbal_yaw", gimbal_yaw);
  require_positive(o, "gimbal_roll", gimbal_roll);
  require_positive(o, "force", force);
  require_positive(o, "torque", torque);
  require_positive(o, "elevation", elevation);
  require_positive(o, "action", action);
}

ObservationVector ObservationScales::divisors() const {
  ObservationVector d = ObservationVector::Zero();
  d.head<6>() << heading, lateral, attitude, attitude, gimbal_yaw, gimbal_roll;
  for (int s = 0; s < 4; ++s) {
    for (int a = 0; a < 6; ++a) d[kFtsBegin + 6 * s + a] = a < 3 ? force : torque;
  }
  d.segment<kElevationSamples>(kElevationBegin).setConstant(elevation);
  d.segment<kActionSize>(kActionBegin).setConstant(action);
  return d;
}

ObservationVector build_observation(const ObservationInputs& in, const ObservationScales& scales) {
  scales.validate();  // a zero or non-finite divisor would make the observation inf or NaN
  ObservationVector raw;
  raw.head<6>() << in.heading_deviation, in.lateral_deviation, in.roll, in.pitch, in.gimbal_yaw,
      in.gimbal_roll;
  raw.segment<24>(kFtsBegin) = Eigen::Map<const Eigen::Matrix<double, 24, 1>>(in.fts.data());
  raw.segment<kElevationSamples>(kElevationBegin) = in.elevation;
  raw.segment<kActionSize>(kActionBegin) = in.action;
  if (!raw.allFinite()) {
    const std::vector<std::string> names = observation_names();
    for (int i = 0; i < kObservationSize; ++i) {
      require(std::isfinite(raw[i]), "build_observation: input '" + names[i] + "' is not finite");
    }
  }
  return raw.cwiseQuotient(scales.divisors()).cwiseMax(-kObservationClip).cwiseMin(kObservationClip);
}

std::vector<std::string> observation_names() {
  std::vector<std::string> n = {"heading_deviation", "lateral_deviation", "roll", "pitch",
                                "gimbal_yaw", "gimbal_roll"};
  const char* wheels[4] = {"FL", "FR", "RL", "RR"};
  const char* axes[6] = {"Fx", "Fy", "Fz", "Tx", "Ty", "Tz"};
  for (const char* w : wheels)
    for (const char* a : axes) n.push_back(std::string("fts_") + w + "_" + a);
  for (const char* w : wheels)
    for (int j = 0; j < 3; ++j) n.push_back(std::string("elev_") + w + "_" + std::to_string(j));
  for (const char* a : {"action_vx", "action_yaw_rate", "action_roll_rate"}) n.push_back(a);
  return n;
}

void ActionLimits::validate() const {
  require_positive("ActionLimits", "vx_max", vx_max);
  require_positive("ActionLimits", "yaw_rate_max", yaw_rate_max);
  require_positive("ActionLimits", "roll_rate_max", roll_rate_max);
}

Eigen::Vector3d action_to_command(const ActionVector& action, const ActionLimits& limits) {
  require(action.allFinite(), "action_to_command: action must be finite");
  limits.validate();
  const ActionVector a = action.cwiseMax(-1.0).cwiseMin(1.0);
  return {0.5 * (a[0] + 1.0) * limits.vx_max, a[1] * limits.yaw_rate_max,
          a[2] * limits.roll_rate_max};
}

ActionVector command_to_action(const Eigen::Vector3d& command, const ActionLimits& limits) {
  require(command.allFinite(), "command_to_action: command must be finite");
  limits.validate();  // a zero limit would divide by zero
  const ActionVector a(2.0 * command[0] / limits.vx_max - 1.0, command[1] / limits.yaw_rate_max,
                       command[2] / limits.roll_rate_max);
  return a.cwiseMax(-1.0).cwiseMin(1.0);
}

}  // namespace ernest::sensing
