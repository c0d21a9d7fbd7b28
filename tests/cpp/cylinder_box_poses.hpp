// Shared by the cylinder–box tests (test_dynamics_cylinder_box*.cpp): the rover's wheel, the exact
// contact of a pose, and random wheel–rock poses.
#pragma once

#include <Eigen/Geometry>
#include <random>

#include "ernest/dynamics/cylinder_box.hpp"
#include "ernest/dynamics/rover_parameters.hpp"

namespace cylinder_box_poses {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using ernest::dynamics::detail::CylinderBoxContact;

inline const double kR = ernest::dynamics::RoverParameters{}.wheel_radius;
inline const double kHl = 0.5 * ernest::dynamics::RoverParameters{}.wheel_width;
inline const Vec3 kY = Vec3::UnitY();

inline bool contact(const Vec3& c, const Vec3& u, const Vec3& b, const Mat3& rb, const Vec3& e,
                    CylinderBoxContact& out) {
  return ernest::dynamics::detail::cylinder_box_contact(c, u, kR, kHl, b, rb, e, out);
}

inline Mat3 rot(double angle, const Vec3& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

struct Pose {
  Vec3 c, u, b, e;
  Mat3 rb;
};

// Wheel-sized cylinders near rock-sized boxes in any orientation, or the rover's (axle within 6
// deg of horizontal, yawed within 11 deg, yawed rocks; benchmarks/profile_cylinder_box's).
inline Pose random_pose(std::mt19937& rng, bool any_axis) {
  std::uniform_real_distribution<double> uni(-1.0, 1.0), size(0.04, 0.2);
  Pose p;
  p.e = Vec3(size(rng), size(rng), size(rng));
  p.b = Vec3(0.1 * uni(rng), 0.1 * uni(rng), 0.1 * uni(rng));
  p.rb = Eigen::Quaterniond(Eigen::Vector4d(uni(rng), uni(rng), uni(rng), uni(rng)).normalized())
             .toRotationMatrix();
  if (any_axis) {
    p.u = Vec3(uni(rng), uni(rng), uni(rng)).normalized();
  } else {
    p.rb = rot(3.14 * uni(rng), Vec3::UnitZ());
    p.u = rot(0.2 * uni(rng), Vec3::UnitZ()) * rot(0.1 * uni(rng), Vec3::UnitX()) * kY;
  }
  p.c = p.b + Vec3(0.4 * uni(rng), 0.4 * uni(rng), 0.3 * uni(rng));
  return p;
}

// The overlap of the pose along a world direction n.
inline double overlap(const Pose& p, const Vec3& n) {
  return ernest::dynamics::detail::cylinder_box_overlap(
      p.rb.transpose() * n, p.rb.transpose() * (p.c - p.b), p.rb.transpose() * p.u, kR, kHl, p.e);
}

}  // namespace cylinder_box_poses
