#include "ernest/envs/rover_env.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/dynamics/wheel_sync.hpp"

namespace ernest::envs {

void EnvOptions::validate() const {
  const char* o = "EnvOptions";
  scenario.validate();
  soil::SoilParameters::preset(soil);  // throws naming the allowed presets
  // Optional fields: unset means "the default"; set, a value must be a real one (no 0 sentinel).
  if (physics_dt) {
    require_positive(o, "physics_dt", *physics_dt);
    require_in_range(o, "physics_dt", *physics_dt, 0.0, 0.05);
  }
  if (slip_force_tolerance) require_in_range(o, "slip_force_tolerance", *slip_force_tolerance, 1e-6, 1e9);
  if (obstacle_substeps) require_in_range(o, "obstacle_substeps", *obstacle_substeps, 1, 64);
  require_in_range(o, "policy_dt", policy_dt, 0.01, 5.0);
  if (episode_duration) {
    require_positive(o, "episode_duration", *episode_duration);
    require_in_range(o, "episode_duration", *episode_duration, 0.0, 3600.0);
  }
  require_in_range(o, "sync_rate", sync_rate, 1.0, 1e4);
  fts.validate();
  require_in_range(o, "fts_noise_force", fts_noise_force, 0.0, 1e3);
  require_in_range(o, "fts_noise_torque", fts_noise_torque, 0.0, 1e3);
  require_in_range(o, "start_speed", start_speed, 0.0, 0.5);
  if (eps_slip) {
    require_positive(o, "eps_slip", *eps_slip);
    require_in_range(o, "eps_slip", *eps_slip, 0.0, 1e8);
  }
  if (eps_motion) {
    require_positive(o, "eps_motion", *eps_motion);
    require_in_range(o, "eps_motion", *eps_motion, 0.0, 1.0);
  }
  require(terrain_source == "truth" || terrain_source == "stereo",
          "EnvOptions.terrain_source = '" + terrain_source + "'; allowed: 'truth', 'stereo'");
  if (terrain_source == "stereo") stereo.validate();
  scales.validate();
  weights.validate();
  limits.validate();
}

double EpisodeMetrics::travel_reduction() const {
  return expected_progress > 1e-9 ? 1.0 - progress / expected_progress : 0.0;
}

double EpisodeMetrics::cost_of_transport(double mass, double g) const {
  return progress > 1e-9 ? energy / (mass * g * progress) : INFINITY;
}

RoverEnv::RoverEnv(const dynamics::RoverParameters& params, const EnvOptions& options)
    : params_(params), options_(options) {
  params_.validate();
  options_.validate();
  sim_options_.ground = options_.rigid_ground ? dynamics::GroundType::Rigid : dynamics::GroundType::Soil;
  sim_options_.soil = soil::SoilParameters::preset(options_.soil);
  if (options_.eps_slip) sim_options_.soil.eps_slip = *options_.eps_slip;
  if (options_.eps_motion) sim_options_.soil.eps_motion = *options_.eps_motion;
  if (options_.physics_dt) sim_options_.dt = *options_.physics_dt;
  if (options_.slip_force_tolerance) sim_options_.slip_force_tolerance = *options_.slip_force_tolerance;
  if (options_.obstacle_substeps) sim_options_.obstacle_substeps = *options_.obstacle_substeps;
  sim_options_.validate();
  const double dt = sim_options_.dt;
  substeps_ = static_cast<int>(std::lround(options_.policy_dt / dt));
  require(substeps_ >= 1 && std::abs(substeps_ * dt - options_.policy_dt) < 1e-9,
          "EnvOptions.policy_dt must be a whole number of physics steps (dt = " +
              std::to_string(dt) + " s)");
  sync_every_ = std::max(1, static_cast<int>(std::lround(1.0 / (options_.sync_rate * dt))));
  // The filter runs at the sensor rate: each physics step feeds it fts_updates_ samples of the
  // (held) wrench, so the 0.5 Hz cutoff holds whatever the physics step.
  fts_updates_ = std::max(1, static_cast<int>(std::lround(options_.fts.sample_rate * dt)));
  sensing::FtsFilterOptions fo = options_.fts;
  fo.sample_rate = fts_updates_ / dt;
  fts_filter_ = sensing::FtsProcessor(fo);

  sensing::ElevationSamplingOptions eo;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d c = params_.wheel_centre(i);
    eo.wheel_xy(i, 0) = c.x();
    eo.wheel_xy(i, 1) = c.y();
  }
  // Rover frame origin at axle height; zero elevation = the ground under a rover at rest on flat
  // hard ground (§4.2), i.e. one wheel radius minus the static tyre deflection under a quarter of
  // the weight on the §3.4 spring (9 mm). On soft soil the samples then show the sinkage.
  const double deflection =
      params_.total_mass() * sim_options_.soil.gravity / 4.0 / sim_options_.rigid.stiffness;
  eo.ground_z = -(params_.wheel_radius - deflection);
  sampler_ = sensing::ElevationSampler(eo);

