// The onboard control loop (seed 004 §4.2, §5): at the force–torque sensor rate (400 Hz) it reads
// a SensorFrame, checks it (watchdog), feeds the FTS samples to the same filter chain the
// environments use (sensing::FtsProcessor); at the policy rate (2 Hz) it builds the 45-value
// observation with the environments' code (sensing::ElevationSampler, sensing::build_observation)
// and runs the TorchScript policy; at the synchroniser rate it turns (Vx, yaw rate, roll rate)
// into wheel speeds with the §2.3 Jacobian synchroniser (eqs 1–10); velocity and joint limits
// are enforced before anything reaches the drives. A fault (stale or non-finite data, failed
// inference) commands zero velocities, logs why, and the loop keeps running; the policy resumes
// after WatchdogOptions::recovery_time of healthy data.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/perception/stereo_mapper.hpp"
#include "ernest/runtime/policy.hpp"
#include "ernest/runtime/rover_interface.hpp"
#include "ernest/runtime/safety.hpp"
#include "ernest/runtime/telemetry.hpp"
#include "ernest/sensing/elevation_sampler.hpp"
#include "ernest/sensing/fts_processor.hpp"
#include "ernest/sensing/observation.hpp"
#include "ernest/sensing/path_reward.hpp"

namespace ernest::envs {
class RoverEnv;
}

namespace ernest::runtime {

struct LoopOptions {
  double sensor_rate = 400.0;  ///< [Hz], FTS rate (§4.2); one tick per sample
  double policy_rate = 2.0;    ///< [Hz] (Table 5)
  double sync_rate = 50.0;     ///< wheel synchroniser [Hz]
  /// Tick within each policy/synchroniser period at which they run (0 = the first). With the
  /// simulator, ticks_per_step - 1 runs them on the last sample before a physics step, which is
  /// the order of envs::RoverEnv (see the equivalence test).
  int phase = 0;
  double cutoff = 0.5;         ///< FTS low-pass cutoff [Hz] (§4.2)
  sensing::ObservationScales scales{};
  sensing::ElevationSamplingOptions elevation{};
  LimitOptions limits{};
  WatchdogOptions watchdog{};
  bool passive = false;        ///< gimbal off, clutch open (§5, Table 6)
  int telemetry_every = 8;     ///< ticks per telemetry row (50 Hz at 400 Hz)
  /// Build the elevation map onboard (§2.4): at each policy tick the map is re-centred on the
  /// rover, a new RoverInterface::stereo() pair is matched (StereoBM) and fused, and the samples
  /// read the map. Off: the samples read RoverInterface::heights().
  bool stereo_map = false;
  perception::StereoMapperOptions stereo{};  ///< camera, matcher, map (render is unused)
  void validate() const;
  /// The settings an envs::RoverEnv episode uses (rates, scales, sampler, limits, passive), with
  /// `phase` aligned to its physics steps. Joint limiting is left on (the env has none).
  static LoopOptions from_env(const envs::RoverEnv& env);
};

class ControlLoop {
 public:
  using Logger = std::function<void(double time, const std::string& message)>;

  /// Keeps references to io, policy and (optionally) telemetry. The default logger prints to stderr.
  ControlLoop(RoverInterface& io, Policy& policy, const dynamics::RoverParameters& params,
              const sensing::PathLine& path, const LoopOptions& options = {});

  /// §4.2 calibration biases of the four sensors (filtered readings, wheels hanging).
  void set_fts_bias(const sensing::Wrenches& bias);
  void set_telemetry(Telemetry* telemetry) { telemetry_ = telemetry; }
  void set_logger(Logger logger) { logger_ = std::move(logger); }
  /// New desired path (a new line segment of the route, §5).
  void set_path(const sensing::PathLine& path) { path_ = path; }

  /// One sensor period: read, check, filter, (policy), (synchroniser), limits, command,
  /// telemetry, then wait for the next tick.
  void tick();
  /// Ticks until `duration` seconds of loop time have passed.
  void run(double duration);

  long ticks() const { return ticks_; }
  /// The onboard elevation map (stereo_map), else nullptr.
  const perception::ElevationMap* map() const { return map_.get(); }
  long stereo_frames() const { return stereo_frames_; }
  long policy_steps() const { return policy_steps_; }
  /// The action in force (normalised, what the next observation reports) and the command sent.
  const sensing::ActionVector& action() const { return action_; }
  const Eigen::Vector3d& command() const { return command_; }
  const ActuatorCommand& actuator_command() const { return out_; }
  const sensing::ObservationVector& last_observation() const { return observation_; }
  const Watchdog& watchdog() const { return watchdog_; }
  const sensing::FtsProcessor& fts() const { return fts_; }
  /// Integral of the commanded Vx [m] (no-slip travel, for travel reduction).
  double expected_progress() const { return expected_progress_; }
  const LoopOptions& options() const { return options_; }
  /// Wall-clock time spent inside tick() except wait_next_tick() [s] (CPU share of the loop).
  double busy_seconds() const { return busy_; }

 private:
  void fault(Fault f, double now, const std::string& why);
  sensing::ObservationVector observe(const SensorFrame& f) const;

  RoverInterface& io_;
  Policy& policy_;
  dynamics::RoverParameters params_;
  sensing::PathLine path_;
  LoopOptions options_;
  sensing::FtsProcessor fts_;
  sensing::ElevationSampler sampler_;
  Watchdog watchdog_;
  Telemetry* telemetry_ = nullptr;
  Logger logger_;
  long ticks_ = 0, policy_steps_ = 0;
  int policy_every_ = 200, sync_every_ = 8;
  sensing::ActionVector action_;
  Eigen::Vector3d command_ = Eigen::Vector3d::Zero();
  ActuatorCommand out_{};
  sensing::ObservationVector observation_ = sensing::ObservationVector::Zero();
  double expected_progress_ = 0.0, busy_ = 0.0;
  std::unique_ptr<perception::StereoMatcher> matcher_;
  std::unique_ptr<perception::ElevationMap> map_;
  StereoPair pair_;
  long stereo_frames_ = 0;
  void update_map(const SensorFrame& f);
};

}  // namespace ernest::runtime
