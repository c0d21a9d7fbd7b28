#include "ernest/perception/camera.hpp"

#include <cmath>

#include "ernest/common/validation.hpp"

namespace ernest::perception {

void StereoCameraParameters::validate() const {
  const char* o = "StereoCameraParameters";
  require_in_range(o, "width", width, 16, 8192);
  require_in_range(o, "height", height, 16, 8192);
  require_in_range(o, "horizontal_fov", horizontal_fov, 0.1, 3.0);
  require_in_range(o, "baseline", baseline, 0.01, 2.0);
  require(mount_position.allFinite(), "StereoCameraParameters.mount_position must be finite");
  require_in_range(o, "mount_pitch", mount_pitch, -1.5, 1.5);
}

double StereoCameraParameters::focal() const {
  return 0.5 * width / std::tan(0.5 * horizontal_fov);
}

Eigen::Matrix3d StereoCameraParameters::chassis_from_camera() const {
  const double c = std::cos(mount_pitch), s = std::sin(mount_pitch);
  Eigen::Matrix3d r;
  // optical axis forward and down; image x to the chassis' right; image y = z × x (down-ish)
  r.col(2) = Eigen::Vector3d(c, 0.0, -s);
  r.col(0) = Eigen::Vector3d(0.0, -1.0, 0.0);
  r.col(1) = r.col(2).cross(r.col(0));
  return r;
}

Eigen::Isometry3d StereoCameraParameters::camera_pose(const Eigen::Vector3d& chassis_position,
                                                      const Eigen::Matrix3d& chassis_rotation,
                                                      int which) const {
  require_in_range("StereoCameraParameters.camera_pose", "which", which, 0, 1);
  const Eigen::Matrix3d rc = chassis_from_camera();
  // left camera half a baseline to the left (-x_cam), right camera half to the right
  const Eigen::Vector3d offset = (which == 0 ? -0.5 : 0.5) * baseline * rc.col(0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = chassis_rotation * rc;
  pose.translation() = chassis_position + chassis_rotation * (mount_position + offset);
  return pose;
}

}  // namespace ernest::perception
