// Static joint torques of a FootFall stance as one leg steps (seed 003 §7.1: "footfalls would be
// identified which were reachable and safely kept the CG within the polygon of support, but which
// violated joint-torque limits"). For a stance (body pose, the other legs' angles fixed) and the
// swing leg's angles: the zero-interaction force distribution over the loaded feet (§5.1.1,
// statics::zero_interaction_forces), every joint's torque tau = J^T f + g(q) (§5.3.2–5.3.3,
// walker::WalkerModel::joint_torques) and the peak |tau| / limit over all legs (Figs 15–16). Two
// stances: the swing foot down on its contact (after the step) and the swing leg in the air (during
// it: the other feet carry the robot, the swing leg only its own links). The fixed legs' Jacobians
// and gravity torques are computed once, so one evaluation costs a force distribution and a few
// 3 × n products. The answer equals walker::stance_loads' peak_saturation (test).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "ernest/walker/walker_model.hpp"

namespace ernest::footfall {

/// Peak of |tau| / torque limit over every joint of every leg, and where it is.
struct TorquePeak {
  double saturation = 0.0;  ///< 1 = a joint at its torque limit
  int leg = -1, joint = -1;
};

/// Evaluates the stance's joint torques for angles of the swing leg. Not thread-safe (holds a
/// workspace); cheap to construct (one forward kinematics per leg).
class StanceTorques {
 public:
  /// body: pose in the world; q: joints × legs (the swing column is replaced per evaluation).
  StanceTorques(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                const Eigen::Ref<const Eigen::MatrixXd>& q, int leg);

  /// Every foot down, the swing leg's wheel on the contact of q_leg (after the step).
  TorquePeak down(const Eigen::Ref<const Eigen::VectorXd>& q_leg);
  /// The swing leg in the air at q_leg, the other feet carry the robot (during the step).
  TorquePeak lifted(const Eigen::Ref<const Eigen::VectorXd>& q_leg);
  /// Peak of lifted() along the straight joint-space segment a -> b, sampled every `resolution`
  /// rad (both ends included).
  TorquePeak lifted_segment(const Eigen::Ref<const Eigen::VectorXd>& a,
                            const Eigen::Ref<const Eigen::VectorXd>& b, double resolution);
  /// Peak of lifted() along a path (joints × waypoints), each edge sampled every `resolution` rad.
  TorquePeak lifted_path(const Eigen::Ref<const Eigen::MatrixXd>& path, double resolution);

  int leg() const { return leg_; }
  long evaluations() const { return evaluations_; }

 private:
  TorquePeak evaluate(bool swing_down);
  const walker::WalkerModel& model_;
  Eigen::Isometry3d body_;
  int leg_;
  walker::LegWorkspace ws_;
  Eigen::Vector3d gravity_, gravity_body_, rest_moment_;
  double total_mass_ = 0.0;
  Eigen::Matrix3Xd contacts_;             // world; the swing column replaced per evaluation
  Eigen::Matrix3Xd loaded_;               // the other legs' contacts (lifted stance)
  std::vector<Eigen::MatrixXd> force_to_tau_;  // per leg: n × 3, tau = g + A f (f: world reaction)
  Eigen::MatrixXd gravity_tau_;           // n × legs (the swing column recomputed)
  Eigen::Matrix3Xd forces_all_, forces_loaded_;
  Eigen::VectorXd tau_;
  Eigen::Matrix3Xd jacobian_;
  long evaluations_ = 0;
};

}  // namespace ernest::footfall
