// ERNEST's stereo camera pair (seed 004 §2.1.2, §2.4): two rectified pinhole cameras in the
// masthead, 1.30 m above the ground (Table 1), looking straight ahead and 30° down relative to the
// chassis horizontal (§2.1.2). The paper gives neither the baseline nor the intrinsics; the
// defaults below are ours (documented plausible values for a small-rover mast pair).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ernest::perception {

/// Intrinsics and mounting of a rectified stereo pair. Camera frame as OpenCV: x right, y down,
/// z forward (optical axis); pixel (u, v) has its centre at integer coordinates.
struct StereoCameraParameters {
  int width = 640;              ///< [px]
  int height = 480;             ///< [px]
  /// Horizontal field of view [rad] (ours: 75°, which with 640×480 gives a 60° vertical field, so
  /// the 30°-down masthead sees the ground from ~0.75 m ahead of the mast to the horizon).
  double horizontal_fov = 75.0 * 3.14159265358979323846 / 180.0;
  double baseline = 0.12;       ///< [m] (ours: a typical mast stereo pair)
  /// Midpoint between the two cameras in the chassis frame (x forward, y left, z up) [m]. Ours:
  /// above the front half of the chassis; z = 1.30 m masthead height (Table 1) minus the chassis
  /// origin's 0.17 m above the ground (wheel-axle height).
  Eigen::Vector3d mount_position{0.30, 0.0, 1.13};
  double mount_pitch = 30.0 * 3.14159265358979323846 / 180.0;  ///< downward tilt [rad] (§2.1.2)
  void validate() const;

  double focal() const;                 ///< f = (width / 2) / tan(hfov / 2) [px]
  double cx() const { return 0.5 * (width - 1); }
  double cy() const { return 0.5 * (height - 1); }
  /// Rotation camera -> chassis (columns: camera x, y, z axes in the chassis frame).
  Eigen::Matrix3d chassis_from_camera() const;
  /// World pose of the left (which = 0) or right (which = 1) camera from the chassis pose:
  /// p_world = rotation * p_cam + translation.
  Eigen::Isometry3d camera_pose(const Eigen::Vector3d& chassis_position,
                                const Eigen::Matrix3d& chassis_rotation, int which) const;
};

}  // namespace ernest::perception
