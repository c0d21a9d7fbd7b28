// The sway gait of seed 003 §5.3.1–5.3.2 (Figs 14–15): a discontinuous reverse-wave gait (each
// leg steps with the body still, then the body shifts with every foot down) whose body position
// during each step is displaced in 3-D to maximise the margin to torque saturation, footfalls
// fixed. Each step phase is an NLopt SLSQP problem in epigraph form,
//   min t  s.t.  |tau_ij(d)| / limit_ij <= t  (every joint of every leg, at lift-off and at
//                touch-down of the stepping leg),  SSM(d) >= min_support_margin,  d in bounds,
// with the contact forces of the zero-interaction distribution (§5.1.1) and the legs' joint angles
// from IK at the displaced body; the phases are independent once the footfalls are fixed, so
// maximising each phase's margin maximises the minimum over the cycle.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ernest/opt/nlopt_solver.hpp"
#include "ernest/walker/stance_loads.hpp"

namespace ernest::walker {

struct SwayGaitOptions {
  double stride = 0.5;        ///< advance of every foot per cycle [m] (our choice for SDM-B)
  double heading = 0.0;       ///< direction of travel in the world xy plane [rad] (leg 0 in front)
  double lift_height = 0.2;   ///< stepping wheel above its footfall [m] (§4.1's 20 cm lift)
  /// Stepping order: reverse wave, front to rear, left side first (§5.3.1) for heading 0.
  std::vector<int> sequence = {0, 1, 5, 2, 4, 3};
  double max_shift_xy = 0.3;     ///< |d_x|, |d_y| bounds [m]
  double max_shift_up = 0.15;    ///< d_z upper bound [m]
  double max_shift_down = 0.15;  ///< -d_z upper bound [m]
  double min_support_margin = 0.15;  ///< SSM of the CG over the loaded feet [m]
  double fd_step = 1e-5;         ///< forward-difference step of the gradients [m]
  opt::SolverOptions solver = [] {
    opt::SolverOptions s;
    s.max_time = 2.0;
    s.xtol_rel = 1e-6;
    s.ftol_rel = 1e-8;
    s.max_eval = 400;
    return s;
  }();
  void validate(int legs) const;
};

/// One step phase of the gait at a body displacement from the reference.
struct GaitPhase {
  int lifted_leg = 0;
  Eigen::Vector3d body_position = Eigen::Vector3d::Zero();  ///< world [m]
  Eigen::Vector3d displacement = Eigen::Vector3d::Zero();   ///< from the reference gait [m]
  bool reachable = false;          ///< every leg has an IK solution at both instants
  double peak_saturation = 0.0;    ///< max over joints, legs and the two instants
  double peak_force = 0.0;         ///< [N]
  double support_margin = 0.0;     ///< min SSM of the two instants [m]
  StanceLoads lift_off, touch_down;  ///< the two instants
  Eigen::MatrixXd q_lift_off, q_touch_down;  ///< joints × legs
};

struct SwayGaitResult {
  std::vector<GaitPhase> reference, sway;
  double reference_margin = 0.0;  ///< min over phases of 1 − peak_saturation
  double sway_margin = 0.0;
  double improvement = 0.0;       ///< sway_margin / reference_margin − 1 (paper: > 20 %)
  /// 1 − (sway gait's peak saturation) / (reference gait's peak): the lowering of Fig. 15's worst
  /// bar. Unlike `improvement` it does not blow up when the reference is near saturation.
  double peak_reduction = 0.0;
  std::vector<std::string> solver_status;
  int evaluations = 0;
  double seconds = 0.0;
};

/// Evaluates phase `phase` (0 .. sequence.size() − 1) of the periodic gait at body displacement d.
GaitPhase evaluate_gait_phase(const WalkerModel& model, const SwayGaitOptions& options, int phase,
                              const Eigen::Vector3d& displacement);

/// The reference gait (d = 0) and the optimised sway gait. Throws std::invalid_argument when the
/// options are invalid or the reference gait is unreachable.
SwayGaitResult optimise_sway_gait(const WalkerModel& model, const SwayGaitOptions& options = {});

}  // namespace ernest::walker
