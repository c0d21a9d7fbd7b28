#include "ernest/footfall/swing_sag.hpp"

#include <limits>

#include "ernest/common/validation.hpp"
#include "ernest/walker/stance_loads.hpp"
#include "ernest/walker/stance_sag.hpp"

namespace ernest::footfall {

void SwingSagOptions::validate() const {
  require_in_range("SwingSagOptions", "stiffness", stiffness, 1.0, 1e9);
  require_in_range("SwingSagOptions", "lift_height", lift_height, 0.0, 2.0);
  sag.validate();
}

SwingSag predict_swing_sag(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                           const Eigen::Ref<const Eigen::MatrixXd>& q, int leg,
                           const SwingSagOptions& options) {
  options.validate();
  model.check_leg(leg);
  model.check_configuration(q);
  require(body.matrix().allFinite(), "predict_swing_sag: body pose is not finite");
  const int legs = model.legs();
  // CG of the swing stance: the wheel raised (walker::lift_legs, IK nearest the current angles).
  const Eigen::MatrixXd lifted = walker::lift_legs(model, body, q, {leg}, options.lift_height);
  const statics::SagProblem p = walker::stance_sag_problem(
      model, body, model.contact_points(body, q), lifted,
      Eigen::Matrix3Xd::Constant(3, legs, options.stiffness), leg);
  const statics::SagResult r = statics::solve_sag(p, options.sag);
  SwingSag out;
  out.status = r.status;
  out.rigid_body = body;
  out.sagged_body = walker::sagged_pose(r);
  out.hip_displacement = r.body_points.col(leg) - p.body_points.col(leg);
  out.hip_drop = (p.body_points.row(2) - r.body_points.row(2)).transpose();
  out.forces = r.forces;
  out.lifted_q = lifted.col(leg);
  return out;
}

}  // namespace ernest::footfall
