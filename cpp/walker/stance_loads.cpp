#include "ernest/walker/stance_loads.hpp"

#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/statics/force_distribution.hpp"
#include "ernest/statics/stability.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::walker {

StanceLoads stance_loads(const WalkerModel& model, const Eigen::Isometry3d& body,
                         const Eigen::Ref<const Eigen::MatrixXd>& q, const std::vector<int>& lifted) {
  model.check_configuration(q);
  require(body.matrix().allFinite(), "body pose is not finite");
  const int legs = model.legs(), n = model.joints_per_leg();
  std::vector<bool> up(legs, false);
  for (int leg : lifted) {
    require(leg >= 0 && leg < legs, "lifted leg " + std::to_string(leg) + " is outside [0, " +
                                        std::to_string(legs - 1) + "]");
    require(!up[leg], "lifted leg " + std::to_string(leg) + " is listed twice");
    up[leg] = true;
  }
  StanceLoads out;
  out.loaded = legs - static_cast<int>(lifted.size());
  require(out.loaded >= 3, "stance_loads needs at least three legs on the ground, got " +
                               std::to_string(out.loaded));
  const WalkerParameters& p = model.params();
  const Eigen::Vector3d gravity(0.0, 0.0, -p.gravity);
  out.center_of_mass = model.center_of_mass(body, q);
  const Eigen::Matrix3Xd all = model.contact_points(body, q);
  Eigen::Matrix3Xd contacts(3, out.loaded), forces(3, out.loaded);
  for (int k = 0, c = 0; k < legs; ++k)
    if (!up[k]) contacts.col(c++) = all.col(k);
  // §5.1.1: the minimum-norm (zero-interaction) solution of the six equilibrium equations.
  const statics::DistributionInfo info = statics::zero_interaction_forces(
      contacts, out.center_of_mass, p.total_mass(), gravity, forces);
  out.equilibrium_residual = info.residual;
  const statics::ProjectionFrame frame = statics::ProjectionFrame::from_gravity(gravity);
  out.support_margin = statics::static_stability_margin(statics::support_polygon(contacts, frame),
                                                        out.center_of_mass, frame);

  out.reactions.setZero(3, legs);
  out.torques.resize(n, legs);
  LegWorkspace ws(model);
  const Eigen::Matrix3d rt = body.linear().transpose();
  const Eigen::Vector3d g_body = rt * gravity;
  double total = 0.0;
  for (int k = 0, c = 0; k < legs; ++k) {
    if (!up[k]) out.reactions.col(k) = forces.col(c++);
    model.forward(k, q.col(k), ws);
    model.joint_torques(ws, rt * out.reactions.col(k), g_body, out.torques.col(k));
    if (!up[k]) {
      const double f = out.reactions.col(k).norm();
      out.peak_force = std::max(out.peak_force, f);
      total += f;
    }
  }
  out.mean_force = total / out.loaded;
  out.saturation = out.torques.cwiseAbs().cwiseQuotient(model.torque_limits().replicate(1, legs));
  out.peak_saturation = out.saturation.maxCoeff(&out.peak_joint, &out.peak_leg);
  return out;
}

Eigen::MatrixXd lift_legs(const WalkerModel& model, const Eigen::Isometry3d& body,
                          const Eigen::Ref<const Eigen::MatrixXd>& q, const std::vector<int>& legs,
                          double height) {
  model.check_configuration(q);
  require_finite("lift_legs", "height", height);
  Eigen::MatrixXd out = q;
  LegIk ik(model);
  const Eigen::Vector3d up = body.linear().transpose() * Eigen::Vector3d::UnitZ();
  for (int leg : legs) {
    require(leg >= 0 && leg < model.params().legs,
            "lift_legs: legs holds " + std::to_string(leg) + ", outside [0, " +
                std::to_string(model.params().legs - 1) + "]");
    const Eigen::Isometry3d foot = model.foot_pose(leg, q.col(leg));
    Eigen::Isometry3d target = foot;
    target.translation() += height * up;
    const IkResult r = ik.solve(leg, target, q.col(leg));
    require(r.status == IkStatus::kSolved,
            "lift_legs: leg " + std::to_string(leg) + " cannot be raised by " + std::to_string(height) + " m");
    out.col(leg) = r.solutions.front();
  }
  return out;
}

}  // namespace ernest::walker
