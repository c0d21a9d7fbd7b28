// The simulator behind the onboard loop's RoverInterface: the C++ RoverSim of an episode set up by
// envs::RoverEnv (terrain, obstacles, soil, friction, start pose), ticked at the sensor rate. The
// physics advances one step every sensor_rate * dt ticks (10 at 400 Hz and dt = 25 ms); between
// steps the sensors hold their last values and keep their stamps, exactly like sampled hardware.
#pragma once

#include <memory>

#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/envs/rover_env.hpp"
#include "ernest/perception/stereo_mapper.hpp"
#include "ernest/runtime/rover_interface.hpp"

namespace ernest::runtime {

/// The sensor frame a simulated rover delivers for `state` (every field; stamps = state time).
/// Shared by SimRoverInterface and the sim-in-the-loop telemetry.
void fill_sensor_frame(const dynamics::RoverState& state, SensorFrame& frame);

class SimRoverInterface : public RoverInterface {
 public:
  /// Drives `sim` (kept by reference) with elevation samples from `heights`. sensor_rate * sim dt
  /// must be a whole number of ticks.
  SimRoverInterface(dynamics::RoverSim& sim, const sensing::HeightSource& heights,
                    double sensor_rate = 400.0);
  /// The simulator of `env`'s current episode (call env.reset(seed) first); heights from its
  /// scenario (terrain and rocks, the stand-in for the stereo elevation map of §2.4). Valid until
  /// the env's next reset, which replaces the simulator.
  explicit SimRoverInterface(envs::RoverEnv& env, double sensor_rate = 400.0);

  double now() const override;
  const SensorFrame& read() override;
  void command(const ActuatorCommand& command) override;
  /// Advances the loop clock one tick, and the physics one step when its time comes. Throws
  /// dynamics::SimulationDiverged if the simulation blows up (a simulator failure, not a sensor
  /// fault).
  void wait_next_tick() override;
  const sensing::HeightSource& heights() const override { return *heights_; }
  /// With an env whose terrain_source is "stereo": the masthead pair ray-cast from the current
  /// state at the env's fusion rate (same scene, seed and frame numbering as its StereoMapper).
  bool stereo(StereoPair& out) override;

  long ticks() const { return ticks_; }
  int ticks_per_step() const { return ticks_per_step_; }
  dynamics::RoverSim& sim() { return sim_; }

 private:
  void init();
  dynamics::RoverSim& sim_;
  std::unique_ptr<sensing::HeightSource> owned_heights_;
  const sensing::HeightSource* heights_;
  double rate_, t0_;
  int ticks_per_step_;
  long ticks_ = 0;
  SensorFrame frame_{};
  std::unique_ptr<perception::Raycaster> raycaster_;  // stereo cameras (env with stereo)
  perception::StereoMapperOptions stereo_options_{};
  std::uint64_t stereo_frames_ = 0;
  double last_stereo_ = 0.0;
};

}  // namespace ernest::runtime
