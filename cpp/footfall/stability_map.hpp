// Reachability and stability map of one leg (seed 003 §3.3): every cell of the digital elevation
// map within the leg's reach of its hip gets an inverse-kinematics solution inside the joint
// limits (the wheel upright on the ground point, heading radially from the hip, as in the
// standard stance), the compliance waypoint directly above it reachable too, and then the new
// centre of gravity, the Conservative Polygon of Support of the new stance and its SSM or, on
// slopes, NESM (cpp/statics). Cells are stable (green), unstable (red) or unreachable (none).
// Torque-aware maps (§7.1: "the kinematically reachable workspace of the robot is much larger than
// the load-bearing workspace"): optionally every reachable cell's peak static joint torque over
// the stance after the step and the stance during it with the swing leg at the waypoint above the
// cell (StanceTorques), and stable cells above a chosen fraction of a torque limit are a third
// class, overloaded. An infinite limit with torques off gives the plain map bit for bit (test).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>

#include "ernest/dynamics/terrain.hpp"
#include "ernest/footfall/stance_torque.hpp"
#include "ernest/walker/leg_ik.hpp"
#include "ernest/walker/walker_model.hpp"

namespace ernest::footfall {

enum class StabilityCriterion { kAuto, kSsm, kNesm };
/// kOverloaded: reachable and stable, but a joint's static torque (after the step or during it)
/// exceeds StabilityMapOptions::max_saturation of its limit (§7.1).
enum class CellStatus : std::uint8_t { kUnreachable = 0, kUnstable = 1, kStable = 2, kOverloaded = 3 };

struct StabilityMapOptions {
  double cell = 0.02;         ///< map cell [m] (the paper's maps are DEM-resolution)
  double lift_height = 0.2;   ///< compliance waypoints above start and goal [m] (§3.3)
  double min_margin = 0.0;    ///< a cell is stable when its margin exceeds this [m]
  /// SSM of the CPS, NESM of the CPS, or kAuto: NESM when the stance's feet lie on a plane
  /// steeper than slope_threshold (§3.3: "when walking on sloped terrain"), SSM otherwise.
  StabilityCriterion criterion = StabilityCriterion::kAuto;
  double slope_threshold = 0.0873;  ///< [rad] (5°)
  int ik_evaluations = 60;    ///< LM evaluations per IK start (each cell is seeded by a neighbour)
  /// Evaluate every reachable cell's peak joint torque (§7.1): |tau| / limit over every joint of
  /// every leg, the larger of the stance after the step and the stance with the swing leg at the
  /// waypoint above the cell. Implied by a finite max_saturation.
  bool torques = false;
  /// A stable cell whose peak torque exceeds this fraction of a joint's limit is kOverloaded:
  /// 1 refuses saturation, 0.8 keeps a 20 % torque margin; infinity (default) never. [0, inf]
  double max_saturation = std::numeric_limits<double>::infinity();
  bool evaluates_torques() const { return torques || max_saturation < std::numeric_limits<double>::infinity(); }
  void validate() const;
};

/// One evaluated cell (or goal point).
struct CellEvaluation {
  CellStatus status = CellStatus::kUnreachable;
  bool ground_reachable = false;  ///< IK on the ground point (the waypoint may still fail)
  double margin = 0.0;          ///< SSM or NESM of the CPS [m] (0 when unreachable)
  Eigen::VectorXd q;            ///< the leg's joint angles on the ground point
  Eigen::VectorXd q_above;      ///< at the compliance waypoint above it (NaN when not reached)
  Eigen::Vector3d cg = Eigen::Vector3d::Zero();  ///< new centre of gravity (world)
  /// Peak |tau| / limit (NaN unless torques are evaluated and the cell is reachable): after the
  /// step (every foot down), during it (the leg at q_above, five feet carrying), the larger.
  double saturation_down = std::numeric_limits<double>::quiet_NaN();
  double saturation_lifted = std::numeric_limits<double>::quiet_NaN();
  double saturation = std::numeric_limits<double>::quiet_NaN();
  int peak_leg = -1, peak_joint = -1;  ///< where the larger peak is
};

/// The map: cell (i, j) is centred at (origin_x + i cell, origin_y + j cell) in the world.
struct StabilityMap {
  double origin_x = 0.0, origin_y = 0.0, cell = 0.0;
  Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic> status;  ///< CellStatus values
  Eigen::MatrixXd margin;  ///< [m]; NaN where unreachable
  bool nesm = false;       ///< the criterion used (false: SSM)
  bool start_waypoint_reachable = false;  ///< the waypoint above the current foot (§3.3)
  Eigen::Vector3d hip = Eigen::Vector3d::Zero();  ///< hip (first joint) in the world
  double reach = 0.0;      ///< cells farther than this from the hip are not tried [m]
  long ik_solves = 0;      ///< local IK solves performed
  /// Peak |tau| / limit per cell (CellEvaluation::saturation); NaN where unreachable or when
  /// torques are not evaluated.
  Eigen::MatrixXd saturation;
  /// Peak |tau| / limit with the leg lifted to the waypoint above its current foot (the same for
  /// every cell; NaN when torques are not evaluated).
  double lift_saturation = std::numeric_limits<double>::quiet_NaN();
  int count(CellStatus s) const;
};

/// Evaluates candidate foot placements of one leg for a stance (body pose in the world, q of
/// shape joints × legs, every foot on the ground) over a terrain. Not thread-safe.
class StabilityMapper {
 public:
  StabilityMapper(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                  const Eigen::Isometry3d& body, const Eigen::Ref<const Eigen::MatrixXd>& q, int leg,
                  const StabilityMapOptions& options = {});
  ~StabilityMapper();

  /// The whole map over the square of half-side `reach` around the hip.
  StabilityMap map();
  /// One ground point (x, y world; z from the terrain), IK from `seed` then the current angles.
  CellEvaluation evaluate(double x, double y, const Eigen::Ref<const Eigen::VectorXd>& seed);
  /// The upright foot pose (body frame) with its contact at world point c, lifted by `lift`.
  Eigen::Isometry3d target(const Eigen::Vector3d& c, double lift) const;
  bool nesm() const { return nesm_; }
  const Eigen::VectorXd& start_above() const { return q_start_above_; }
  bool start_waypoint_reachable() const { return start_ok_; }

 private:
  bool solve(const Eigen::Isometry3d& target, const Eigen::Ref<const Eigen::VectorXd>& seed,
             Eigen::Ref<Eigen::VectorXd> q);
  const walker::WalkerModel& model_;
  const dynamics::HeightMap& terrain_;
  Eigen::Isometry3d body_, body_inv_;
  Eigen::MatrixXd q_;
  int leg_;
  StabilityMapOptions options_;
  walker::LegIk ik_;
  walker::LegWorkspace ws_;
  Eigen::Matrix3Xd contacts_;    // world, the swing column replaced per cell
  Eigen::Vector3d rest_moment_;  // sum of m r over everything but the swing leg (world)
  double swing_mass_ = 0.0, total_mass_ = 0.0;
  Eigen::Vector3d gravity_, up_body_, hip_body_;
  bool nesm_ = false, start_ok_ = false;
  Eigen::VectorXd q_start_above_;
  long solves_ = 0;
  std::unique_ptr<StanceTorques> torques_;  // when options_.evaluates_torques()
};

}  // namespace ernest::footfall
