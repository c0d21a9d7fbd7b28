// The walker's stance as seed 003's compliance (sag) problem (§5.1.1, eqs 1–12): one definition
// shared by the planner (footfall: the pose to plan against) and the ODE walker (walker_sim: the
// model its sag is checked against).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ernest/statics/sag.hpp"
#include "ernest/walker/walker_model.hpp"

namespace ernest::walker {

/// The sag problem of the walker at `body`: the unsagged feet `feet` (3 × legs), the CG of
/// configuration `cg_q` (joints × legs), springs `stiffness` (3 × legs: k_xx, k_yy, k_zz, eq 3) in
/// the world frame, leg `lifted` in the air (eq 9's Δh = +inf; -1 for none), the hip mounts
/// carried along as body points. Throws std::invalid_argument on a bad leg index or shape.
statics::SagProblem stance_sag_problem(const WalkerModel& model, const Eigen::Isometry3d& body,
                                       const Eigen::Ref<const Eigen::Matrix3Xd>& feet,
                                       const Eigen::Ref<const Eigen::MatrixXd>& cg_q,
                                       const Eigen::Ref<const Eigen::Matrix3Xd>& stiffness,
                                       int lifted);

/// The sagged chassis pose of a solved problem.
Eigen::Isometry3d sagged_pose(const statics::SagResult& result);

}  // namespace ernest::walker
