// Numerical inverse kinematics of one leg (seed 003 §3.3: "if the mapper finds an inverse
// kinematic solution that puts the foot at the selected point"): the foot frame (wheel centre and
// wheel orientation) is driven to a target by Levenberg–Marquardt (Eigen's unsupported
// LevenbergMarquardt, a MINPACK port) inside the joint limits, from several seeds; distinct
// solutions are kept, or the target is reported unreachable with the closest approach.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "ernest/walker/walker_model.hpp"

namespace ernest::walker {

struct IkOptions {
  int seeds = 24;                      ///< starts (the caller's seed first, then a Halton set)
  int max_evaluations = 150;           ///< residual evaluations per start
  double position_tolerance = 1e-6;    ///< accepted wheel-centre error [m]
  double orientation_tolerance = 1e-6; ///< accepted foot rotation error [rad]
  double orientation_weight = 0.5;     ///< [m] per unit of ||R − R*||_F in the residual
  double duplicate_tolerance = 1e-3;   ///< two solutions closer than this (max |Δq|, rad) are one
  int max_solutions = 16;              ///< stop after this many distinct solutions
  void validate() const;
};

enum class IkStatus { kSolved, kUnreachable };

struct IkResult {
  IkStatus status = IkStatus::kUnreachable;
  /// Distinct solutions inside the joint limits, nearest to the caller's seed first. A 6-joint
  /// leg has finitely many (SDM-B: up to 8 branches, yaw × knee × wrist); for a redundant leg
  /// (T12's seven joints) they are samples of a continuum, one per converged start.
  std::vector<Eigen::VectorXd> solutions;
  /// Errors of the best start (the first solution when solved; the closest approach otherwise).
  double position_error = 0.0;     ///< [m]
  double orientation_error = 0.0;  ///< [rad]
  Eigen::VectorXd closest;         ///< joint angles of the best start
  int evaluations = 0;             ///< residual evaluations over all starts
};

/// IK workspace for one model (not thread-safe: one per thread). Solutions always respect the
/// joint limits: each bounded joint is solved in u with q = c + h sin(u) (c, h the range's
/// centre and half-width), so every iterate stays inside [lower, upper].
class LegIk {
 public:
  explicit LegIk(const WalkerModel& model, const IkOptions& options = {});
  ~LegIk();
  LegIk(const LegIk&) = delete;
  LegIk& operator=(const LegIk&) = delete;

  const IkOptions& options() const { return options_; }
  /// One local solve from `seed` (clamped into the limits). Writes the end point to q and returns
  /// true when it meets the tolerances. Allocation-free after the first call.
  bool solve_from(int leg, const Eigen::Isometry3d& target, const Eigen::Ref<const Eigen::VectorXd>& seed,
                  Eigen::Ref<Eigen::VectorXd> q);
  /// Multi-start solve: every distinct solution found from the seeds.
  IkResult solve(int leg, const Eigen::Isometry3d& target, const Eigen::Ref<const Eigen::VectorXd>& seed);
  /// Errors of the last solve_from: wheel-centre distance [m] and rotation angle [rad].
  double last_position_error() const;
  double last_orientation_error() const;
  int last_evaluations() const;

 private:
  struct Impl;
  const WalkerModel& model_;
  IkOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ernest::walker