  bias_ = calibrate_bias();
  fts_filter_.set_bias(bias_);
}

RoverEnv::~RoverEnv() = default;

sensing::Wrenches RoverEnv::read_fts(const dynamics::RoverState& s) {
  sensing::Wrenches w;
  for (int i = 0; i < 4; ++i) w.row(i) = s.fts[i].transpose();
  return w;
}

sensing::Wrenches RoverEnv::calibrate_bias() const {
  // §4.2's calibration records the filtered readings with the chassis on a jack and the wheels
  // hanging. On a level simulated rover each sensor then reads its wheel assembly's weight,
  // F = (0, 0, -m g) and no torque (the assembly's CoM lies on the sensor axis; the simulator's
  // sensors read load - m g, checked by the environment tests). The four rows are identical, so
  // they vanish with the four-sensor mean: the bias matters on hardware, where sensors differ.
  sensing::Wrenches bias = sensing::Wrenches::Zero();
  bias.col(2).setConstant(-params_.wheel_assembly_mass * sim_options_.soil.gravity);
  return bias;
}

const Scenario& RoverEnv::scenario() const {
  if (!scenario_) throw std::logic_error("RoverEnv: call reset() first");
  return *scenario_;
}
const dynamics::RoverSim& RoverEnv::sim() const {
  if (!sim_) throw std::logic_error("RoverEnv: call reset() first");
  return *sim_;
}
dynamics::RoverSim& RoverEnv::sim() {
  if (!sim_) throw std::logic_error("RoverEnv: call reset() first");
  return *sim_;
}

sensing::ObservationVector RoverEnv::reset(std::uint64_t seed) {
  episode_rng_.seed(seed);
  return start_episode(seed);
}

// 63-bit seeds so that they stay representable as signed 64-bit integers (numpy, Python infos).
sensing::ObservationVector RoverEnv::reset_next() { return start_episode(episode_rng_() >> 1); }

sensing::ObservationVector RoverEnv::start_episode(std::uint64_t seed) {
  episode_seed_ = seed;
  scenario_ = std::make_shared<const Scenario>(generate_scenario(options_.scenario, seed));
  dynamics::SimOptions so = sim_options_;
  so.seed = seed;
  so.friction = scenario_->friction;
  sim_.reset();
  heights_.reset();
  sim_ = std::make_shared<dynamics::RoverSim>(params_, scenario_->terrain, scenario_->obstacles, so);
  sim_->reset(scenario_->start_x, scenario_->start_y, scenario_->start_heading, 0.0, 0.0,
              options_.start_speed);
  heights_ = std::make_unique<TerrainHeightSource>(scenario_->terrain, scenario_->obstacles);
  mapper_.reset();
  if (options_.terrain_source == "stereo") {
    perception::StereoMapperOptions mo = options_.stereo;
    mo.render.seed ^= seed;  // texture and sensor noise follow the episode seed (deterministic)
    mapper_ = std::make_shared<perception::StereoMapper>(scenario_->terrain, scenario_->obstacles, mo);
  }
  duration_ = options_.episode_duration.value_or(scenario_->episode_duration);
  noise_rng_.seed(seed ^ 0x9E3779B97F4A7C15ULL);
  fts_filter_.reset(read_fts(sim_->state()));
  action_ = sensing::command_to_action(Eigen::Vector3d::Zero(), options_.limits);  // standing still
  wheel_speeds_ = {0.0, 0.0, 0.0, 0.0};
  metrics_ = EpisodeMetrics{};
  step_count_ = 0;
  done_ = false;
  return observe();
}

void RoverEnv::physics_step(const Eigen::Vector3d& cmd) {
  const dynamics::RoverState& st = sim_->state();
  const bool active = !options_.passive;
  const double yaw_rate = active ? cmd[1] : 0.0, roll_rate = active ? cmd[2] : 0.0;
  if (step_count_ % sync_every_ == 0) {
    // §2.3, eq 8: knowns are V_x and the joint rates from the policy, and the chassis roll and
    // pitch rates measured by the IMU.
    const dynamics::WheelSyncResult r = dynamics::synchronise_wheels(
        params_, st.gimbal_yaw, st.gimbal_roll, cmd[0], st.body_angular_velocity.x(),
        st.body_angular_velocity.y(), yaw_rate, roll_rate);
    wheel_speeds_ = r.wheel_speeds;
  }
  dynamics::Commands c;
  c.wheel_speed = wheel_speeds_;
  c.yaw_rate = yaw_rate;
  c.roll_rate = roll_rate;
  c.gimbal_enabled = active;
  c.clutch_engage = active;
  sim_->set_commands(c);
  sim_->step();
  ++step_count_;
  const sensing::Wrenches w = read_fts(sim_->state());
  for (int k = 0; k < fts_updates_; ++k) fts_filter_.update(w);
}

