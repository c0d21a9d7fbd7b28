// Kinematics and statics of a wheel-on-leg walker (seed 003 §2.3, §5.3): forward kinematics of
// each leg, contact Jacobians, joint torques from contact forces plus link gravity
// (tau = J^T f + g(q)), margins to saturation (Figs 15–16), whole-robot centre of mass and
// contact points, and the collision capsules of every link. Model/workspace split: WalkerModel is
// immutable after construction (thread-safe); LegWorkspace holds the preallocated frames that
// forward() fills, so evaluation in a loop never allocates.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ernest/walker/walker_parameters.hpp"

namespace ernest::walker {

class WalkerModel;

/// Frames of one leg in the body frame, filled by WalkerModel::forward (preallocated).
struct LegWorkspace {
  explicit LegWorkspace(const WalkerModel& model);
  Eigen::Matrix3Xd joint_position;  ///< origin of joint i [m]
  Eigen::Matrix3Xd joint_axis;      ///< unit axis of joint i
  Eigen::Matrix3Xd link_com;        ///< centre of mass of link i [m]
  Eigen::Matrix3Xd rotation;        ///< 3 × 3n: orientation of joint frame i (rotated by q_i)
  Eigen::Matrix3d foot_rotation;    ///< foot frame F (z_F up the leg, y_F the axle)
  Eigen::Vector3d wheel_centre;     ///< origin of F [m]
  Eigen::Vector3d contact;          ///< wheel centre − wheel_radius · z_F [m]
};

/// One collision capsule in the body (or world) frame; `link` is the joint index, or -1 for the
/// wheel (a capsule along the axle) — the chassis is WalkerModel::chassis_cylinder.
struct LinkCapsule {
  int leg = 0;
  int link = 0;
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

class WalkerModel {
 public:
  /// Validates the parameters and computes the standard configuration (every wheel upright on
  /// flat ground at standard_foot_radius, hips at standard_height; knees up, the solution
  /// closest to a spider stance). Throws std::invalid_argument when the parameters are invalid
  /// or the standard stance is unreachable.
  explicit WalkerModel(const WalkerParameters& params);

  const WalkerParameters& params() const { return p_; }
  int legs() const { return p_.legs; }
  int joints_per_leg() const { return n_; }
  /// Hip mount of a leg in the body frame (origin on the first joint axis, x radially out).
  const Eigen::Isometry3d& hip_mount(int leg) const;
  /// Joint limits and torque limits of one leg (same for all legs).
  const Eigen::VectorXd& lower_limits() const { return lower_; }
  const Eigen::VectorXd& upper_limits() const { return upper_; }
  const Eigen::VectorXd& torque_limits() const { return torque_limit_; }
  /// Standard configuration: joints × legs, and the body pose over flat ground (z = 0).
  const Eigen::MatrixXd& standard_configuration() const { return q_standard_; }
  Eigen::Isometry3d standard_body_pose() const;

  /// Fills ws with every frame of `leg` at joint angles q (body frame). Does not allocate.
  void forward(int leg, const Eigen::Ref<const Eigen::VectorXd>& q, LegWorkspace& ws) const;
  /// Foot frame F (origin at the wheel centre) in the body frame.
  Eigen::Isometry3d foot_pose(int leg, const Eigen::Ref<const Eigen::VectorXd>& q) const;
  /// Wheel contact point in the body frame: the rim point below the centre along -z_F (the lowest
  /// point of the wheel whenever the wheel is upright, as FootFall places it).
  Eigen::Vector3d contact_point(int leg, const Eigen::Ref<const Eigen::VectorXd>& q) const;

