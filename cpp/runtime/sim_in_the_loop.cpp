#include "ernest/runtime/sim_in_the_loop.hpp"

#include <cmath>

#include "ernest/runtime/sim_interface.hpp"

namespace ernest::runtime {

namespace {
void finish(EpisodeReport& r, const envs::RoverEnv& env) {
  r.travel_reduction = r.metrics.travel_reduction();
  r.cost_of_transport = r.metrics.cost_of_transport(env.parameters().total_mass());
}
}  // namespace

EpisodeReport run_env_episode(envs::RoverEnv& env, Policy& policy, std::uint64_t seed,
                              Telemetry* telemetry, const ProgressCallback& progress) {
  EpisodeReport rep;
  sensing::ObservationVector obs = env.reset(seed);
  SensorFrame frame;
  auto record = [&](const sensing::ActionVector& a, const Eigen::Vector3d& cmd) {
    if (!telemetry) return;
    const dynamics::RoverState& s = env.sim().state();
    fill_sensor_frame(s, frame);
    TelemetryRow row;
    row.time = s.time;
    row.frame = &frame;
    row.action = a;
    row.command = cmd;
    telemetry->record(row);
  };
  for (;;) {
    // The Python path: physical command from the module, mapped back to [-1, 1]^3.
    const Eigen::Vector3d cmd = policy.command(obs);
    const sensing::ActionVector a = sensing::command_to_action(cmd, env.options().limits);
    rep.actions.push_back(a);
    record(a, cmd);  // the state the action was computed from, and the action
    const envs::StepResult r = env.step(a);
    obs = r.observation;
    if (progress) progress(env.metrics().time, env.metrics().progress, a);
    if (r.terminated || r.truncated) {
      rep.end = r.message;
      rep.diverged = r.diverged;
      break;
    }
  }
  rep.metrics = env.metrics();
  finish(rep, env);
  return rep;
}

EpisodeReport run_onboard_episode(envs::RoverEnv& env, Policy& policy, std::uint64_t seed,
                                  const LoopOptions* options, Telemetry* telemetry,
                                  const ProgressCallback& progress) {
  EpisodeReport rep;
  env.reset(seed);
  const envs::Scenario& sc = env.scenario();
  const LoopOptions opts = options ? *options : LoopOptions::from_env(env);
  SimRoverInterface io(env, opts.sensor_rate);
  ControlLoop loop(io, policy, env.parameters(), sc.path, opts);
  loop.set_fts_bias(env.fts_bias());
  loop.set_telemetry(telemetry);
  const double duration =
      env.options().episode_duration.value_or(sc.episode_duration);
  const long per_policy = std::lround(opts.sensor_rate / opts.policy_rate);
  const long total = std::lround(duration * opts.sensor_rate);
  const double start = sc.path.arc_length(sc.start_x, sc.start_y);
  const auto& t = sc.terrain;
  long last_steps = 0;
  rep.end = "time limit";
  for (long i = 0; i < total; ++i) {
    try {
      loop.tick();
    } catch (const dynamics::SimulationDiverged& e) {
      rep.diverged = true;
      rep.end = e.what();
      break;
    }
    if (loop.policy_steps() != last_steps) {
      last_steps = loop.policy_steps();
      rep.actions.push_back(loop.action());
    }
    if ((i + 1) % per_policy == 0) {
      const dynamics::RoverState& s = env.sim().state();
      rep.metrics.progress = sc.path.arc_length(s.position.x(), s.position.y()) - start;
      if (progress) progress((i + 1) / opts.sensor_rate, rep.metrics.progress, loop.action());
      const bool outside = s.position.x() < t.origin_x() + 0.5 || s.position.y() < t.origin_y() + 0.5 ||
                           s.position.x() > t.origin_x() + t.length_x() - 0.5 ||
                           s.position.y() > t.origin_y() + t.length_y() - 0.5;
      if (sc.path.arc_length(s.position.x(), s.position.y()) >= sc.end_distance || outside) {
        rep.end = outside ? "left the map" : "reached the end of the map";
        break;
      }
    }
  }
  const dynamics::RoverState& s = env.sim().state();
  rep.metrics.time = loop.ticks() / opts.sensor_rate;
  rep.metrics.progress = sc.path.arc_length(s.position.x(), s.position.y()) - start;
  rep.metrics.expected_progress = loop.expected_progress();
  rep.metrics.energy = s.energy;
  rep.watchdog_trips = loop.watchdog().trips();
  finish(rep, env);
  return rep;
}

}  // namespace ernest::runtime