StepResult RoverEnv::step(const sensing::ActionVector& action) {
  if (done_) throw std::logic_error("RoverEnv.step: the episode has ended; call reset()");
  require(action.allFinite(), "RoverEnv.step: action must be finite");
  action_ = action.cwiseMax(-1.0).cwiseMin(1.0);
  const Eigen::Vector3d cmd = sensing::action_to_command(action_, options_.limits);
  const Eigen::Vector3d p0 = sim_->state().position;
  StepResult out;
  double abs_roll_torque = 0.0;
  try {
    for (int i = 0; i < substeps_; ++i) {
      if (i > 0) poll_interrupt();  // Ctrl-C inside a VecRoverEnv step (common/interrupt.hpp)
      physics_step(cmd);
      abs_roll_torque += std::abs(sim_->state().roll_torque);
    }
  } catch (const Interrupted&) {
    done_ = true;  // stopped part way through the policy step: the episode cannot go on
    throw;
  } catch (const dynamics::SimulationDiverged& e) {
    // Never an exception out of step(): the episode ends, flagged (the agent is not to blame).
    out.diverged = true;
    out.truncated = true;
    out.message = e.what();
    out.observation = sensing::build_observation(sensing::ObservationInputs{}, options_.scales);
    done_ = true;
    return out;
  }
  abs_roll_torque /= substeps_;
  const dynamics::RoverState& st = sim_->state();
  const Scenario& sc = *scenario_;
  out.reward = sensing::compute_reward(sc.path, p0.x(), p0.y(), st.position.x(), st.position.y(),
                                       abs_roll_torque, options_.weights);
  metrics_.time += options_.policy_dt;
  metrics_.expected_progress += cmd[0] * options_.policy_dt;
  metrics_.progress = sc.path.arc_length(st.position.x(), st.position.y()) -
                      sc.path.arc_length(sc.start_x, sc.start_y);
  metrics_.distance += std::hypot(st.position.x() - p0.x(), st.position.y() - p0.y());
  metrics_.energy = st.energy;
  const double n = metrics_.time / options_.policy_dt;
  metrics_.mean_abs_roll_torque += (abs_roll_torque - metrics_.mean_abs_roll_torque) / n;
  out.observation = observe();

  const auto& t = sc.terrain;
  const bool outside = st.position.x() < t.origin_x() + 0.5 || st.position.y() < t.origin_y() + 0.5 ||
                       st.position.x() > t.origin_x() + t.length_x() - 0.5 ||
                       st.position.y() > t.origin_y() + t.length_y() - 0.5;
  if (sc.path.arc_length(st.position.x(), st.position.y()) >= sc.end_distance || outside) {
    out.terminated = true;
    out.message = outside ? "left the map" : "reached the end of the map";
  } else if (metrics_.time >= duration_ - 1e-9) {
    out.truncated = true;
    out.message = "time limit";
  }
  done_ = out.terminated || out.truncated;
  return out;
}

sensing::ObservationVector RoverEnv::observe() {
  const dynamics::RoverState& st = sim_->state();
  const Eigen::Quaterniond q(st.quaternion[0], st.quaternion[1], st.quaternion[2], st.quaternion[3]);
  const Eigen::Matrix3d rotation = q.toRotationMatrix();
  if (mapper_) {
    // the map moves with the rover every step; a frame is fused when the fusion rate says so
    mapper_->update(metrics_.time, st.position, rotation);
    elevation_ = sampler_.sample(st.position, rotation, mapper_->map());
  } else {
    elevation_ = sampler_.sample(st.position, rotation, *heights_);
  }
  fts_ = fts_filter_.processed();
  if (options_.fts_noise_force > 0.0 || options_.fts_noise_torque > 0.0) {
    std::normal_distribution<double> nf(0.0, options_.fts_noise_force),
        nt(0.0, options_.fts_noise_torque);
    for (int i = 0; i < 4; ++i)
      for (int a = 0; a < 6; ++a) fts_(i, a) += a < 3 ? nf(noise_rng_) : nt(noise_rng_);
  }
  sensing::ObservationInputs in;
  const sensing::PathLine& path = scenario_->path;
  in.heading_deviation = path.heading_deviation(st.yaw);
  in.lateral_deviation = path.lateral_deviation(st.position.x(), st.position.y());
  in.roll = st.roll;
  in.pitch = st.pitch;
  in.gimbal_yaw = st.gimbal_yaw;
  in.gimbal_roll = st.gimbal_roll;
  in.fts = fts_;
  in.elevation = elevation_.values;
  in.action = action_;
  return sensing::build_observation(in, options_.scales);
}

}  // namespace ernest::envs
