#include "ernest/walker/stance_sag.hpp"

#include <limits>

#include "ernest/common/validation.hpp"

namespace ernest::walker {

statics::SagProblem stance_sag_problem(const WalkerModel& model, const Eigen::Isometry3d& body,
                                       const Eigen::Ref<const Eigen::Matrix3Xd>& feet,
                                       const Eigen::Ref<const Eigen::MatrixXd>& cg_q,
                                       const Eigen::Ref<const Eigen::Matrix3Xd>& stiffness,
                                       int lifted) {
  const int legs = model.legs();
  if (lifted != -1) model.check_leg(lifted);
  require(feet.cols() == legs && stiffness.cols() == legs,
          "stance_sag_problem: feet and stiffness need one column per leg");
  statics::SagProblem p;
  p.feet = feet;
  p.stiffness = stiffness;
  p.lift = Eigen::VectorXd::Zero(legs);
  if (lifted >= 0) p.lift[lifted] = std::numeric_limits<double>::infinity();  // eq 9: never touches
  p.cg = model.center_of_mass(body, cg_q);
  p.mass = model.params().total_mass();
  p.gravity = Eigen::Vector3d(0.0, 0.0, -model.params().gravity);
  p.chassis_position = body.translation();
  p.chassis_rotation = body.linear();
  p.body_points.resize(3, legs);
  for (int k = 0; k < legs; ++k) p.body_points.col(k) = body * model.hip_mount(k).translation();
  return p;
}

Eigen::Isometry3d sagged_pose(const statics::SagResult& result) {
  Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
  b.linear() = result.chassis_rotation;
  b.translation() = result.chassis_position;
  return b;
}

}  // namespace ernest::walker
