// The simulator's terrain (terrain.hpp): height maps (flat, slope, from heights) with their
// bilinear height, gradient and normal, and the validation of box obstacles.
#include "ernest/dynamics/terrain.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "ernest/common/validation.hpp"

namespace ernest::dynamics {

HeightMap::HeightMap(Eigen::MatrixXd heights, double spacing, double origin_x, double origin_y)
    : heights_(std::move(heights)), spacing_(spacing), origin_x_(origin_x), origin_y_(origin_y),
      inv_spacing_(1.0 / spacing) {
  require_positive("HeightMap", "spacing", spacing);
  require_finite("HeightMap", "origin_x", origin_x);
  require_finite("HeightMap", "origin_y", origin_y);
  require(heights_.rows() >= 2 && heights_.cols() >= 2,
          "HeightMap: heights must be at least 2 x 2, got " + std::to_string(heights_.rows()) +
              " x " + std::to_string(heights_.cols()));
  require(heights_.allFinite(), "HeightMap: heights must all be finite");
}

HeightMap HeightMap::flat(double length, double width, double spacing, double z, double x0,
                          double y0) {
  require_positive("HeightMap.flat", "length", length);
  require_positive("HeightMap.flat", "width", width);
  require_positive("HeightMap.flat", "spacing", spacing);
  const int nx = std::max(2, static_cast<int>(std::ceil(length / spacing)) + 1);
  const int ny = std::max(2, static_cast<int>(std::ceil(width / spacing)) + 1);
  return HeightMap(Eigen::MatrixXd::Constant(nx, ny, z), spacing, x0, y0);
}

HeightMap HeightMap::slope(double angle, double length, double width, double spacing, double x0,
                           double y0) {
  require_in_range("HeightMap.slope", "angle", angle, -1.4, 1.4);
  HeightMap m = flat(length, width, spacing, 0.0, x0, y0);
  const double t = std::tan(angle);
  for (int i = 0; i < m.heights_.rows(); ++i) m.heights_.row(i).setConstant(t * (x0 + i * spacing));
  return m;
}

double HeightMap::height_gradient(double x, double y, double& dhdx, double& dhdy) const {
  const Eigen::Index nx = heights_.rows(), ny = heights_.cols();
  const double u = (x - origin_x_) * inv_spacing_, v = (y - origin_y_) * inv_spacing_;
  // Outside the grid the edge value continues (zero gradient across the border).
  const bool out_x = !(u >= 0.0 && u <= static_cast<double>(nx - 1));
  const bool out_y = !(v >= 0.0 && v <= static_cast<double>(ny - 1));
  const double uc = std::clamp(u, 0.0, static_cast<double>(nx - 1));
  const double vc = std::clamp(v, 0.0, static_cast<double>(ny - 1));
  Eigen::Index i = std::min<Eigen::Index>(static_cast<Eigen::Index>(uc), nx - 2);
  Eigen::Index j = std::min<Eigen::Index>(static_cast<Eigen::Index>(vc), ny - 2);
  const double tx = uc - static_cast<double>(i), ty = vc - static_cast<double>(j);
  const double h00 = heights_(i, j), h10 = heights_(i + 1, j);
  const double h01 = heights_(i, j + 1), h11 = heights_(i + 1, j + 1);
  const double h = (1 - tx) * (1 - ty) * h00 + tx * (1 - ty) * h10 + (1 - tx) * ty * h01 +
                   tx * ty * h11;
  dhdx = out_x ? 0.0 : ((h10 - h00) * (1 - ty) + (h11 - h01) * ty) * inv_spacing_;
  dhdy = out_y ? 0.0 : ((h01 - h00) * (1 - tx) + (h11 - h10) * tx) * inv_spacing_;
  return h;
}

double HeightMap::height(double x, double y) const {
  double gx, gy;
  return height_gradient(x, y, gx, gy);
}

double HeightMap::height_normal(double x, double y, Eigen::Vector3d& n) const {
  double gx, gy;
  const double h = height_gradient(x, y, gx, gy);
  n = Eigen::Vector3d(-gx, -gy, 1.0) * (1.0 / std::sqrt(1.0 + gx * gx + gy * gy));
  return h;
}

Eigen::Vector3d HeightMap::normal(double x, double y) const {
  Eigen::Vector3d n;
  height_normal(x, y, n);
  return n;
}

void BoxObstacle::validate() const {
  for (int k = 0; k < 3; ++k) {
    require_finite("BoxObstacle", "centre", centre[k]);
    require_in_range("BoxObstacle", "size", size[k], 1e-3, 1e3);
  }
  require_finite("BoxObstacle", "yaw", yaw);
  require_finite("BoxObstacle", "pitch", pitch);
  require_finite("BoxObstacle", "roll", roll);
}

}  // namespace ernest::dynamics
