// Path smoothing for the smallest peak joint torque (seed 003 §7.1: "it would be worth exploring
// torque-based optimizations for the path-smoothing step ... it may be preferable to optimize for
// a minimal peak joint-torque"). FootFall's Dijkstra–bisection rounds (§3.4.2, Fig. 4) with
// another cost: a path's cost is the pair (peak |tau| / limit along it with the swing leg in the
// air, the other legs' loads from the zero-interaction distribution at every sample — StanceTorques
// — then its joint-space length), compared lexicographically (peaks within torque_tolerance tie).
// Edges are checked lazily for collisions as in path_smoothing.cpp and evaluated lazily for their
// peak: Dijkstra runs with each unevaluated edge's peak bounded below by its end nodes' peaks, the
// edges of its answer are evaluated (sampled every torque_resolution) and it reruns until its
// answer's bounds are exact. The bottleneck is minimised exactly over the shortcut graph; among
// paths of equal peak, the length is Dijkstra's (not always the shortest of them).
#pragma once

#include <Eigen/Core>

#include "ernest/footfall/path_smoothing.hpp"
#include "ernest/footfall/stance_torque.hpp"

namespace ernest::footfall {

/// Smooths a collision-free path (joints × waypoints, at least two) for the smallest peak torque
/// of `torques`' stance (built on the body pose the path was planned against), then length.
/// options.objective is ignored. Throws std::invalid_argument for a malformed or non-finite path
/// or a checker and torques of different legs.
SmoothingResult smooth_path_for_torque(LegCollisionChecker& checker, StanceTorques& torques,
                                       const Eigen::Ref<const Eigen::MatrixXd>& path,
                                       const SmoothingOptions& options = {});

}  // namespace ernest::footfall
