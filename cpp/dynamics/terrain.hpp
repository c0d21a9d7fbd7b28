// Terrain of the simulator: a height map (bilinear height and normal, seed 004 §3.1 DEM h = f(x, y))
// covered by soft soil or rigid ground, and rigid box obstacles (rocks, steps; §3.4).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace ernest::dynamics {

/// Regular grid of heights: heights(i, j) is the ground height at
/// (origin_x + i * spacing, origin_y + j * spacing). Queries outside the grid use the nearest
/// edge value (the terrain continues flat beyond its border).
class HeightMap {
 public:
  HeightMap(Eigen::MatrixXd heights, double spacing, double origin_x, double origin_y);

  /// Flat ground at height z covering [x0, x0 + length] x [y0, y0 + width].
  static HeightMap flat(double length, double width, double spacing, double z = 0.0,
                        double x0 = -5.0, double y0 = -5.0);
  /// Plane rising along +x with the given slope angle [rad] (z = tan(angle) * x), on
  /// [x0, x0 + length] x [y0, y0 + width].
  static HeightMap slope(double angle, double length, double width, double spacing,
                         double x0 = -5.0, double y0 = -5.0);

  /// Bilinear interpolation of the grid.
  double height(double x, double y) const;
  /// Unit upward normal of the bilinear surface (from its exact gradient).
  Eigen::Vector3d normal(double x, double y) const;
  /// Height and gradient in one call.
  double height_gradient(double x, double y, double& dhdx, double& dhdy) const;
  /// Height and unit upward normal in one call.
  double height_normal(double x, double y, Eigen::Vector3d& n) const;

  const Eigen::MatrixXd& heights() const { return heights_; }
  double spacing() const { return spacing_; }
  double origin_x() const { return origin_x_; }
  double origin_y() const { return origin_y_; }
  double length_x() const { return spacing_ * static_cast<double>(heights_.rows() - 1); }
  double length_y() const { return spacing_ * static_cast<double>(heights_.cols() - 1); }

 private:
  Eigen::MatrixXd heights_;
  double spacing_, origin_x_, origin_y_;
  double inv_spacing_;  // queries multiply: they run 12+ times per wheel per step
};

/// Rigid box obstacle: centre, full sizes and yaw/pitch/roll (Z-Y-X) orientation [rad].
struct BoxObstacle {
  Eigen::Vector3d centre{0.0, 0.0, 0.0};
  Eigen::Vector3d size{0.2, 0.2, 0.2};
  double yaw = 0.0, pitch = 0.0, roll = 0.0;
  void validate() const;
};

enum class GroundType { Soil, Rigid };

}  // namespace ernest::dynamics
