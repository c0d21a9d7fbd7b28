// Parameters of an ATHLETE-class wheel-on-leg hexapod (seed 003 §2.3): a hexagonal chassis with
// six identical serial legs of revolute joints, each ending in a wheel. The paper gives no full
// parameter set; sdm_b_parameters() and t12_parameters() document, field by field, what comes from
// the paper, what is public ATHLETE knowledge, and what is our assumption.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <string>
#include <vector>

namespace ernest::walker {

/// Capsule (segment p0–p1 swept by a sphere of `radius`) in the frame it is attached to.
struct Capsule {
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();
  double radius = 0.0;  ///< [m]; 0 means "no collision geometry"
};

/// One revolute joint and the rigid link it moves (up to the next joint).
/// Frames: joint i's frame is its parent's frame moved by `offset` (no rotation at q = 0), then
/// rotated by q_i about `axis`. Link quantities are in joint i's (rotated) frame.
struct JointSpec {
  std::string name;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< from the previous joint (or the hip mount) [m]
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();   ///< unit rotation axis
  double lower = -3.14159;        ///< joint limit [rad]
  double upper = 3.14159;         ///< joint limit [rad]
  double torque_limit = 1000.0;   ///< |tau| at saturation [N m]
  double mass = 1.0;              ///< link mass [kg]
  Eigen::Vector3d com = Eigen::Vector3d::Zero();       ///< link centre of mass [m]
  Eigen::Vector3d inertia = Eigen::Vector3d::Ones();   ///< principal inertia about the CoM [kg m^2]
  Capsule geometry;               ///< collision capsule of the link
};

/// The whole robot. Body frame B: origin at the centre of the hexagon in the plane of the hip
/// joints, z up, leg 0 mounted on +x, legs numbered counter-clockwise every 360°/legs.
struct WalkerParameters {
  std::string name = "walker";
  int legs = 6;
  double hip_radius = 1.3;        ///< body centre to each leg's first joint axis [m]
  double chassis_mass = 370.0;    ///< [kg]
  Eigen::Vector3d chassis_com = Eigen::Vector3d::Zero();    ///< in B [m]
  Eigen::Vector3d chassis_inertia = Eigen::Vector3d::Ones();  ///< principal, about the CoM [kg m^2]
  double chassis_collision_radius = 1.4;     ///< hex ring as a bounding cylinder [m]
  double chassis_collision_half_height = 0.2;  ///< [m]
  std::vector<JointSpec> joints;  ///< one leg, hip to wheel (all legs identical)
  /// Wheel centre in the last joint's frame [m]. The foot frame F sits there with its axes given by
  /// `foot_rotation` (columns = F's axes in the last joint frame): z_F points from the wheel centre
  /// back up the leg, y_F is the wheel axle, x_F the rolling direction.
  Eigen::Vector3d foot_offset = Eigen::Vector3d(0.3, 0.0, 0.0);
  Eigen::Matrix3d foot_rotation = Eigen::Matrix3d::Identity();
  double wheel_radius = 0.35;     ///< [m]
  double wheel_width = 0.25;      ///< [m]
  double standard_height = 1.75;  ///< hip plane above flat ground in the standard pose [m]
  double standard_foot_radius = 2.05;  ///< body axis to wheel contact in the standard pose [m]
  double gravity = 9.81;          ///< [m/s^2]

  /// Throws std::invalid_argument naming the first field outside its allowed range.
  void validate() const;
  int joints_per_leg() const { return static_cast<int>(joints.size()); }
  double total_mass() const;
};

/// SDM-B, the first-generation ATHLETE of seed 003 §3–5 (six 6-DOF legs). See the .cpp for where
/// every value comes from.
WalkerParameters sdm_b_parameters();
/// T12 (Tri-ATHLETE pair, seed 003 §5.1.3): seven joints per leg, standard height 2.15 m (§5.1.4).
WalkerParameters t12_parameters();

}  // namespace ernest::walker
