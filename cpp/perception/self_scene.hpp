// The self-imaging scene shared by the tests, the benchmark and the Python demo: an SDM-B-sized
// walker (seed 003 §2.3) standing in its standard pose on gently undulating ground with a seeded
// ring of rocks just beyond its feet, and a leg raised by inverse kinematics as mid-step (§5.2:
// "we capture the stereo images mid-step, with the leg raised").
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/walker/walker_model.hpp"

namespace ernest::perception {

struct SelfImageScene {
  dynamics::HeightMap terrain = dynamics::HeightMap::flat(1.0, 1.0, 0.5);
  std::vector<dynamics::BoxObstacle> rocks;
  Eigen::Isometry3d body = Eigen::Isometry3d::Identity();  ///< body -> world
  Eigen::MatrixXd q;  ///< joints x legs: the standard configuration
};

/// 16 m x 16 m of ground (±3 cm undulation) centred under the walker, `rocks` boxes (0.15–0.35 m)
/// at 2.9–3.8 m from the body axis, in front of the legs in turn (beyond every wheel's reach in the
/// scene's poses), the body
/// at its standard pose.
SelfImageScene self_image_scene(const walker::WalkerModel& model, std::uint64_t seed, int rocks = 12);

/// Joint angles of `leg` with its wheel lifted by `lift` [m] and moved radially out by `reach`
/// [m] from the standard stance, foot orientation kept (LegIk from the standard angles). Throws
/// std::invalid_argument if the target is unreachable.
Eigen::VectorXd raised_leg(const walker::WalkerModel& model, int leg, double lift, double reach);

}  // namespace ernest::perception
