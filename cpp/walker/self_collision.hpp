// Self-collision of a walker configuration with FCL (the project's collision library): the links'
// capsules (WalkerModel::leg_capsules) against those of the other legs, against the chassis
// (the hex ring's bounding cylinder) and against the non-neighbouring links of the same leg.
// FootFall's planner checks self-collisions along each leg motion (seed 003 §3.4, §2.3).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ernest/walker/walker_model.hpp"

namespace ernest::walker {

/// Index of the chassis in CollisionPair::leg_b (link_b is then -1).
inline constexpr int kChassis = -1;

/// Two shapes closer than the clearance. link -1 is the wheel (capsule along the axle).
struct CollisionPair {
  int leg_a = 0, link_a = 0;
  int leg_b = 0, link_b = 0;  ///< leg_b = kChassis for the chassis
  double distance = 0.0;      ///< separation [m]; 0 when the shapes intersect
};

/// Every pair within `clearance` [m] (0: intersecting only) in configuration q (joints × legs).
/// Pairs of one leg, and a leg's links with the chassis, that already touch in the standard
/// stance are joined by construction (neighbouring links, the wheel round the ankle, the hip in
/// the ring) and are not checked; every pair of links of different legs is. Throws
/// std::invalid_argument for a bad q or a clearance outside [0, 10] m.
std::vector<CollisionPair> self_collisions(const WalkerModel& model,
                                           const Eigen::Ref<const Eigen::MatrixXd>& q,
                                           double clearance = 0.0);

}  // namespace ernest::walker
