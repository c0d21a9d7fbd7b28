// Weight distribution of a walker stance (seed 003 §5.3.3, Fig. 16): the zero-interaction contact
// forces of the feet on the ground (statics::zero_interaction_forces, §5.1.1), the joint torques
// they and the links' weight load every leg with (tau = J^T f + g(q)), and the peak torque as a
// fraction of its limit. A lifted leg carries only its own links.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "ernest/walker/walker_model.hpp"

namespace ernest::walker {

struct StanceLoads {
  Eigen::Matrix3Xd reactions;   ///< ground on wheel, world frame [N] (3 × legs; 0 when lifted)
  Eigen::MatrixXd torques;      ///< joints × legs [N m]
  Eigen::MatrixXd saturation;   ///< |tau| / limit, joints × legs
  Eigen::Vector3d center_of_mass = Eigen::Vector3d::Zero();  ///< world [m]
  double peak_saturation = 0.0;  ///< max of `saturation` (Figs 15–16: 1 = saturation)
  int peak_leg = 0, peak_joint = 0;
  double peak_force = 0.0;       ///< largest |reaction| over the loaded legs [N]
  double mean_force = 0.0;       ///< mean |reaction| over the loaded legs [N]
  int loaded = 0;                ///< legs on the ground
  double support_margin = 0.0;   ///< SSM of the CG in the loaded feet's support polygon [m]
  double equilibrium_residual = 0.0;  ///< statics::DistributionInfo::residual
  double margin() const { return 1.0 - peak_saturation; }
};

/// Loads of the stance (body pose in the world, q of shape joints × legs, the legs in the air).
/// Throws std::invalid_argument for bad shapes, non-finite input, repeated or out-of-range
/// lifted legs, or fewer than three loaded legs.
StanceLoads stance_loads(const WalkerModel& model, const Eigen::Isometry3d& body,
                         const Eigen::Ref<const Eigen::MatrixXd>& q, const std::vector<int>& lifted);

/// q with each listed leg's wheel raised by `height` along the world vertical (wheel kept
/// upright, same heading), solved by IK from the leg's current angles (the solution nearest to
/// them). Throws std::invalid_argument when a raised foot is unreachable.
Eigen::MatrixXd lift_legs(const WalkerModel& model, const Eigen::Isometry3d& body,
                          const Eigen::Ref<const Eigen::MatrixXd>& q, const std::vector<int>& legs,
                          double height);

}  // namespace ernest::walker
