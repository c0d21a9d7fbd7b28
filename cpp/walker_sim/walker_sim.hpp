// The wheel-on-leg walker in ODE (beyond seed 003: executing FootFall's plans in simulation, the
// check §4.1's Moses Lake lesson calls for). Chassis and every link of every leg are ODE bodies
// (inertias of cpp/walker's model); each joint is an ODE hinge driven to its target angle by the
// hinge's velocity motor (dParamVel from a P law on the angle error plus the path's rate, dParamFMax
// a multiple of the joint's torque limit) — ODE solves the motor implicitly, so a stiff gain is
// stable. The wheel is rigid on the foot link (braked while walking). Compliance sits in the wheel
// contacts only, as seed 003 §5.1.1 models SDM-B (Fig. 9, eq 3): one contact per wheel at its
// lowest rim point whose normal row is a linear spring k_zz and damper c, set through ODE's contact
// ERP and CFM, ERP = h k / (h k + c), CFM = 1 / (h k + c) (ODE manual, "How do I make a
// spring/damper with ERP and CFM"); tangentially the wheel sticks (Coulomb friction, ODE's
// friction pyramid), the limit k_xx, k_yy -> inf of eq 3. Terrain: the plane z = 0 and rocks as
// boxes (ODE's cylinder–box collider, called directly with dCollide: no callback runs).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <stdexcept>
#include <vector>

#include "ernest/walker/walker_model.hpp"

namespace ernest::walker_sim {

/// A rock: a box on the ground (z = 0 plane), yawed about the vertical.
struct Rock {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();         ///< world [m]
  Eigen::Vector3d half_extents = Eigen::Vector3d::Constant(0.1);  ///< [m] (> 0)
  double yaw = 0.0;                                         ///< [rad]
  void validate() const;
};

struct WalkerSimOptions {
  double dt = 0.005;                ///< physics step [s], (0, 0.05]
  double contact_stiffness = 6e4;   ///< k_zz of each wheel [N/m] (seed 003 eq 3; walker_statics' SDM-B tyre)
  double contact_damping = 8e3;     ///< normal damper of each wheel [N s/m] (ours: about critical for 1/6 of SDM-B)
  double friction = 1.0;            ///< Coulomb coefficient wheel–ground and wheel–rock, [0, 10]
  double rock_stiffness = 2e6;      ///< wheel–rock contact spring [N/m] (a stiff rock)
  double rock_damping = 2e4;        ///< [N s/m]
  double position_gain = 25.0;      ///< joint rate command per rad of error [1/s], (0, 1000]
  double max_joint_rate = 2.0;      ///< clamp of the commanded joint rate [rad/s], (0, 100]
  double torque_scale = 4.0;        ///< motor force limit = this × the joint's torque limit, (0, 100]
  double min_link_mass = 0.5;       ///< lighter links get this mass in ODE [kg], (0, 100]
  /// Throws std::invalid_argument naming the field.
  void validate() const;
};

/// Thrown when the state stops being finite or a body flies off (ODE internal errors included).
class WalkerSimDiverged : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Signed distance of a wheel (a cylinder: centre, axle, radius, width) to a rock [m]: the
/// separation, or minus the penetration depth (FCL) when they overlap.
double wheel_rock_clearance(const Eigen::Vector3d& centre, const Eigen::Vector3d& axle, double radius,
                            double width, const Rock& rock);
/// Height of a wheel's lowest rim point over the ground plane z = 0 (negative when sunk) [m].
double wheel_ground_clearance(const Eigen::Vector3d& centre, const Eigen::Vector3d& axle, double radius);

class WalkerSim {
 public:
  /// Builds the robot at body pose `body` and configuration q (joints × legs) over flat ground with
  /// `rocks`. The model must outlive the simulator. Throws std::invalid_argument for bad input.
  WalkerSim(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
            const Eigen::Ref<const Eigen::MatrixXd>& q, const std::vector<Rock>& rocks = {},
            const WalkerSimOptions& options = {});
  ~WalkerSim();
  WalkerSim(const WalkerSim&) = delete;
  WalkerSim& operator=(const WalkerSim&) = delete;

  const walker::WalkerModel& model() const;
  const WalkerSimOptions& options() const;
  const std::vector<Rock>& rocks() const;
  double time() const;
  /// One physics step towards the joint targets (joints × legs) with feed-forward rates (same
  /// shape; empty = zero). Throws WalkerSimDiverged on a non-finite or runaway state.
  void step(const Eigen::Ref<const Eigen::MatrixXd>& q_target,
            const Eigen::Ref<const Eigen::MatrixXd>& rate = Eigen::MatrixXd());
  /// Holds the targets for `seconds` (settling).
  void hold(const Eigen::Ref<const Eigen::MatrixXd>& q_target, double seconds);

  /// Chassis frame (the model's body frame) in the world.
  Eigen::Isometry3d body_pose() const;
  /// Measured joint angles (joints × legs).
  Eigen::MatrixXd joint_angles() const;
  /// Wheel centres and axles in the world (3 × legs).
  Eigen::Matrix3Xd wheel_centres() const;
  Eigen::Matrix3Xd wheel_axles() const;
  /// Normal force of each wheel's ground spring in the last step [N] (0 in the air).
  Eigen::VectorXd wheel_loads() const;
  /// Clearance of one wheel to the nearest rock (+inf without rocks) and to the ground [m].
  double rock_clearance(int leg) const;
  double ground_clearance(int leg) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ernest::walker_sim
