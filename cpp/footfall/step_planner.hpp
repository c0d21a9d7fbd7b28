// One FootFall step of one leg (seed 003 §3.3–3.4, §4.1, §5.1): the goal checked on the
// stability map's criteria (reachable, waypoint above it reachable, stable), the stance's sag
// predicted with the leg in the air, the compliance waypoints directly above start and goal
// placed over the real ground in that sagged pose (so the wheel breaks contact however far the
// chassis droops), SBL between the waypoints against the sagged pose, and the plan smoothed.
// Torque-aware (§7.1): with map.max_saturation finite a goal whose stance overloads a joint is
// refused, so is a swing whose path (the leg in the air) exceeds it, and smoothing.objective =
// kPeakTorque smooths for the smallest peak joint torque.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <string>

#include "ernest/footfall/leg_collision.hpp"
#include "ernest/footfall/leg_planner.hpp"
#include "ernest/footfall/path_smoothing.hpp"
#include "ernest/footfall/stability_map.hpp"
#include "ernest/footfall/swing_sag.hpp"

namespace ernest::footfall {

struct StepOptions {
  CollisionOptions collision;
  PlannerOptions planner;
  SmoothingOptions smoothing;
  SwingSagOptions sag;
  StabilityMapOptions map;  ///< lift_height of the waypoints, the stability criterion and margin
  /// true: plan against the sagged pose the compliance model predicts; false: the rigid pose
  /// (the uncompensated plan, for comparison).
  bool sag_compensation = true;
  void validate(int joints) const;
};

struct StepPlan {
  PlanStatus status = PlanStatus::kNoPlan;
  std::string reason;                 ///< why there is no plan ("" when solved)
  SwingSag sag;                       ///< predicted sag during the swing
  Eigen::Isometry3d planning_body = Eigen::Isometry3d::Identity();  ///< pose planned against
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();  ///< goal ground point (world)
  double goal_margin = 0.0;           ///< SSM/NESM of the CPS after the step [m]
  /// Peak |tau| / limit of the goal's stances (CellEvaluation::saturation) and along the path
  /// between the waypoints with the leg in the air; NaN unless torques are evaluated
  /// (map.evaluates_torques() or the kPeakTorque smoother).
  double goal_saturation = std::numeric_limits<double>::quiet_NaN();
  double path_saturation = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd q_start, q_start_above, q_goal_above, q_goal;
  PlanResult plan;                    ///< SBL between the two waypoints
  SmoothingResult smoothing;          ///< of plan.path
  Eigen::MatrixXd path;               ///< q_start, the smoothed waypoints path, q_goal
};

/// Plans a step of `leg` from the stance (body pose, q joints × legs, every foot down) to the
/// ground point below (goal_x, goal_y). Non-finite input throws std::invalid_argument; an
/// unreachable, unstable or overloaded goal, an unstable swing stance, a blocked compliance segment or no
/// path within the budget give kNoPlan with the reason.
StepPlan plan_step(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                   const Eigen::Isometry3d& body, const Eigen::Ref<const Eigen::MatrixXd>& q, int leg,
                   double goal_x, double goal_y, const StepOptions& options = {});

}  // namespace ernest::footfall
