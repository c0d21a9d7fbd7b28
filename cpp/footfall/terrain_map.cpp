#include "ernest/footfall/terrain_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "ernest/common/validation.hpp"

namespace ernest::footfall {

void MapTerrainOptions::validate() const {
  const char* o = "MapTerrainOptions";
  require_in_range(o, "spacing", spacing, 0.005, 1.0);
  require_in_range(o, "sigma_factor", sigma_factor, 0.0, 10.0);
  require_in_range(o, "max_sigma", max_sigma, 1e-6, 10.0);
  require_in_range(o, "fill_radius", fill_radius, 0.0, 1.0);
  require_in_range(o, "unknown_height", unknown_height, 1.0, 1000.0);
}

bool MapTerrain::unknown_at(double x, double y) const {
  if (!(std::isfinite(x) && std::isfinite(y))) return true;
  const double h = terrain.spacing();
  const long i = std::lround((x - terrain.origin_x()) / h), j = std::lround((y - terrain.origin_y()) / h);
  if (i < 0 || j < 0 || i >= state.rows() || j >= state.cols()) return true;
  return state(i, j) == static_cast<std::uint8_t>(TerrainCell::kUnknown);
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Max over a (2r+1)-wide window along one axis, ignoring NaN (NaN only where the window has no
// number). Separable: a square window is a row pass then a column pass.
Eigen::MatrixXd window_max(const Eigen::MatrixXd& in, int r, bool along_rows) {
  Eigen::MatrixXd out(in.rows(), in.cols());
  const Eigen::Index n = along_rows ? in.rows() : in.cols();
  for (Eigen::Index i = 0; i < in.rows(); ++i)
    for (Eigen::Index j = 0; j < in.cols(); ++j) {
      const Eigen::Index c = along_rows ? i : j;
      double m = kNaN;
      for (Eigen::Index k = std::max<Eigen::Index>(0, c - r); k <= std::min<Eigen::Index>(n - 1, c + r); ++k) {
        const double v = along_rows ? in(k, j) : in(i, k);
        if (v == v && !(v <= m)) m = v;  // NaN m: take v
      }
      out(i, j) = m;
    }
  return out;
}

}  // namespace

MapTerrain terrain_from_map(const Eigen::Ref<const Eigen::MatrixXd>& heights,
                            const Eigen::Ref<const Eigen::MatrixXd>& variances, double resolution,
                            double origin_x, double origin_y, const MapTerrainOptions& o) {
  o.validate();
  require_positive("terrain_from_map", "resolution", resolution);
  require_finite("terrain_from_map", "origin_x", origin_x);
  require_finite("terrain_from_map", "origin_y", origin_y);
  require(heights.rows() == variances.rows() && heights.cols() == variances.cols(),
          "terrain_from_map: heights and variances must have the same shape");
  require(heights.rows() >= 2 && heights.cols() >= 2,
          "terrain_from_map: the elevation map is empty (" + std::to_string(heights.rows()) + " x " +
              std::to_string(heights.cols()) + " cells): nothing to plan on");
  require(o.spacing >= resolution, "terrain_from_map: spacing " + std::to_string(o.spacing) +
                                       " m must be at least the map's resolution " + std::to_string(resolution) + " m");
  // 1. Seen cells raised by k sigma; NaN / inf / too uncertain = unseen (NaN).
  Eigen::MatrixXd seen(heights.rows(), heights.cols());
  double top = -std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < seen.rows(); ++i)
    for (Eigen::Index j = 0; j < seen.cols(); ++j) {
      const double h = heights(i, j), v = variances(i, j);
      const bool ok = std::isfinite(h) && std::isfinite(v) && v >= 0.0 && std::sqrt(v) <= o.max_sigma;
      seen(i, j) = ok ? h + o.sigma_factor * std::sqrt(v) : kNaN;
      if (ok) top = std::max(top, seen(i, j));
    }
  require(std::isfinite(top), "terrain_from_map: the elevation map has no observed cell (all " +
                                  std::to_string(seen.size()) + " cells unseen or sigma > max_sigma " +
                                  std::to_string(o.max_sigma) + " m): nothing to plan on");
  // 2. Small holes: the highest seen cell within fill_radius (upper envelope).
  const int fr = static_cast<int>(std::floor(o.fill_radius / resolution + 1e-9));
  Eigen::MatrixXd filled = seen;
  int filled_cells = 0;
  if (fr > 0) {
    const Eigen::MatrixXd near = window_max(window_max(seen, fr, true), fr, false);
    for (Eigen::Index k = 0; k < seen.size(); ++k)
      if (std::isnan(seen.data()[k]) && !std::isnan(near.data()[k])) filled.data()[k] = near.data()[k], ++filled_cells;
  }
  // 3.–4. Planner vertices over the map's extent: the max over the cells whose area reaches
  // within one spacing (centres within spacing + resolution / 2); any unseen cell: unknown.
  const double s = o.spacing;
  const int ni = std::max(2, static_cast<int>(std::floor((heights.rows() - 1) * resolution / s + 1e-9)) + 1);
  const int nj = std::max(2, static_cast<int>(std::floor((heights.cols() - 1) * resolution / s + 1e-9)) + 1);
  const double w = (s + 0.5 * resolution) / resolution;  // window half-width in cells
  Eigen::MatrixXd out(ni, nj);
  MapTerrain r{dynamics::HeightMap(Eigen::MatrixXd::Zero(2, 2), s, origin_x, origin_y), {}};
  r.state.resize(ni, nj);
  auto range = [&](int v, Eigen::Index n, Eigen::Index& lo, Eigen::Index& hi) {
    const double c = v * s / resolution;
    lo = std::max<Eigen::Index>(0, static_cast<Eigen::Index>(std::ceil(c - w - 1e-9)));
    hi = std::min<Eigen::Index>(n - 1, static_cast<Eigen::Index>(std::floor(c + w + 1e-9)));
  };
  for (int I = 0; I < ni; ++I) {
    Eigen::Index i0, i1;
    range(I, heights.rows(), i0, i1);
    for (int J = 0; J < nj; ++J) {
      Eigen::Index j0, j1;
      range(J, heights.cols(), j0, j1);
      double m = -std::numeric_limits<double>::infinity();
      bool unknown = false, any_filled = false;
      for (Eigen::Index i = i0; i <= i1 && !unknown; ++i)
        for (Eigen::Index j = j0; j <= j1; ++j) {
          const double v = filled(i, j);
          if (std::isnan(v)) { unknown = true; break; }
          any_filled |= std::isnan(seen(i, j));
          m = std::max(m, v);
        }
      const TerrainCell c = unknown ? TerrainCell::kUnknown : any_filled ? TerrainCell::kFilled : TerrainCell::kObserved;
      r.state(I, J) = static_cast<std::uint8_t>(c);
      out(I, J) = unknown ? top + o.unknown_height : m;
      (unknown ? r.unknown : any_filled ? r.filled : r.observed) += 1;
    }
  }
  require(r.observed + r.filled > 0, "terrain_from_map: no planner cell of " + std::to_string(s) +
                                         " m is fully observed: nothing to plan on");
  r.terrain = dynamics::HeightMap(std::move(out), s, origin_x, origin_y);
  r.filled_cells = filled_cells;
  r.top = top;
  return r;
}

MapTerrain terrain_from_map(const perception::ElevationMap& map, const MapTerrainOptions& options) {
  return terrain_from_map(map.heights(), map.variances(), map.resolution(), map.origin_x(), map.origin_y(), options);
}

}  // namespace ernest::footfall
