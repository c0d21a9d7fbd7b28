#include "ernest/runtime/control_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "ernest/common/validation.hpp"
#include "ernest/dynamics/wheel_sync.hpp"
#include "ernest/envs/rover_env.hpp"

namespace ernest::runtime {

namespace {
int ticks_per(double sensor_rate, double rate, const char* field) {
  const double n = sensor_rate / rate;
  const int k = static_cast<int>(std::lround(n));
  require(k >= 1 && std::abs(n - k) < 1e-9,
          std::string("LoopOptions.") + field + " must divide sensor_rate (" + std::to_string(n) +
              " ticks per period)");
  return k;
}
}  // namespace

void LoopOptions::validate() const {
  const char* o = "LoopOptions";
  require_in_range(o, "sensor_rate", sensor_rate, 1.0, 1e5);
  require_in_range(o, "policy_rate", policy_rate, 0.01, sensor_rate);
  require_in_range(o, "sync_rate", sync_rate, policy_rate, sensor_rate);
  ticks_per(sensor_rate, policy_rate, "policy_rate");
  ticks_per(sensor_rate, sync_rate, "sync_rate");
  require_in_range(o, "phase", phase, 0.0, sensor_rate / policy_rate - 1.0);
  require_positive(o, "cutoff", cutoff);
  scales.validate();
  elevation.validate();
  limits.validate();
  watchdog.validate();
  if (stereo_map) stereo.validate();
  require_in_range(o, "telemetry_every", telemetry_every, 1.0, 1e9);
}

LoopOptions LoopOptions::from_env(const envs::RoverEnv& env) {
  const envs::EnvOptions& e = env.options();
  LoopOptions o;
  const double dt = env.options().policy_dt / env.substeps();
  const int per_step = std::max(1, static_cast<int>(std::lround(e.fts.sample_rate * dt)));
  o.sensor_rate = per_step / dt;
  o.policy_rate = 1.0 / e.policy_dt;
  // RoverEnv synchronises every max(1, round(1 / (sync_rate dt))) physics steps.
  const int sync_steps = std::max(1, static_cast<int>(std::lround(1.0 / (e.sync_rate * dt))));
  o.sync_rate = o.sensor_rate / (sync_steps * per_step);
  o.phase = per_step - 1;
  o.cutoff = e.fts.cutoff;
  o.scales = e.scales;
  o.elevation = env.sampler().options();
  o.limits.velocity = e.limits;
  o.passive = e.passive;
  o.stereo_map = e.terrain_source == "stereo";
  o.stereo = env.mapper() ? env.mapper()->options() : e.stereo;
  return o;
}

ControlLoop::ControlLoop(RoverInterface& io, Policy& policy, const dynamics::RoverParameters& params,
                         const sensing::PathLine& path, const LoopOptions& options)
    : io_(io),
      policy_(policy),
      params_(params),
      path_(path),
      options_(options),
      fts_(sensing::FtsFilterOptions{options.sensor_rate, options.cutoff}),
      sampler_(options.elevation),
      watchdog_(options.watchdog) {
  params_.validate();
  options_.validate();
  policy_every_ = ticks_per(options_.sensor_rate, options_.policy_rate, "policy_rate");
  sync_every_ = ticks_per(options_.sensor_rate, options_.sync_rate, "sync_rate");
  action_ = sensing::command_to_action(Eigen::Vector3d::Zero(), options_.limits.velocity);  // standing
  out_.gimbal_enabled = out_.clutch_engage = !options_.passive;
  if (options_.stereo_map) {
    matcher_ = std::make_unique<perception::StereoMatcher>(options_.stereo.matcher);
    map_ = std::make_unique<perception::ElevationMap>(options_.stereo.map);
  }
  logger_ = [](double t, const std::string& m) { std::fprintf(stderr, "[runtime %9.3f s] %s\n", t, m.c_str()); };
}

void ControlLoop::set_fts_bias(const sensing::Wrenches& bias) { fts_.set_bias(bias); }

void ControlLoop::fault(Fault f, double now, const std::string& why) {
  if (watchdog_.trip(f, now, why))
    logger_(now, std::string("watchdog: ") + to_string(f) + ": " + why + " -> zero velocities");
}

void ControlLoop::update_map(const SensorFrame& f) {
  // the order of perception::StereoMapper::update: re-centre, then fuse a new pair
  map_->move_to(f.position.x(), f.position.y());
  if (!io_.stereo(pair_)) return;
  const auto& cam = options_.stereo.camera;
  const perception::FloatImage disparity = matcher_->compute(pair_.left, pair_.right);
  const perception::PointCloud cloud =
      perception::disparity_to_points(disparity, cam, 0.5, options_.stereo.max_depth);
  map_->fuse_cloud(cloud.points, pair_.left_pose, cam);
  ++stereo_frames_;
}

sensing::ObservationVector ControlLoop::observe(const SensorFrame& f) const {
  const sensing::HeightSource& heights = map_ ? static_cast<const sensing::HeightSource&>(*map_)
                                              : io_.heights();
  const sensing::ElevationSample elev =
      sampler_.sample(f.position, f.orientation.toRotationMatrix(), heights);
  sensing::ObservationInputs in;
  in.heading_deviation = path_.heading_deviation(f.yaw);
  in.lateral_deviation = path_.lateral_deviation(f.position.x(), f.position.y());
  in.roll = f.roll;
  in.pitch = f.pitch;
  in.gimbal_yaw = f.gimbal_yaw;
  in.gimbal_roll = f.gimbal_roll;
  in.fts = fts_.processed();
  in.elevation = elev.values;
  in.action = action_;
  return sensing::build_observation(in, options_.scales);
}

void ControlLoop::tick() {
  const auto t0 = std::chrono::steady_clock::now();
  const double now = io_.now();
  const SensorFrame& f = io_.read();
  std::string why;
  const Fault check = check_frame(f, now, options_.watchdog, why);
  if (check != Fault::None) {
    fault(check, now, why);
  } else {
    if (!fts_.initialised()) fts_.reset(f.fts);  // start the filter on the first sample
    fts_.update(f.fts);
    if (watchdog_.healthy(now)) logger_(now, "watchdog: data healthy again, policy resumes");
  }
  const long k = ticks_ - options_.phase;
  const bool policy_tick = k >= 0 && k % policy_every_ == 0;
  const bool sync_tick = k >= 0 && k % sync_every_ == 0;

  if (policy_tick && !watchdog_.tripped()) {
    bool ok = true;
    try {
      if (map_) update_map(f);
      observation_ = observe(f);
    } catch (const std::exception& e) {
      fault(Fault::Observation, now, e.what());
      ok = false;
    }
    if (ok) {
      try {
        // As in the environments: the action is the policy's command mapped to [-1, 1]^3 and
        // clamped; the command is the action mapped back.
        const Eigen::Vector3d raw = policy_.command(observation_);
        const sensing::ActionVector a =
            sensing::command_to_action(raw, options_.limits.velocity).cwiseMax(-1.0).cwiseMin(1.0);
        const Eigen::Vector3d cmd = sensing::action_to_command(a, options_.limits.velocity);
        command_ = limit_command(cmd, f.gimbal_yaw, f.gimbal_roll, params_, options_.limits);
        action_ = command_ == cmd ? a : sensing::command_to_action(command_, options_.limits.velocity);
        ++policy_steps_;
      } catch (const PolicyError& e) {
        fault(Fault::Inference, now, e.what());
      }
    }
  }

  if (watchdog_.tripped()) {
    command_.setZero();
    action_ = sensing::command_to_action(command_, options_.limits.velocity);
    out_.wheel_speed = {0.0, 0.0, 0.0, 0.0};
    out_.yaw_rate = out_.roll_rate = 0.0;
  } else {
    // Joint limits are re-checked every tick: a rate is cut as soon as its joint reaches the stop.
    command_ = limit_command(command_, f.gimbal_yaw, f.gimbal_roll, params_, options_.limits);
    const double yaw_rate = options_.passive ? 0.0 : command_[1];
    const double roll_rate = options_.passive ? 0.0 : command_[2];
    if (sync_tick) {
      // §2.3, eq 8: knowns V_x and the joint rates from the policy, chassis roll and pitch rates
      // from the IMU; eq 9-10 give the wheel speeds.
      const dynamics::WheelSyncResult r = dynamics::synchronise_wheels(
          params_, f.gimbal_yaw, f.gimbal_roll, command_[0], f.body_angular_velocity.x(),
          f.body_angular_velocity.y(), yaw_rate, roll_rate);
      for (int i = 0; i < 4; ++i) {
        const double w = r.wheel_speeds[i];
        const double m = options_.limits.max_wheel_speed;
        out_.wheel_speed[i] = std::isfinite(w) ? std::clamp(w, -m, m) : 0.0;
      }
    }
    out_.yaw_rate = yaw_rate;
    out_.roll_rate = roll_rate;
  }
  out_.gimbal_enabled = out_.clutch_engage = !options_.passive;
  io_.command(out_);
  expected_progress_ += command_[0] / options_.sensor_rate;

  if (telemetry_ && ticks_ % options_.telemetry_every == 0) {
    TelemetryRow row;
    row.time = now;
    row.frame = &f;
    row.action = action_;
    row.command = command_;
    row.fault = static_cast<int>(watchdog_.fault());
    telemetry_->record(row);
  }
  busy_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  io_.wait_next_tick();
  ++ticks_;
}

void ControlLoop::run(double duration) {
  const long n = std::lround(duration * options_.sensor_rate);
  for (long i = 0; i < n; ++i) tick();
}

}  // namespace ernest::runtime
