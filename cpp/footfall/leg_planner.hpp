// Single-leg motion planning (seed 003 §3.4.1): OMPL's SBL (Sanchez and Latombe's single-query
// bi-directional planner with lazy collision checking) in the leg's joint space, bounded by the
// joint limits; edges are checked by recursive bisection to ε (0.01 rad, the paper's) through a
// custom ompl::base::MotionValidator over LegCollisionChecker. OMPL's RRT-Connect is available
// as the reference planner of the benchmark. Plans are reproducible: every random stream of the
// planner (its own RNG and the state samplers) is seeded from PlannerOptions::seed, not from
// OMPL's global seed.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "ernest/footfall/leg_collision.hpp"

namespace ernest::footfall {

enum class PlannerType { kSbl, kRrtConnect };
enum class PlanStatus { kSolved, kNoPlan };
const char* to_string(PlanStatus status);

struct PlannerOptions {
  PlannerType planner = PlannerType::kSbl;
  double time_limit = 1.0;   ///< planning budget [s]; past it the result is kNoPlan ("timeout")
  double epsilon = 0.01;     ///< bisection resolution of the edge checks [rad] (§3.4.1)
  /// Longest tree step [rad], (0, 100]; unset: OMPL's default (20 % of the joint space's extent,
  /// ~4.6 rad for SDM-B). 1 rad: on the benchmark's rock field SBL's hard queries (no free straight edge) took
  /// 11 ms median instead of 22–66 ms at the default, the raw paths are half as long (12 vs
  /// 24 rad) so smoothing them costs less, all 60 queries solved (benchmarks/RESULTS.md).
  std::optional<double> range = 1.0;
  std::uint32_t seed = 1;    ///< seeds every random stream of the planner
  void validate() const;
};

struct PlanResult {
  PlanStatus status = PlanStatus::kNoPlan;
  std::string reason;        ///< why there is no plan ("" when solved)
  Eigen::MatrixXd path;      ///< joints × waypoints, start to goal (empty without a plan)
  double seconds = 0.0;      ///< wall time of the query
  double length = 0.0;       ///< Euclidean joint-space length [rad]
  long checks = 0;           ///< configurations checked during the query
};

/// Euclidean joint-space length of a path (joints × waypoints) [rad] (§3.4.2's measure).
double path_length(const Eigen::Ref<const Eigen::MatrixXd>& path);

/// Plans one leg's motions with a fixed checker (one stance, one terrain). Not thread-safe.
class LegPlanner {
 public:
  LegPlanner(LegCollisionChecker& checker, const PlannerOptions& options = {});
  ~LegPlanner();
  const PlannerOptions& options() const { return options_; }
  LegCollisionChecker& checker() const { return checker_; }
  /// Joint-space query. NaN or wrongly sized input throws std::invalid_argument; an invalid
  /// start or goal (limits, collision) or no path within the budget gives kNoPlan with the reason.
  PlanResult plan(const Eigen::Ref<const Eigen::VectorXd>& start, const Eigen::Ref<const Eigen::VectorXd>& goal);
  /// OMPL's PathSimplifier (simplifyMax: shortcutting, B-spline smoothing, collapsing) on a path,
  /// with the same motion validator: the reference for the Dijkstra–bisection smoother.
  Eigen::MatrixXd simplify_with_ompl(const Eigen::Ref<const Eigen::MatrixXd>& path);

 private:
  struct Impl;
  LegCollisionChecker& checker_;
  PlannerOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ernest::footfall
