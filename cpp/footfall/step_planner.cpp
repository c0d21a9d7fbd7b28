#include "ernest/footfall/step_planner.hpp"

#include <cmath>

#include "ernest/common/validation.hpp"
#include "ernest/footfall/torque_smoothing.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::footfall {

void StepOptions::validate(int joints) const {
  collision.validate(joints);
  planner.validate();
  smoothing.validate();
  sag.validate();
  map.validate();
}

StepPlan plan_step(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                   const Eigen::Isometry3d& body, const Eigen::Ref<const Eigen::MatrixXd>& q, int leg,
                   double goal_x, double goal_y, const StepOptions& options) {
  options.validate(model.joints_per_leg());
  model.check_leg(leg);
  model.check_configuration(q);
  require(body.matrix().allFinite(), "plan_step: body pose is not finite");
  require(std::isfinite(goal_x) && std::isfinite(goal_y),
          "plan_step: goal_x, goal_y must be finite (got " + std::to_string(goal_x) + ", " +
              std::to_string(goal_y) + ")");
  StepPlan s;
  s.q_start = q.col(leg);
  s.goal = Eigen::Vector3d(goal_x, goal_y, terrain.height(goal_x, goal_y));
  auto no_plan = [&](std::string reason) {
    s.status = PlanStatus::kNoPlan;
    s.reason = std::move(reason);
    return s;
  };
  // The goal on the stability map's terms, in the stance after the step (§3.3).
  StabilityMapper after(model, terrain, body, q, leg, options.map);
  const CellEvaluation goal = after.evaluate(goal_x, goal_y, q.col(leg));
  if (goal.status == CellStatus::kUnreachable) return no_plan("goal unreachable (no IK solution on it or above it)");
  s.goal_margin = goal.margin;
  s.q_goal = goal.q;
  if (goal.status == CellStatus::kUnstable)
    return no_plan("goal unstable (CPS margin " + std::to_string(goal.margin) + " m)");
  s.goal_saturation = goal.saturation;
  if (goal.status == CellStatus::kOverloaded)  // §7.1: reachable and stable, beyond a torque limit
    return no_plan("goal overloads leg " + std::to_string(goal.peak_leg) + " joint " + std::to_string(goal.peak_joint) +
                   " (peak torque " + std::to_string(goal.saturation) + " of its limit, max_saturation " +
                   std::to_string(options.map.max_saturation) + ")");
  // Sag with the leg in the air (§4.1, §5.1).
  s.sag = predict_swing_sag(model, body, q, leg, options.sag);
  if (s.sag.status != statics::SagStatus::Converged)
    return no_plan(std::string("the stance cannot hold the robot with the leg lifted (sag model: ") +
                   statics::to_string(s.sag.status) + ")");
  s.planning_body = options.sag_compensation ? s.sag.sagged_body : body;
  // Compliance waypoints directly above the real ground points, in the planning pose (§3.3).
  StabilityMapper planning(model, terrain, s.planning_body, q, leg, options.map);
  walker::LegIk ik(model);
  const Eigen::Vector3d start_ground = body * model.contact_point(leg, q.col(leg));
  const walker::IkResult up0 = ik.solve(leg, planning.target(start_ground, options.map.lift_height), q.col(leg));
  if (up0.status != walker::IkStatus::kSolved) return no_plan("the waypoint above the start is unreachable");
  const walker::IkResult up1 = ik.solve(leg, planning.target(s.goal, options.map.lift_height), goal.q_above);
  if (up1.status != walker::IkStatus::kSolved) return no_plan("the waypoint above the goal is unreachable");
  s.q_start_above = up0.solutions.front();
  s.q_goal_above = up1.solutions.front();
  LegCollisionChecker checker(model, terrain, s.planning_body, q, leg, options.collision);
  // The compliance segments: the wheel leaves and meets the ground there (not checked with it).
  if (!checker.valid(s.q_start, false) || !checker.motion_valid(s.q_start, s.q_start_above, options.planner.epsilon, false))
    return no_plan("the lift above the start collides");
  if (!checker.valid(s.q_goal, false) || !checker.motion_valid(s.q_goal_above, s.q_goal, options.planner.epsilon, false))
    return no_plan("the descent onto the goal collides");
  LegPlanner planner(checker, options.planner);
  s.plan = planner.plan(s.q_start_above, s.q_goal_above);
  if (s.plan.status != PlanStatus::kSolved) return no_plan(s.plan.reason);
  SmoothingOptions smoothing = options.smoothing;
  smoothing.epsilon = options.planner.epsilon;
  if (smoothing.objective == SmoothingObjective::kPeakTorque || options.map.evaluates_torques()) {
    StanceTorques torques(model, s.planning_body, q, leg);
    s.smoothing = smoothing.objective == SmoothingObjective::kPeakTorque
                      ? smooth_path_for_torque(checker, torques, s.plan.path, smoothing)
                      : smooth_path(checker, s.plan.path, smoothing);
    s.path_saturation = torques.lifted_path(s.smoothing.path, smoothing.torque_resolution).saturation;
    if (s.path_saturation > options.map.max_saturation)  // §7.1: the swing itself overloads a joint
      return no_plan("the swing overloads a joint (peak torque " + std::to_string(s.path_saturation) +
                     " of its limit with the leg in the air, max_saturation " +
                     std::to_string(options.map.max_saturation) + ")");
  } else {
    s.smoothing = smooth_path(checker, s.plan.path, smoothing);
  }
  const Eigen::Index m = s.smoothing.path.cols();
  s.path.resize(model.joints_per_leg(), m + 2);
  s.path.col(0) = s.q_start;
  s.path.middleCols(1, m) = s.smoothing.path;
  s.path.col(m + 1) = s.q_goal;
  s.status = PlanStatus::kSolved;
  return s;
}

}  // namespace ernest::footfall
