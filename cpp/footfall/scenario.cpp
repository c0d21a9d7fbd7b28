#include "ernest/footfall/scenario.hpp"

#include <cmath>
#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "ernest/common/validation.hpp"

namespace ernest::footfall {

void RockFieldOptions::validate() const {
  const char* o = "RockFieldOptions";
  require_in_range(o, "length", length, 0.5, 200.0);
  require_in_range(o, "centre_x", centre_x, -1e4, 1e4);
  require_in_range(o, "centre_y", centre_y, -1e4, 1e4);
  require_in_range(o, "spacing", spacing, 0.005, 1.0);
  require_in_range(o, "rocks", rocks, 0, 10000);
  require_in_range(o, "min_height", min_height, 0.0, 5.0);
  require_in_range(o, "max_height", max_height, min_height, 5.0);
  require_in_range(o, "min_radius", min_radius, 0.01, 5.0);
  require_in_range(o, "max_radius", max_radius, min_radius, 5.0);
  require_in_range(o, "keep_clear", keep_clear, 0.0, 10.0);
  require_in_range(o, "inner_radius", inner_radius, 0.0, 100.0);
}

dynamics::HeightMap rock_field(const RockFieldOptions& o, const Eigen::Ref<const Eigen::Matrix2Xd>& keep_clear) {
  o.validate();
  require(keep_clear.allFinite(), "rock_field: keep_clear must be finite");
  const int cells = static_cast<int>(std::ceil(o.length / o.spacing)) + 1;
  const double x0 = o.centre_x - 0.5 * o.length, y0 = o.centre_y - 0.5 * o.length;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(cells, cells);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int placed = 0;
  for (int attempt = 0; placed < o.rocks && attempt < 1000 * (o.rocks + 1); ++attempt) {
    const double r = o.min_radius + (o.max_radius - o.min_radius) * u(rng);
    const double height = o.min_height + (o.max_height - o.min_height) * u(rng);
    const Eigen::Vector2d c(x0 + r + (o.length - 2 * r) * u(rng), y0 + r + (o.length - 2 * r) * u(rng));
    if ((c - Eigen::Vector2d(o.centre_x, o.centre_y)).norm() < o.inner_radius) continue;
    bool clear = true;
    for (Eigen::Index k = 0; k < keep_clear.cols() && clear; ++k)
      clear = (c - keep_clear.col(k)).norm() >= o.keep_clear + r;
    if (!clear) continue;
    ++placed;
    // Half ellipsoid: z = height sqrt(1 - (d/r)^2) inside the footprint.
    const int i0 = std::max(0, int((c.x() - r - x0) / o.spacing)), i1 = std::min(cells - 1, int((c.x() + r - x0) / o.spacing) + 1);
    const int j0 = std::max(0, int((c.y() - r - y0) / o.spacing)), j1 = std::min(cells - 1, int((c.y() + r - y0) / o.spacing) + 1);
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) {
        const double d = std::hypot(x0 + i * o.spacing - c.x(), y0 + j * o.spacing - c.y()) / r;
        if (d < 1.0) h(i, j) = std::max(h(i, j), height * std::sqrt(1.0 - d * d));
      }
  }
  return dynamics::HeightMap(std::move(h), o.spacing, x0, y0);
}

Eigen::MatrixXd sample_waypoints(StabilityMapper& mapper, const StabilityMap& map, LegCollisionChecker& checker,
                                 int count, std::uint32_t seed) {
  // (the attempts, 50 per waypoint, stay within an int)
  require_in_range("sample_waypoints", "count", count, 1, 1e6);
  std::vector<std::array<int, 2>> stable;
  for (Eigen::Index i = 0; i < map.status.rows(); ++i)
    for (Eigen::Index j = 0; j < map.status.cols(); ++j)
      if (map.status(i, j) == static_cast<std::uint8_t>(CellStatus::kStable)) stable.push_back({int(i), int(j)});
  require(!stable.empty(), "sample_waypoints: the map has no stable cell");
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, stable.size() - 1);
  const int n = checker.model().joints_per_leg();
  Eigen::MatrixXd out(n, count);
  int found = 0;
  for (int attempt = 0; found < count && attempt < 50 * count; ++attempt) {
    const auto [i, j] = stable[pick(rng)];
    const CellEvaluation e = mapper.evaluate(map.origin_x + i * map.cell, map.origin_y + j * map.cell, mapper.start_above());
    if (e.status != CellStatus::kStable || !checker.valid(e.q_above)) continue;
    out.col(found++) = e.q_above;
  }
  require(found == count, "sample_waypoints: found only " + std::to_string(found) + " of " +
                              std::to_string(count) + " collision-free waypoints");
  return out;
}

}  // namespace ernest::footfall
