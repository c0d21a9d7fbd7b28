#include "ernest/perception/stereo_mapper.hpp"

#include "ernest/common/validation.hpp"

namespace ernest::perception {

void StereoMapperOptions::validate() const {
  camera.validate();
  render.validate();
  matcher.validate();
  map.validate();
  require_in_range("StereoMapperOptions", "fusion_rate", fusion_rate, 1e-3, 1000.0);
  require_in_range("StereoMapperOptions", "max_depth", max_depth, 0.1, 1000.0);
}

StereoMapper::StereoMapper(const dynamics::HeightMap& terrain,
                           const std::vector<dynamics::BoxObstacle>& boxes,
                           const StereoMapperOptions& options)
    : options_(options),
      raycaster_(terrain, boxes, options.render),
      matcher_(options.matcher),
      map_(options.map) {
  options_.validate();
}

void StereoMapper::reset() {
  map_.clear();
  frames_ = 0;
  last_fusion_ = 0.0;
}

bool StereoMapper::update(double time, const Eigen::Vector3d& chassis_position,
                          const Eigen::Matrix3d& chassis_rotation) {
  require_finite("StereoMapper.update", "time", time);
  require(chassis_position.allFinite() && chassis_rotation.allFinite(),
          "StereoMapper.update: chassis_position and chassis_rotation must be finite");
  map_.move_to(chassis_position.x(), chassis_position.y());
  // a small tolerance so that time steps summing to 1 / rate in floating point still trigger
  if (frames_ > 0 && time - last_fusion_ < 1.0 / options_.fusion_rate - 1e-9) return false;
  capture(chassis_position, chassis_rotation);
  last_fusion_ = time;
  return true;
}

const StereoFrame& StereoMapper::capture(const Eigen::Vector3d& chassis_position,
                                         const Eigen::Matrix3d& chassis_rotation) {
  require(chassis_position.allFinite() && chassis_rotation.allFinite(),
          "StereoMapper.capture: chassis_position and chassis_rotation must be finite");
  const auto& cam = options_.camera;
  map_.move_to(chassis_position.x(), chassis_position.y());
  frame_.left_pose = cam.camera_pose(chassis_position, chassis_rotation, 0);
  const Eigen::Isometry3d right_pose = cam.camera_pose(chassis_position, chassis_rotation, 1);
  raycaster_.render(frame_.left_pose, cam, 2 * frames_, frame_.left, frame_.depth);
  FloatImage unused;
  raycaster_.render(right_pose, cam, 2 * frames_ + 1, frame_.right, unused);
  frame_.disparity = matcher_.compute(frame_.left, frame_.right);
  frame_.cloud = disparity_to_points(frame_.disparity, cam, 0.5, options_.max_depth);
  frame_.stats = map_.fuse_cloud(frame_.cloud.points, frame_.left_pose, cam);
  ++frames_;
  return frame_;
}

}  // namespace ernest::perception
