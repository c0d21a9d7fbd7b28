// FootFall's gait planner (seed 003 §5.3.1): the skeleton gait of a discontinuous reverse-wave
// gait. The legs step one at a time with the body still, in order from front to rear, starting
// with the left side relative to the direction of travel; after each step the body shifts with
// every foot down. The step length is found "numerically by successive inverse kinematics
// tests": the largest advance of the stepping foot (up to max_step) for which the leg's IK has a
// solution inside the joint limits at the goal and at the compliance waypoints above start and
// goal (§3.3), and the stance on the other feet is statically stable (SSM, cpp/statics) with the
// leg at either waypoint. The body shift recentres the body over the feet along the direction of
// travel, shortened (again by successive IK) until every leg reaches its foot. Step planning (the
// leg's path between the configurations) is not done here: see walker_sim's swing paths.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "ernest/walker/walker_model.hpp"

namespace ernest::walker {

struct GaitPlannerOptions {
  double heading = 0.0;          ///< direction of travel in the world xy plane [rad]
  int cycles = 4;                ///< gait cycles to plan (every leg steps once a cycle), [1, 100]
  double max_step = 0.5;         ///< longest step of a foot [m] (sway gait's stride), (0, 5]
  double lift_height = 0.2;      ///< compliance waypoints above start and goal [m] (§4.1), [0, 2]
  double min_support_margin = 0.05;  ///< SSM required while a leg is in the air [m], [-10, 10]
  double search_increment = 0.05;  ///< successive IK tests every this much [m], (0, 1]
  double search_tolerance = 1e-4;  ///< bisection of the last interval down to this [m], (0, 0.1]
  int ik_seeds = 8;              ///< multi-start IK seeds before a target is declared unreachable
  /// Stepping order; empty: the reverse wave for `heading` (reverse_wave_sequence).
  std::vector<int> sequence;
  /// Throws std::invalid_argument naming the field (the sequence must list every leg once).
  void validate(int legs) const;
};

/// One event of the skeleton gait: a step of one leg (body still) or a body shift (feet still).
struct GaitEvent {
  enum Kind { kStep = 0, kShift = 1 };
  Kind kind = kStep;
  int cycle = 0;
  int leg = -1;                      ///< stepping leg (kStep), -1 for a shift
  double length = 0.0;               ///< step of the foot or shift of the body [m]
  Eigen::Vector3d body_before = Eigen::Vector3d::Zero(), body_after = Eigen::Vector3d::Zero();
  Eigen::Matrix3Xd feet_before, feet_after;  ///< wheel contact points, world (3 × legs)
  Eigen::MatrixXd q_before, q_after;         ///< joints × legs
  /// kStep: the leg at the compliance waypoints above start and goal (joints).
  Eigen::VectorXd q_lift_start, q_lift_goal;
  /// Smallest SSM of the CG over the loaded feet during the event [m] (a step: the leg at either
  /// waypoint over the other feet; a shift: all feet at the start and the end).
  double support_margin = 0.0;
};

struct GaitPlan {
  std::vector<int> sequence;
  std::vector<GaitEvent> events;  ///< step, shift, step, shift, ... (12 a cycle for six legs)
  Eigen::MatrixXd step_lengths;   ///< cycles × legs-in-sequence order [m]
  Eigen::MatrixXd shift_lengths;  ///< cycles × legs [m] (the shift after each step)
  int ik_tests = 0;               ///< IK problems solved by the searches
  double seconds = 0.0;
};

/// Legs ordered front to rear along `heading` (projection of the hip on the direction of travel),
/// left before right at equal projection (§5.3.1's reverse wave).
std::vector<int> reverse_wave_sequence(const WalkerModel& model, double heading);

/// Plans options.cycles gait cycles on flat ground (z = 0) from the body pose `body` (any
/// position, level) and configuration q (joints × legs, every wheel on the ground). Throws
/// std::invalid_argument for invalid options or input, or when a leg cannot step at all.
GaitPlan plan_gait(const WalkerModel& model, const Eigen::Vector3d& body_position,
                   const Eigen::Ref<const Eigen::MatrixXd>& q, const GaitPlannerOptions& options = {});

}  // namespace ernest::walker
