// Collision checking of one swing leg for FootFall's planner (seed 003 §3.4.1): self-collisions
// with a per-pair clearance table (the leg against the other legs and the chassis) and against the
// non-neighbouring links of its own leg, and environmental collisions with one clearance against
// the terrain (the digital elevation map as an FCL triangle mesh). The paper uses PQP with a
// distance ε per pair; we use FCL (the project's collision library, as walker/self_collision):
// "within ε" of a capsule is exactly "intersects the capsule inflated by ε" (a Minkowski sum of a
// capsule and a ball is a capsule), so every test is a boolean FCL collide on inflated capsules,
// cheaper than a distance query. Edges between configurations are checked by recursive bisection
// to a resolution ε in joint space (§3.4.1, ε = 0.01 rad). The terrain is solid: before the FCL
// mesh query, a capsule higher than its radius above the highest mesh block under each piece of
// its axis is free, and one whose axis passes within its radius above (or below) the surface
// straight under it collides (that point of the surface is inside it); only the rest goes to
// FCL. The other legs are grouped per leg, and a leg whose bounding sphere is out of reach is
// skipped whole.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/walker/walker_model.hpp"

namespace ernest::footfall {

/// Clearances of the swing leg's checks [m]. Shapes are indexed by "type": a leg's link i
/// (joint index, 0..n-1), its wheel (n), and the chassis (n + 1).
struct CollisionOptions {
  /// One clearance for the terrain (§3.4.1: "environmental collisions use one value of ε").
  double environment_clearance = 0.05;
  /// Pairs within the swing leg (neighbouring links that touch by construction are skipped).
  double own_leg_clearance = 0.02;
  /// Per-pair table (§3.4.1: "a lookup table indicating values of ε for each pair"): entry
  /// (a, b) is the clearance between the swing leg's shape type a (rows 0..n) and another leg's
  /// shape type b (cols 0..n) or the chassis (col n + 1). Empty: default_clearance_table().
  Eigen::MatrixXd clearance_table;
  /// Terrain mesh: the height map is sampled over the square around the hip that the leg can
  /// reach (its length plus this margin) [m].
  double terrain_margin = 0.3;
  /// Throws std::invalid_argument naming the field; `joints` is the leg's joint count.
  void validate(int joints) const;
};

/// The default table: pairs ordinarily far apart (another leg's links) get a larger ε than the
/// chassis, which the hip links pass close to (the paper's reasoning: larger uncertainty from
/// compliance and encoder noise for parts far apart). 0.05 m between legs, 0.03 m to the chassis.
Eigen::MatrixXd default_clearance_table(int joints);

/// Checks one leg's configurations with the rest of the robot fixed: body pose (world), the
/// whole configuration q (joints × legs; the swing leg's column is ignored) and the terrain.
/// Not thread-safe (preallocated workspace): one checker per thread.
class LegCollisionChecker {
 public:
  LegCollisionChecker(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                      const Eigen::Isometry3d& body, const Eigen::Ref<const Eigen::MatrixXd>& q,
                      int leg, const CollisionOptions& options = {});
  ~LegCollisionChecker();
  LegCollisionChecker(const LegCollisionChecker&) = delete;
  LegCollisionChecker& operator=(const LegCollisionChecker&) = delete;

  const walker::WalkerModel& model() const { return model_; }
  int leg() const { return leg_; }
  const Eigen::Isometry3d& body() const;
  /// Joint limits, self-collisions and (with include_wheel false: all but the wheel, for the
  /// compliance segments where the wheel leaves or meets the ground) the terrain.
  bool valid(const Eigen::Ref<const Eigen::VectorXd>& q_leg, bool include_wheel = true);
  /// Straight joint-space edge a -> b by recursive bisection (§3.4.1): midpoints level by level
  /// until every sub-segment is at most `epsilon` [rad] long (max-norm); b is checked, a is
  /// assumed valid. Stops at the first collision.
  bool motion_valid(const Eigen::Ref<const Eigen::VectorXd>& a,
                    const Eigen::Ref<const Eigen::VectorXd>& b, double epsilon,
                    bool include_wheel = true);
  /// Configurations checked so far (for statistics).
  long checks() const { return checks_; }

 private:
  struct Impl;
  const walker::WalkerModel& model_;
  int leg_;
  long checks_ = 0;
  std::unique_ptr<Impl> impl_;
};

/// Smallest first_colliding_edge resolution and motion_valid epsilon [rad].
inline constexpr double kMinResolution = 1e-5;
/// Most configuration checks along one edge (a path's joint angles lie within the joint limits:
/// a few radians apart at most, 1e6 checks at kMinResolution).
inline constexpr double kMaxEdgeChecks = 1e7;

/// Dense re-check of a path (joints × waypoints): every step of at most `resolution` [rad] along
/// each edge (resolution >= kMinResolution), all points (the edges' ends included) checked with
/// `checker.valid`; polls for Ctrl-C between checks. Returns the
/// index of the first edge with a collision, or -1 when the whole path is free.
/// `wheel_free_edges` edges at each end are checked without the wheel (compliance segments).
int first_colliding_edge(LegCollisionChecker& checker, const Eigen::Ref<const Eigen::MatrixXd>& path,
                         double resolution, int wheel_free_edges = 0);

}  // namespace ernest::footfall
