// Largest roll torque the clutch can apply before a wheel lifts off (seed 004 §5.5, Fig. 25), by
// linear programming (GLPK) on the mass model of §3.2: unknowns the four vertical wheel loads and
// the roll torque, equalities the statics of cpp/statics/mass_model.hpp (force balance, two
// moment balances, moment about the roll axis on the bogie), loads >= a minimum; maximise and
// minimise the torque. The loads at the optimum are the load distribution Fig. 25 plots.
#pragma once

#include <Eigen/Core>

#include "ernest/common/validation.hpp"
#include "ernest/statics/mass_model.hpp"

namespace ernest::statics {

struct LiftoffOptions {
  double min_load = 0.0;  ///< a wheel "lifts" when its load would fall below this [N]
  /// Bound on |tau| [N m] (e.g. the roll actuator's N eta K_tau I_max); inf: geometry only.
  double torque_limit = kInf;
  void validate() const;
};

/// One direction's limit. torque is signed (about the roll axis, on the bogie, as
/// dynamics::RoverState::roll_torque).
struct LiftoffLimit {
  double torque = 0.0;
  Eigen::Vector4d loads = Eigen::Vector4d::Zero();  ///< FL, FR, RL, RR at that torque [N]
  int lifted_wheel = -1;        ///< the wheel at min_load (-1 when the torque limit binds first)
  bool torque_limited = false;  ///< LiftoffOptions::torque_limit was reached before any lift-off
};

struct LiftoffResult {
  bool feasible = false;  ///< some torque keeps every load >= min_load (else the rover tips over)
  Eigen::Vector4d loads_at_zero = Eigen::Vector4d::Zero();  ///< loads with the clutch open
  LiftoffLimit positive;  ///< largest tau (>= 0 when feasible at tau = 0)
  LiftoffLimit negative;  ///< smallest tau
};

/// Solves the two LPs (GLPK simplex) for the pose's configuration (chassis attitude, psi, phi,
/// ground normal; the pose's loads and roll_torque are ignored). Throws std::invalid_argument on
/// bad input, std::runtime_error if GLPK fails.
LiftoffResult max_roll_torque(const MassModel& model, const RoverGeometry& geometry,
                              const LoadPose& pose, const LiftoffOptions& options = {});

/// The configuration of a rover standing with all four wheels on a plane that rises along world
/// +x at `slope` [rad], heading [rad] relative to uphill, gimbal yaw psi, roll 0 (the chassis is
/// parallel to the plane).
LoadPose slope_pose(double slope, double heading, double psi);

}  // namespace ernest::statics
