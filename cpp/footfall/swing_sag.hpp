// Sag of the stance while one leg swings (seed 003 §4.1, §5.1): the compliance model of
// cpp/statics (eqs 1–12, each wheel three linear springs) solved with the swing leg's foot in the
// air, giving the pose the chassis sags to during the step. FootFall's planner plans against this
// predicted pose instead of the paper's field heuristic of lifting the terrain by 15 cm (§4.1).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "ernest/statics/sag.hpp"
#include "ernest/walker/walker_model.hpp"

namespace ernest::footfall {

struct SwingSagOptions {
  /// Wheel spring constant, every axis [N/m]: 6e4 is the tyre constant of ernest statics'
  /// Fig. 11 sag experiment (SDM-B's pneumatic tyres, calibrated there on synthetic heights).
  double stiffness = 6e4;
  /// Height the swing wheel is lifted to for the CG of the swing stance [m].
  double lift_height = 0.2;
  statics::SagOptions sag;  ///< the sag solver's options
  void validate() const;
};

struct SwingSag {
  statics::SagStatus status = statics::SagStatus::NotConverged;
  Eigen::Isometry3d rigid_body = Eigen::Isometry3d::Identity();   ///< the unsagged body pose
  Eigen::Isometry3d sagged_body = Eigen::Isometry3d::Identity();  ///< predicted pose (world)
  Eigen::Vector3d hip_displacement = Eigen::Vector3d::Zero();     ///< of the swing leg's hip [m]
  Eigen::VectorXd hip_drop;       ///< downward displacement of every hip [m] (> 0 down)
  Eigen::Matrix3Xd forces;        ///< ground on each wheel [N] (swing column zero)
  Eigen::VectorXd lifted_q;       ///< the swing leg's angles with its wheel lifted (rigid pose)
};

/// Predicted sagged body pose of a stance (body pose in the world, q joints × legs, every foot
/// on the ground) while `leg` swings. Throws std::invalid_argument for invalid input or when the
/// lifted wheel is unreachable; status Unstable when the other feet cannot hold the robot.
SwingSag predict_swing_sag(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                           const Eigen::Ref<const Eigen::MatrixXd>& q, int leg,
                           const SwingSagOptions& options = {});

}  // namespace ernest::footfall
