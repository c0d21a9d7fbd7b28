// One rock field for FootFall's planner and the ODE walker (beyond seed 003: the D-RATS 2010 rock
// field of §6, Fig. 19 as boxes). The simulator collides the wheels with the boxes; the planner
// sees the same boxes rasterised into its digital elevation map (a grid node inside a box's
// footprint gets the box's top, elsewhere the ground z = 0), so plan and execution share one world.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/footfall/scenario.hpp"
#include "ernest/walker_sim/walker_sim.hpp"

namespace ernest::walker_sim {

struct RockMapOptions {
  double length = 9.0;                    ///< square side [m], (0.1, 200]
  double centre_x = 0.0, centre_y = 0.0;  ///< [m]
  double spacing = 0.02;                  ///< grid step [m], [0.002, 1]
  /// Footprints grown by this before rasterising [m], [0, 1]. The bilinear surface at a point
  /// is set by its cell's four nodes, each within a cell diagonal (√2 spacing) of it: a dilation
  /// of √2 spacing puts all four at the box top wherever the point lies over the box, so the
  /// planner's terrain never underestimates a rock (one spacing is not enough for a yawed box).
  double dilation = 0.0;
  void validate() const;
};

/// Box rocks placed like footfall::rock_field's bumps (same options, same std::mt19937_64 draw
/// order per rock: radius, height, centre; then a yaw and a width ratio in [0.5, 1]): half
/// extents (r, ratio r, height / 2), standing on z = 0; none within keep_clear of the points in
/// `keep_clear` (2 × k) measured to the box's circumcircle, none within inner_radius of the centre.
std::vector<Rock> box_rock_field(const footfall::RockFieldOptions& options,
                                 const Eigen::Ref<const Eigen::Matrix2Xd>& keep_clear);

/// The rocks as a height map: node (i, j) at (centre_x − length/2 + i spacing, centre_y −
/// length/2 + j spacing) holds the highest top (centre z + half height) of the boxes whose
/// (dilated) footprint contains it, 0 elsewhere. Throws std::invalid_argument for bad input.
dynamics::HeightMap rock_height_map(const std::vector<Rock>& rocks, const RockMapOptions& options = {});

}  // namespace ernest::walker_sim
