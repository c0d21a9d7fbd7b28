// FootFall's path smoothing (seed 003 §3.4.2, Fig. 4): shortest path through the plan's nodes by
// Dijkstra's algorithm over every shortcut between them (Boost.Graph), each shortcut edge
// collision-checked by the planner's bisection; then the simplified path is bisected (a midpoint
// in every edge, N2 − 1 new nodes) and Dijkstra runs again, until an iteration shortens the total
// Euclidean joint-space length by less than a threshold. Edges are checked lazily: Dijkstra runs on
// the unchecked graph, the edges of its answer are checked, colliding ones removed, and it runs
// again until its answer is free.
#pragma once

#include <Eigen/Core>

#include "ernest/footfall/leg_collision.hpp"

namespace ernest::footfall {

struct SmoothingOptions {
  double epsilon = 0.01;           ///< bisection resolution of the edge checks [rad]
  double min_improvement = 0.01;   ///< stop when an iteration gains less than this fraction (1 %)
  int max_iterations = 30;         ///< Dijkstra–bisection rounds at most
  int max_nodes = 64;              ///< no bisection beyond this many nodes
  void validate() const;
};

struct SmoothingResult {
  Eigen::MatrixXd path;            ///< joints × waypoints, same start and goal
  double initial_length = 0.0;     ///< [rad]
  double length = 0.0;             ///< [rad]
  int iterations = 0;              ///< Dijkstra–bisection rounds
  long edge_checks = 0;            ///< shortcut edges checked
  double seconds = 0.0;
};

/// Smooths a collision-free path (joints × waypoints, at least two) with the checker it was
/// planned with. Throws std::invalid_argument for a malformed or non-finite path.
SmoothingResult smooth_path(LegCollisionChecker& checker, const Eigen::Ref<const Eigen::MatrixXd>& path,
                            const SmoothingOptions& options = {});

}  // namespace ernest::footfall
