// Scenario helpers shared by the tests, the benchmark and `ernest footfall`: a rock field as a
// digital elevation map (ellipsoidal rocks on flat ground, like the D-RATS 2010 site of seed 003
// §6, Fig. 19) and random feasible planning queries (collision-free waypoints above stable cells).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/footfall/leg_collision.hpp"
#include "ernest/footfall/stability_map.hpp"

namespace ernest::footfall {

struct RockFieldOptions {
  double length = 9.0;        ///< square side [m], centred on (centre_x, centre_y)
  double centre_x = 0.0, centre_y = 0.0;
  double spacing = 0.05;      ///< DEM cell [m]
  int rocks = 14;
  double min_height = 0.15, max_height = 0.4;  ///< rock heights [m]
  double min_radius = 0.15, max_radius = 0.35;  ///< rock footprint radii [m]
  double keep_clear = 0.55;   ///< no rock within this of a keep-clear point [m]
  double inner_radius = 1.6;  ///< no rock closer to the centre (under the body) [m]
  std::uint32_t seed = 1;
  void validate() const;
};

/// Heights of flat ground (z = 0) with half-ellipsoid rocks at random places (std::mt19937_64
/// from the seed), none within keep_clear of the points in `keep_clear` (2 × k, e.g. the feet).
dynamics::HeightMap rock_field(const RockFieldOptions& options,
                               const Eigen::Ref<const Eigen::Matrix2Xd>& keep_clear);

/// `count` joint configurations (joints × count) of the mapper's leg at the compliance waypoint
/// above random stable cells of `map`, each valid for `checker` — the ends of random feasible
/// queries. Throws std::invalid_argument when the map has too few usable cells.
Eigen::MatrixXd sample_waypoints(StabilityMapper& mapper, const StabilityMap& map,
                                 LegCollisionChecker& checker, int count, std::uint32_t seed);

}  // namespace ernest::footfall
