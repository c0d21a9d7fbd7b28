#include "ernest/walker_sim/rock_map.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "ernest/common/validation.hpp"

namespace ernest::walker_sim {

void RockMapOptions::validate() const {
  const char* o = "RockMapOptions";
  require_in_range(o, "length", length, 0.1, 200.0);
  require_in_range(o, "centre_x", centre_x, -1e4, 1e4);
  require_in_range(o, "centre_y", centre_y, -1e4, 1e4);
  require_in_range(o, "spacing", spacing, 0.002, 1.0);
  require_in_range(o, "dilation", dilation, 0.0, 1.0);
}

std::vector<Rock> box_rock_field(const footfall::RockFieldOptions& o,
                                 const Eigen::Ref<const Eigen::Matrix2Xd>& keep_clear) {
  o.validate();
  require(keep_clear.allFinite(), "box_rock_field: keep_clear must be finite");
  const double x0 = o.centre_x - 0.5 * o.length, y0 = o.centre_y - 0.5 * o.length;
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Rock> rocks;
  for (int attempt = 0; static_cast<int>(rocks.size()) < o.rocks && attempt < 1000 * (o.rocks + 1); ++attempt) {
    const double r = o.min_radius + (o.max_radius - o.min_radius) * u(rng);
    const double height = o.min_height + (o.max_height - o.min_height) * u(rng);
    const Eigen::Vector2d c(x0 + r + (o.length - 2 * r) * u(rng), y0 + r + (o.length - 2 * r) * u(rng));
    const double yaw = 3.14159265358979323846 * u(rng), ratio = 0.5 + 0.5 * u(rng);
    const double circum = r * std::sqrt(1.0 + ratio * ratio);
    if ((c - Eigen::Vector2d(o.centre_x, o.centre_y)).norm() < o.inner_radius + circum) continue;
    bool clear = true;
    for (Eigen::Index k = 0; k < keep_clear.cols() && clear; ++k)
      clear = (c - keep_clear.col(k)).norm() >= o.keep_clear + circum;
    if (!clear || height <= 0.0) continue;
    Rock rock;
    rock.centre = Eigen::Vector3d(c.x(), c.y(), 0.5 * height);
    rock.half_extents = Eigen::Vector3d(r, ratio * r, 0.5 * height);
    rock.yaw = yaw;
    rocks.push_back(rock);
  }
  return rocks;
}

dynamics::HeightMap rock_height_map(const std::vector<Rock>& rocks, const RockMapOptions& o) {
  o.validate();
  for (const Rock& r : rocks) r.validate();
  const int cells = static_cast<int>(std::ceil(o.length / o.spacing - 1e-9)) + 1;
  const double x0 = o.centre_x - 0.5 * o.length, y0 = o.centre_y - 0.5 * o.length;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(cells, cells);
  for (const Rock& r : rocks) {
    const double top = r.centre.z() + r.half_extents.z();
    if (top <= 0.0) continue;  // buried entirely: the ground is higher
    const double c = std::cos(r.yaw), s = std::sin(r.yaw);
    const double ax = r.half_extents.x() + o.dilation, ay = r.half_extents.y() + o.dilation;
    const double reach = std::hypot(ax, ay);  // bounding square of the yawed footprint
    const int i0 = std::max(0, static_cast<int>(std::floor((r.centre.x() - reach - x0) / o.spacing)));
    const int i1 = std::min(cells - 1, static_cast<int>(std::ceil((r.centre.x() + reach - x0) / o.spacing)));
    const int j0 = std::max(0, static_cast<int>(std::floor((r.centre.y() - reach - y0) / o.spacing)));
    const int j1 = std::min(cells - 1, static_cast<int>(std::ceil((r.centre.y() + reach - y0) / o.spacing)));
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) {
        const double dx = x0 + i * o.spacing - r.centre.x(), dy = y0 + j * o.spacing - r.centre.y();
        // the node in the box's frame (rotated by -yaw)
        if (std::abs(c * dx + s * dy) <= ax && std::abs(-s * dx + c * dy) <= ay) h(i, j) = std::max(h(i, j), top);
      }
  }
  return dynamics::HeightMap(std::move(h), o.spacing, x0, y0);
}

}  // namespace ernest::walker_sim
