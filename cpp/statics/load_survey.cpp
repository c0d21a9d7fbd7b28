// Simulated load survey for eq 11 (seed 004 §3.2): static poses, settled, FTS read.
#include "ernest/statics/load_survey.hpp"
#include "ernest/common/interrupt.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/dynamics/terrain.hpp"

namespace ernest::statics {

using namespace ernest::dynamics;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

namespace {
constexpr double kDeg = M_PI / 180.0;

void require_list(const char* field, const std::vector<double>& v, double lo, double hi) {
  require(!v.empty(), std::string("SurveyOptions.") + field + " must not be empty");
  for (double x : v) require_in_range("SurveyOptions", field, x, lo, hi);
}

// Rigid plane rising along +x at `slope`, plus square plateaus `block` high centred on `blocks`.
HeightMap survey_terrain(double slope, const std::vector<Vec3>& blocks, double block) {
  const double spacing = 0.02, half = 2.0;
  const int n = static_cast<int>(std::lround(2.0 * half / spacing)) + 1;
  Eigen::MatrixXd h(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = -half + i * spacing, y = -half + j * spacing;
      h(i, j) = std::tan(slope) * x;
      for (const Vec3& b : blocks)
        if (std::abs(x - b.x()) <= 0.18 && std::abs(y - b.y()) <= 0.18) h(i, j) += block;
    }
  }
  return HeightMap(h, spacing, -half, -half);
}

LoadPose settle_and_measure(const RoverParameters& p, const HeightMap& terrain, double heading,
                            double psi, const SurveyOptions& o) {
  SimOptions so;
  so.ground = GroundType::Rigid;
  so.friction = o.friction;
  RoverSim sim(p, terrain, {}, so);
  sim.reset(0.0, 0.0, heading, psi, 0.0);
  Commands c;  // AGS off (yaw brake holds psi), clutch open (§3.2), wheels held
  c.gimbal_enabled = false;
  c.clutch_engage = false;
  sim.set_commands(c);
  const int settle = static_cast<int>(std::lround(o.settle_time / so.dt));
  const int avg = std::max(1, static_cast<int>(std::lround(o.average_time / so.dt)));
  sim.step_n(std::max(0, settle - avg));
  LoadPose mean;
  mean.loads.setZero();
  mean.roll_torque = 0.0;
  for (int k = 0; k < avg; ++k) {  // forces averaged, attitude and joints of the last step
    poll_interrupt();  // Ctrl-C between steps (common/interrupt.hpp); step_n above polls too
    sim.step();
    const LoadPose q = pose_from_state(p, sim.state(), so.soil.gravity);
    mean.loads += q.loads / avg;
    mean.horizontal_forces += q.horizontal_forces / avg;
    mean.roll_torque += q.roll_torque / avg;
    if (k == avg - 1) {
      mean.chassis_quaternion = q.chassis_quaternion;
      mean.psi = q.psi;
      mean.phi = q.phi;
    }
  }
  return mean;
}

}  // namespace

LoadPose pose_from_state(const RoverParameters& p, const RoverState& s, double gravity,
                         const Vec3& ground_normal) {
  LoadPose pose;
  const Eigen::Quaterniond q(s.quaternion[0], s.quaternion[1], s.quaternion[2], s.quaternion[3]);
  const Mat3 rc = q.normalized().toRotationMatrix();
  const Mat3 rb = rc * (Eigen::AngleAxisd(s.gimbal_yaw, Vec3::UnitZ()) *
                        Eigen::AngleAxisd(s.gimbal_roll, Vec3::UnitX())).toRotationMatrix();
  for (int i = 0; i < 4; ++i) {
    // FTS: force of the assembly on its mount in the mount's frame (the bogie for the front
    // wheels); static assembly: ground force = that force + the assembly's weight
    const Vec3 f = (i < 2 ? rb : rc) * s.fts[i].head<3>();
    pose.loads[i] = f.z() + p.wheel_assembly_mass * gravity;
    pose.horizontal_forces.col(i) = f.head<2>();
  }
  pose.chassis_quaternion = s.quaternion;
  pose.psi = s.gimbal_yaw;
  pose.phi = s.gimbal_roll;
  pose.roll_torque = s.roll_torque;
  pose.ground_normal = ground_normal;
  return pose;
}

void SurveyOptions::validate() const {
  require_list("yaws_deg", yaws_deg, -45.0, 45.0);
  require_list("slopes_deg", slopes_deg, 0.0, 30.0);
  require_list("headings_deg", headings_deg, -360.0, 360.0);
  require_in_range("SurveyOptions", "block_height", block_height, 0.0, 0.15);
  require_in_range("SurveyOptions", "settle_time", settle_time, 0.5, 60.0);
  require_in_range("SurveyOptions", "average_time", average_time, 0.0, settle_time);
  require_in_range("SurveyOptions", "friction", friction, 0.05, 2.0);
}

std::vector<LoadPose> survey_loads(const RoverParameters& params, const SurveyOptions& o) {
  params.validate();
  o.validate();
  for (double yaw : o.yaws_deg)
    require_in_range("SurveyOptions", "yaws_deg", yaw * kDeg, -params.yaw_limit, params.yaw_limit);
  std::vector<LoadPose> poses;
  const Vec3 gimbal = params.gimbal_point();
  for (double slope_deg : o.slopes_deg) {
    const double slope = slope_deg * kDeg;
    const Vec3 normal(-std::sin(slope), 0.0, std::cos(slope));
    const std::vector<double> headings =
        slope_deg == 0.0 ? std::vector<double>{0.0} : o.headings_deg;
    for (double heading_deg : headings) {
      const double heading = heading_deg * kDeg;
      const Mat3 rz = Eigen::AngleAxisd(heading, Vec3::UnitZ()).toRotationMatrix();
      for (double yaw_deg : o.yaws_deg) {
        const double psi = yaw_deg * kDeg;
        // no block, then (flat ground only) a block under each wheel in turn
        const int variants = slope_deg == 0.0 && o.block_height > 0.0 ? 5 : 1;
        for (int v = 0; v < variants; ++v) {
          std::vector<Vec3> blocks;
          if (v > 0) {
            const int i = v - 1;
            Vec3 w = params.wheel_centre(i);
            if (i < 2) w = gimbal + Eigen::AngleAxisd(psi, Vec3::UnitZ()) * (w - gimbal);
            blocks.push_back(rz * w);
          }
          LoadPose pose = settle_and_measure(params, survey_terrain(slope, blocks, o.block_height),
                                             heading, psi, o);
          pose.ground_normal = normal;
          poses.push_back(pose);
        }
      }
    }
  }
  return poses;
}

}  // namespace ernest::statics
