// The stereo mapping pipeline of seed 004 §2.4 / Fig. 3 in simulation: at the fusion rate (0.5 Hz)
// render the two masthead cameras from the chassis pose, match them (StereoBM), back-project the
// disparity and fuse the cloud into the robot-centric elevation map; every update re-centres the
// map on the robot. The map then serves the elevation samples of §4.2 (it is a HeightSource).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/perception/camera.hpp"
#include "ernest/perception/elevation_map.hpp"
#include "ernest/perception/raycaster.hpp"
#include "ernest/perception/stereo_matcher.hpp"

namespace ernest::perception {

struct StereoMapperOptions {
  StereoCameraParameters camera{};
  RenderOptions render{};
  StereoMatcherOptions matcher{};
  ElevationMapOptions map{};
  double fusion_rate = 0.5;  ///< [Hz] (§2.4: point clouds fused at 0.5 Hz)
  double max_depth = 8.0;    ///< points deeper than this are not fused [m]
  void validate() const;
};

/// One stereo frame, kept for debug views.
struct StereoFrame {
  GrayImage left, right;
  FloatImage depth;      ///< exact depth of the left camera [m]
  FloatImage disparity;  ///< matched disparity [px], NaN where none
  PointCloud cloud;      ///< left camera frame
  Eigen::Isometry3d left_pose = Eigen::Isometry3d::Identity();
  FuseStats stats{};
};

class StereoMapper {
 public:
  /// Copies the scene into its ray caster.
  StereoMapper(const dynamics::HeightMap& terrain, const std::vector<dynamics::BoxObstacle>& boxes,
               const StereoMapperOptions& options = {});

  /// Re-centres the map on the chassis; when at least 1 / fusion_rate has passed since the last
  /// fusion (or none happened yet), captures and fuses a frame. Returns whether it fused.
  bool update(double time, const Eigen::Vector3d& chassis_position,
              const Eigen::Matrix3d& chassis_rotation);
  /// Captures and fuses one frame now.
  const StereoFrame& capture(const Eigen::Vector3d& chassis_position,
                             const Eigen::Matrix3d& chassis_rotation);
  /// Empties the map and the schedule (new episode on the same scene).
  void reset();

  const ElevationMap& map() const { return map_; }
  const StereoFrame& last_frame() const { return frame_; }
  const Raycaster& raycaster() const { return raycaster_; }
  const StereoMapperOptions& options() const { return options_; }
  std::uint64_t frames() const { return frames_; }

 private:
  StereoMapperOptions options_;
  Raycaster raycaster_;
  StereoMatcher matcher_;
  ElevationMap map_;
  StereoFrame frame_;
  std::uint64_t frames_ = 0;
  double last_fusion_ = 0.0;
};

}  // namespace ernest::perception
