#include "ernest/runtime/sim_interface.hpp"

#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/envs/terrain_source.hpp"

namespace ernest::runtime {

SimRoverInterface::SimRoverInterface(dynamics::RoverSim& sim, const sensing::HeightSource& heights,
                                     double sensor_rate)
    : sim_(sim), heights_(&heights), rate_(sensor_rate), t0_(sim.state().time) {
  init();
}

SimRoverInterface::SimRoverInterface(envs::RoverEnv& env, double sensor_rate)
    : sim_(env.sim()),
      owned_heights_(std::make_unique<envs::TerrainHeightSource>(env.scenario().terrain,
                                                                 env.scenario().obstacles)),
      heights_(owned_heights_.get()),
      rate_(sensor_rate),
      t0_(env.sim().state().time) {
  init();
  if (env.mapper()) {
    stereo_options_ = env.mapper()->options();  // render seed already follows the episode seed
    raycaster_ = std::make_unique<perception::Raycaster>(env.scenario().terrain,
                                                         env.scenario().obstacles,
                                                         stereo_options_.render);
  }
}

bool SimRoverInterface::stereo(StereoPair& out) {
  if (!raycaster_) return false;
  // the schedule of perception::StereoMapper::update, on the simulator's clock
  const dynamics::RoverState& s = sim_.state();
  const double time = s.time - t0_;
  if (stereo_frames_ > 0 && time - last_stereo_ < 1.0 / stereo_options_.fusion_rate - 1e-9) return false;
  const Eigen::Vector3d position = s.position;
  const Eigen::Matrix3d rotation =
      Eigen::Quaterniond(s.quaternion[0], s.quaternion[1], s.quaternion[2], s.quaternion[3])
          .toRotationMatrix();
  const auto& cam = stereo_options_.camera;
  out.stamp = s.time;
  out.left_pose = cam.camera_pose(position, rotation, 0);
  perception::FloatImage depth;
  raycaster_->render(out.left_pose, cam, 2 * stereo_frames_, out.left, depth);
  raycaster_->render(cam.camera_pose(position, rotation, 1), cam, 2 * stereo_frames_ + 1, out.right,
                     depth);
  last_stereo_ = time;
  ++stereo_frames_;
  return true;
}

void SimRoverInterface::init() {
  require_positive("SimRoverInterface", "sensor_rate", rate_);
  const double per = rate_ * sim_.options().dt;
  ticks_per_step_ = static_cast<int>(std::lround(per));
  require(ticks_per_step_ >= 1 && std::abs(per - ticks_per_step_) < 1e-9,
          "SimRoverInterface: sensor_rate * dt = " + std::to_string(per) +
              " must be a whole number of ticks per physics step");
}

double SimRoverInterface::now() const { return t0_ + static_cast<double>(ticks_) / rate_; }

void fill_sensor_frame(const dynamics::RoverState& s, SensorFrame& f) {
  f.fts_stamp = f.pose_stamp = f.joint_stamp = s.time;
  for (int i = 0; i < 4; ++i) f.fts.row(i) = s.fts[i].transpose();
  f.position = s.position;
  f.orientation = Eigen::Quaterniond(s.quaternion[0], s.quaternion[1], s.quaternion[2], s.quaternion[3]);
  f.roll = s.roll;
  f.pitch = s.pitch;
  f.yaw = s.yaw;
  f.body_angular_velocity = s.body_angular_velocity;
  f.gimbal_yaw = s.gimbal_yaw;
  f.gimbal_roll = s.gimbal_roll;
  f.wheel_speed = s.wheel_speed;
  f.wheel_load = s.wheel_load;
  f.power = 0.0;
  for (double p : s.motor_power) f.power += p;
  f.energy = s.energy;
  f.roll_torque = s.roll_torque;
}

const SensorFrame& SimRoverInterface::read() {
  fill_sensor_frame(sim_.state(), frame_);
  return frame_;
}

void SimRoverInterface::command(const ActuatorCommand& c) {
  dynamics::Commands k;
  k.wheel_speed = c.wheel_speed;
  k.yaw_rate = c.yaw_rate;
  k.roll_rate = c.roll_rate;
  k.gimbal_enabled = c.gimbal_enabled;
  k.clutch_engage = c.clutch_engage;
  sim_.set_commands(k);
}

void SimRoverInterface::wait_next_tick() {
  ++ticks_;
  if (ticks_ % ticks_per_step_ == 0) sim_.step();
}

}  // namespace ernest::runtime
