#include "ernest/envs/terrain_source.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace ernest::envs {

Eigen::Matrix3d box_rotation(const dynamics::BoxObstacle& b) {
  return (Eigen::AngleAxisd(b.yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(b.pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(b.roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

TerrainHeightSource::TerrainHeightSource(const dynamics::HeightMap& terrain,
                                         const std::vector<dynamics::BoxObstacle>& obstacles)
    : terrain_(terrain) {
  boxes_.reserve(obstacles.size());
  for (const auto& o : obstacles) {
    Box b;
    b.rt = box_rotation(o).transpose();
    b.centre = o.centre;
    b.half = 0.5 * o.size;
    b.reach = b.half.norm();
    boxes_.push_back(b);
  }
}

bool TerrainHeightSource::height(double x, double y, double& z) const {
  z = terrain_.height(x, y);
  for (const Box& b : boxes_) {
    if (std::abs(x - b.centre.x()) > b.reach || std::abs(y - b.centre.y()) > b.reach) continue;
    // Line p(t) = (x, y, t) in box coordinates: q(t) = rt (p(t) - c) = q0 + t d, d = rt e_z.
    const Eigen::Vector3d q0 = b.rt * (Eigen::Vector3d(x, y, 0.0) - b.centre);
    const Eigen::Vector3d d = b.rt.col(2);
    double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
    bool hit = true;
    for (int k = 0; k < 3 && hit; ++k) {
      if (std::abs(d[k]) < 1e-12) {
        hit = std::abs(q0[k]) <= b.half[k];
      } else {
        double t1 = (-b.half[k] - q0[k]) / d[k], t2 = (b.half[k] - q0[k]) / d[k];
        if (t1 > t2) std::swap(t1, t2);
        lo = std::max(lo, t1);
        hi = std::min(hi, t2);
        hit = lo <= hi;
      }
    }
    if (hit) z = std::max(z, hi);  // hi = the top of the box along the vertical line
  }
  return true;
}

}  // namespace ernest::envs
