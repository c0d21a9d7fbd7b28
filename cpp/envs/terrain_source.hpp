// Heights seen by the elevation samples in simulation: the height map and, on top of it, the rigid
// obstacles (the simulator's stand-in for the stereo elevation map of seed 004 §2.4).
#pragma once

#include <vector>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/sensing/elevation_sampler.hpp"

namespace ernest::envs {

class TerrainHeightSource : public sensing::HeightSource {
 public:
  /// Keeps references: terrain and obstacles must outlive the source.
  TerrainHeightSource(const dynamics::HeightMap& terrain,
                      const std::vector<dynamics::BoxObstacle>& obstacles);
  /// max(height map, top of every box above (x, y)); the top of a tilted box is found exactly by
  /// intersecting the vertical line with the oriented box (slab method). Always has data.
  bool height(double x, double y, double& z) const override;

 private:
  struct Box {
    Eigen::Matrix3d rt;  // world-to-box rotation
    Eigen::Vector3d centre, half;
    double reach;        // horizontal bounding radius, for a cheap rejection
  };
  const dynamics::HeightMap& terrain_;
  std::vector<Box> boxes_;
};

/// Rotation of a box from its yaw/pitch/roll (Z-Y-X), box frame to world.
Eigen::Matrix3d box_rotation(const dynamics::BoxObstacle& b);

}  // namespace ernest::envs
