// The planner's digital elevation map from the perception stack (stereo -> fused map; the
// simulator's ground truth is the other option). The fused stereo map (perception::ElevationMap,
// 1 cm cells, NaN = never seen, a variance per cell) becomes a dynamics::HeightMap at the
// planner's spacing that is, wherever the map says anything, an upper envelope of what was
// seen, and that never turns an unseen cell into free ground. The policy, and why:
//  1. Each observed cell is raised by k sigma (its standard deviation): the planner's clearances
//     then hold against the stereo noise (k = 2: one-sided 97.7 %). A cell whose sigma exceeds
//     max_sigma tells nothing useful and counts as unseen. Raising the ground also raises foot
//     targets by k sigma: harmless, the compliance segment lowers the wheel onto the real ground.
//  2. Small holes (an observed cell within fill_radius: stereo drop-outs, rock-edge mismatches)
//     are filled with the highest such cell (upper envelope, not the mean: a hole next to a rock
//     top must not dig a notch the swing leg could pass through).
//  3. The planner's vertex at (x, y) takes the highest cell whose area lies within one planner
//     spacing of it, so the bilinear surface between vertices stays above every cell it spans.
//  4. A vertex with any unseen cell in that window is unknown: it becomes a column
//     `unknown_height` above the highest seen point, which the collision checker treats as an
//     obstacle and on which the stability map finds no IK (the cell is unreachable, never
//     "stable"). Large holes (occlusion shadows behind rocks, the blind area under the body)
//     therefore block the leg instead of being guessed.
// An empty map or one with no usable cell throws std::invalid_argument: nothing to plan on.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/perception/elevation_map.hpp"

namespace ernest::footfall {

struct MapTerrainOptions {
  double spacing = 0.05;         ///< planner DEM spacing [m] (the rock field's; the FCL mesh's)
  double sigma_factor = 2.0;     ///< k: observed heights raised by k sigma
  double max_sigma = 0.10;       ///< cells less certain than this [m] count as unseen
  double fill_radius = 0.05;     ///< holes with a seen cell this close are filled [m] (max-norm)
  double unknown_height = 10.0;  ///< unknown vertices: this far above the highest seen point [m]
  void validate() const;
};

/// Per planner vertex: seen (only observed cells in its window), filled (some filled holes) or
/// unknown (an unseen cell in its window: an obstacle column).
enum class TerrainCell : std::uint8_t { kObserved = 0, kFilled = 1, kUnknown = 2 };

struct MapTerrain {
  dynamics::HeightMap terrain;   ///< the planner's DEM (vertex (i, j) at origin + (i, j) spacing)
  Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic> state;  ///< TerrainCell per vertex
  int observed = 0, filled = 0, unknown = 0;  ///< vertex counts
  int filled_cells = 0;          ///< map cells (input resolution) filled from neighbours
  double top = 0.0;              ///< highest seen (raised) height [m]
  /// Whether the planner DEM is unknown at (x, y) (nearest vertex; outside the map: true).
  bool unknown_at(double x, double y) const;
};

/// From snapshot arrays: heights and variances (same shape, NaN / inf = unseen), cell (i, j)
/// centred at (origin_x + i resolution, origin_y + j resolution) as ElevationMap::heights().
MapTerrain terrain_from_map(const Eigen::Ref<const Eigen::MatrixXd>& heights,
                            const Eigen::Ref<const Eigen::MatrixXd>& variances, double resolution,
                            double origin_x, double origin_y, const MapTerrainOptions& options = {});
/// From the fused stereo map.
MapTerrain terrain_from_map(const perception::ElevationMap& map, const MapTerrainOptions& options = {});

}  // namespace ernest::footfall
