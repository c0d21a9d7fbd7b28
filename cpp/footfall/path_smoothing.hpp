// FootFall's path smoothing (seed 003 §3.4.2, Fig. 4): shortest path through the plan's nodes by
// Dijkstra's algorithm over every shortcut between them (Boost.Graph), each shortcut edge
// collision-checked by the planner's bisection; then the simplified path is bisected (a midpoint
// in every edge, N2 − 1 new nodes) and Dijkstra runs again, until an iteration shortens the total
// Euclidean joint-space length by less than a threshold. Edges are checked lazily: Dijkstra runs on
// the unchecked graph, the edges of its answer are checked, colliding ones removed, and it runs
// again until its answer is free.
#pragma once

#include <Eigen/Core>
#include <limits>

#include "ernest/footfall/leg_collision.hpp"

namespace ernest::footfall {

/// What the smoothing minimises: the Euclidean joint-space length (§3.4.2, FootFall's), or the
/// peak static joint torque along the path, then its length (§7.1's suggestion;
/// torque_smoothing.hpp). plan_step picks the smoother by this field.
enum class SmoothingObjective { kLength = 0, kPeakTorque = 1 };

struct SmoothingOptions {
  double epsilon = 0.01;           ///< bisection resolution of the edge checks [rad]
  double min_improvement = 0.01;   ///< stop when an iteration gains less than this fraction (1 %)
  int max_iterations = 30;         ///< Dijkstra–bisection rounds at most
  int max_nodes = 64;              ///< no bisection beyond this many nodes
  SmoothingObjective objective = SmoothingObjective::kLength;
  /// kPeakTorque: edges sampled for their peak torque every this much [rad], [1e-3, 1]
  double torque_resolution = 0.05;
  /// kPeakTorque: peaks closer than this (fraction of a limit) are equal and length decides, [0, 1]
  double torque_tolerance = 1e-3;
  void validate() const;
};

struct SmoothingResult {
  Eigen::MatrixXd path;            ///< joints × waypoints, same start and goal
  double initial_length = 0.0;     ///< [rad]
  double length = 0.0;             ///< [rad]
  int iterations = 0;              ///< Dijkstra–bisection rounds
  long edge_checks = 0;            ///< shortcut edges checked
  double seconds = 0.0;
  /// Peak |tau| / limit along the path with the leg in the air, before and after (NaN unless the
  /// smoother evaluated torques: kPeakTorque).
  double initial_peak_saturation = std::numeric_limits<double>::quiet_NaN();
  double peak_saturation = std::numeric_limits<double>::quiet_NaN();
};

/// Smooths a collision-free path (joints × waypoints, at least two) with the checker it was
/// planned with. Throws std::invalid_argument for a malformed or non-finite path.
SmoothingResult smooth_path(LegCollisionChecker& checker, const Eigen::Ref<const Eigen::MatrixXd>& path,
                            const SmoothingOptions& options = {});

}  // namespace ernest::footfall