  /// Contact Jacobian (3 × n, body frame): d contact_point / d q, from the frames in ws (after
  /// forward()). Column i = axis_i × (contact − joint_i).
  void contact_jacobian(const LegWorkspace& ws, Eigen::Ref<Eigen::Matrix3Xd> J) const;
  /// Geometric Jacobian of the foot frame (6 × n: wheel-centre velocity over angular velocity).
  void foot_jacobian(const LegWorkspace& ws, Eigen::Ref<Eigen::MatrixXd> J) const;
  /// Gravity torques g(q) = dV/dq (V the potential energy of the leg's links) for a gravity
  /// vector given in the body frame: the torques the joints must supply to hold the leg.
  void gravity_torques(const LegWorkspace& ws, const Eigen::Vector3d& gravity_body,
                       Eigen::Ref<Eigen::VectorXd> tau) const;
  /// Static joint torques tau = J^T f + g(q), f = -reaction the force the wheel applies to the
  /// ground; `reaction` is the ground's force on the wheel (body frame), as Fig. 16 draws it.
  void joint_torques(const LegWorkspace& ws, const Eigen::Vector3d& reaction,
                     const Eigen::Vector3d& gravity_body, Eigen::Ref<Eigen::VectorXd> tau) const;
  /// Convenience: forward + joint_torques, gravity from the body's world rotation.
  Eigen::VectorXd joint_torques(int leg, const Eigen::Ref<const Eigen::VectorXd>& q,
                                const Eigen::Vector3d& reaction,
                                const Eigen::Matrix3d& body_rotation = Eigen::Matrix3d::Identity()) const;
  /// |tau_i| / torque_limit_i per joint (1 = saturation, as Figs 15–16 plot it).
  Eigen::VectorXd saturation(const Eigen::Ref<const Eigen::VectorXd>& tau) const;
  /// 1 − max_i |tau_i| / torque_limit_i (negative when a joint is beyond its limit).
  double margin_to_saturation(const Eigen::Ref<const Eigen::VectorXd>& tau) const;

  /// Gravity vector in the body frame for a body with world rotation R (world z up).
  Eigen::Vector3d gravity_in_body(const Eigen::Matrix3d& body_rotation) const;
  /// Whole-robot centre of mass in the world for a body pose and q (joints × legs).
  Eigen::Vector3d center_of_mass(const Eigen::Isometry3d& body,
                                 const Eigen::Ref<const Eigen::MatrixXd>& q) const;
  /// Contact points of every leg in the world (3 × legs).
  Eigen::Matrix3Xd contact_points(const Eigen::Isometry3d& body,
                                  const Eigen::Ref<const Eigen::MatrixXd>& q) const;

  /// Collision capsules of one leg's links (and its wheel) in the body frame.
  std::vector<LinkCapsule> leg_capsules(int leg, const Eigen::Ref<const Eigen::VectorXd>& q) const;
  /// Every leg's capsules transformed by the body pose (world frame).
  std::vector<LinkCapsule> capsules(const Eigen::Isometry3d& body,
                                    const Eigen::Ref<const Eigen::MatrixXd>& q) const;

  /// Input checks for run-time arguments (std::invalid_argument naming the field).
  void check_leg(int leg) const;
  void check_q(const Eigen::Ref<const Eigen::VectorXd>& q, const char* field = "q") const;
  void check_configuration(const Eigen::Ref<const Eigen::MatrixXd>& q, const char* field = "q") const;
  /// True when every joint is within its limits (with a tolerance in rad).
  bool within_limits(const Eigen::Ref<const Eigen::VectorXd>& q, double tolerance = 1e-9) const;

 private:
  WalkerParameters p_;
  int n_ = 0;
  std::vector<Eigen::Isometry3d> mounts_;
  Eigen::VectorXd lower_, upper_, torque_limit_;
  Eigen::MatrixXd q_standard_;
};

/// Foot frame target for an upright wheel: contact point c (body frame), wheel heading (rolling
/// direction angle about `up`, from +x), `up` the ground normal in the body frame.
Eigen::Isometry3d upright_foot_pose(const WalkerModel& model, const Eigen::Vector3d& contact,
                                    double heading, const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

}  // namespace ernest::walker
