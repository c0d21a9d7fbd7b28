// Sim-in-the-loop without Python: a TorchScript policy driving the C++ episode core
// (envs::RoverEnv, the code under the Gymnasium environments) step by step, exactly as the Python
// path does (observation -> physical command -> sensing::command_to_action -> env.step), so that
// the only difference between the two is libtorch versus Python torch inference. Also the same
// episode through the onboard ControlLoop on the simulator interface.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ernest/envs/rover_env.hpp"
#include "ernest/runtime/control_loop.hpp"
#include "ernest/runtime/policy.hpp"
#include "ernest/runtime/telemetry.hpp"

namespace ernest::runtime {

struct EpisodeReport {
  std::vector<sensing::ActionVector> actions;  ///< one per policy step
  envs::EpisodeMetrics metrics{};
  double travel_reduction = 0.0;   ///< 1 - progress / commanded travel (Table 6)
  double cost_of_transport = 0.0;  ///< energy / (m g progress) (Table 6)
  std::string end;                 ///< why the episode ended
  bool diverged = false;
  long watchdog_trips = 0;         ///< onboard loop only
};

using ProgressCallback = std::function<void(double time, double progress, const sensing::ActionVector& action)>;

/// One episode of `env` from `seed` (reset inside) with `policy`, until terminated or truncated.
/// Telemetry (optional) gets one row per policy step. `progress` (optional) is called after each
/// step.
EpisodeReport run_env_episode(envs::RoverEnv& env, Policy& policy, std::uint64_t seed,
                              Telemetry* telemetry = nullptr, const ProgressCallback& progress = {});

/// The same episode through the onboard ControlLoop: env.reset(seed) sets up the scenario, then
/// the loop drives env.sim() through SimRoverInterface at the sensor rate for the episode's
/// duration (or until the end of the path). `options` defaults to LoopOptions::from_env(env).
EpisodeReport run_onboard_episode(envs::RoverEnv& env, Policy& policy, std::uint64_t seed,
                                  const LoopOptions* options = nullptr, Telemetry* telemetry = nullptr,
                                  const ProgressCallback& progress = {});

}  // namespace ernest::runtime
