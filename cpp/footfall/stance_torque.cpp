// Static joint torques of a stance as one leg steps (seed 003 §7.1, §5.3.2–5.3.3, §5.1.1); see
// stance_torque.hpp.
#include "ernest/footfall/stance_torque.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/statics/force_distribution.hpp"

namespace ernest::footfall {

StanceTorques::StanceTorques(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                             const Eigen::Ref<const Eigen::MatrixXd>& q, int leg)
    : model_(model), body_(body), leg_(leg), ws_(model) {
  model.check_leg(leg);
  model.check_configuration(q);
  require(body.matrix().allFinite(), "StanceTorques: body pose is not finite");
  const walker::WalkerParameters& p = model.params();
  const int legs = model.legs(), n = model.joints_per_leg();
  gravity_ = Eigen::Vector3d(0.0, 0.0, -p.gravity);
  const Eigen::Matrix3d rt = body.linear().transpose();
  gravity_body_ = rt * gravity_;
  total_mass_ = p.total_mass();
  contacts_.resize(3, legs);
  loaded_.resize(3, legs - 1);
  forces_all_.resize(3, legs);
  forces_loaded_.resize(3, legs - 1);
  force_to_tau_.assign(legs, Eigen::MatrixXd::Zero(n, 3));
  gravity_tau_.resize(n, legs);
  tau_.resize(n);
  jacobian_.resize(3, n);
  Eigen::Matrix3Xd& J = jacobian_;
  Eigen::Vector3d swing_moment = Eigen::Vector3d::Zero();
  for (int k = 0, c = 0; k < legs; ++k) {
    model.forward(k, q.col(k), ws_);
    contacts_.col(k) = body * ws_.contact;
    if (k != leg) loaded_.col(c++) = contacts_.col(k);
    model.gravity_torques(ws_, gravity_body_, gravity_tau_.col(k));
    // tau = g + J^T (-R^T f) with f the ground's force on the wheel in the world (joint_torques).
    model.contact_jacobian(ws_, J);
    force_to_tau_[k] = -J.transpose() * rt;
    if (k == leg)
      for (int i = 0; i < n; ++i) swing_moment += p.joints[i].mass * (body * ws_.link_com.col(i));
  }
  rest_moment_ = total_mass_ * model.center_of_mass(body, q) - swing_moment;
}

TorquePeak StanceTorques::evaluate(bool swing_down) {
  ++evaluations_;
  // ws_ holds the swing leg's frames: its CG contribution, contact, Jacobian and gravity torques.
  const walker::WalkerParameters& p = model_.params();
  const int legs = model_.legs(), n = model_.joints_per_leg();
  Eigen::Vector3d moment = rest_moment_;
  for (int i = 0; i < n; ++i) moment += p.joints[i].mass * (body_ * ws_.link_com.col(i));
  const Eigen::Vector3d cg = moment / total_mass_;
  model_.gravity_torques(ws_, gravity_body_, gravity_tau_.col(leg_));
  if (swing_down) {
    model_.contact_jacobian(ws_, jacobian_);
    force_to_tau_[leg_].noalias() = -jacobian_.transpose() * body_.linear().transpose();
    contacts_.col(leg_) = body_ * ws_.contact;
    statics::zero_interaction_forces(contacts_, cg, total_mass_, gravity_, forces_all_);
  } else {
    statics::zero_interaction_forces(loaded_, cg, total_mass_, gravity_, forces_loaded_);
  }
  const Eigen::VectorXd& limit = model_.torque_limits();
  TorquePeak peak;
  peak.saturation = -1.0;
  for (int k = 0, c = 0; k < legs; ++k) {
    tau_ = gravity_tau_.col(k);
    if (swing_down) tau_.noalias() += force_to_tau_[k] * forces_all_.col(k);
    else if (k != leg_) tau_.noalias() += force_to_tau_[k] * forces_loaded_.col(c++);
    for (int i = 0; i < n; ++i) {
      const double s = std::abs(tau_[i]) / limit[i];
      if (s > peak.saturation) peak = {s, k, i};
    }
  }
  return peak;
}

TorquePeak StanceTorques::down(const Eigen::Ref<const Eigen::VectorXd>& q_leg) {
  model_.check_q(q_leg, "q_leg");
  model_.forward(leg_, q_leg, ws_);
  return evaluate(true);
}

TorquePeak StanceTorques::lifted(const Eigen::Ref<const Eigen::VectorXd>& q_leg) {
  model_.check_q(q_leg, "q_leg");
  model_.forward(leg_, q_leg, ws_);
  return evaluate(false);
}

TorquePeak StanceTorques::lifted_segment(const Eigen::Ref<const Eigen::VectorXd>& a,
                                         const Eigen::Ref<const Eigen::VectorXd>& b, double resolution) {
  require_in_range("StanceTorques.lifted_segment", "resolution", resolution, 1e-4, 10.0);
  model_.check_q(a, "a");
  model_.check_q(b, "b");
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / resolution)));
  TorquePeak peak;
  peak.saturation = -1.0;
  Eigen::VectorXd qi(a.size());
  for (int s = 0; s <= steps; ++s) {
    const double u = static_cast<double>(s) / steps;
    qi = (1.0 - u) * a + u * b;
    model_.forward(leg_, qi, ws_);
    const TorquePeak t = evaluate(false);
    if (t.saturation > peak.saturation) peak = t;
  }
  return peak;
}

TorquePeak StanceTorques::lifted_path(const Eigen::Ref<const Eigen::MatrixXd>& path, double resolution) {
  require(path.rows() == model_.joints_per_leg() && path.cols() >= 1 && path.allFinite(),
          "StanceTorques.lifted_path: path must be finite, joints x waypoints (at least one)");
  if (path.cols() == 1) return lifted(path.col(0));
  TorquePeak peak;
  peak.saturation = -1.0;
  for (Eigen::Index c = 0; c + 1 < path.cols(); ++c) {
    const TorquePeak t = lifted_segment(path.col(c), path.col(c + 1), resolution);
    if (t.saturation > peak.saturation) peak = t;
  }
  return peak;
}

}  // namespace ernest::footfall
