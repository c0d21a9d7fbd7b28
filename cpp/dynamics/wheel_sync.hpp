// Jacobian wheel synchroniser of seed 004 §2.3 (eqs 1–10), shared by the simulator, the
// environments and the onboard runtime.
#pragma once

#include <Eigen/Core>
#include <array>

#include "ernest/dynamics/rover_parameters.hpp"

namespace ernest::dynamics {

/// Generalised velocities q_dot of eq 3: (Vx, Vy, Vz, wx, wy, wz, psi_dot, phi_dot), chassis frame.
using GeneralisedVelocity = Eigen::Matrix<double, 8, 1>;
/// J_i of eqs 1–2: the velocity of wheel i's centre in the wheel frame (x forward, y along the
/// axle, z up; steering locked so the front frames are the bogie's and the rear the chassis')
/// as a linear map of q_dot.
using WheelJacobian = Eigen::Matrix<double, 3, 8>;

/// Per-wheel Jacobian (eqs 1–2) at gimbal yaw psi and roll phi [rad]. wheel in 0..3 (FL, FR, RL,
/// RR). The Jacobians are expressed in chassis/wheel frames, so the chassis attitude does not enter.
WheelJacobian wheel_jacobian(const RoverParameters& p, double psi, double phi, int wheel);

struct WheelSyncResult {
  /// x of eq 5: (Vy, Vz, wz, v1x, v1z, v2x, v2z, v3x, v3z, v4x, v4z), wheels in order FL, FR, RL, RR.
  Eigen::Matrix<double, 11, 1> x;
  /// Wheel angular speeds of eq 10 [rad/s], positive rolling forward.
  std::array<double, 4> wheel_speeds{};
  /// ||A x - y||: ~0 when the commanded motion is kinematically consistent.
  double residual = 0.0;
  Eigen::Matrix<double, 12, 11> A;  ///< eq 6
  Eigen::Matrix<double, 12, 1> y;   ///< eq 8
};

/// Solve eqs 4–10: build A (eq 6) and y (eq 8) from the Jacobians at (psi, phi), solve with the
/// pseudo-inverse x = A^+ y (eq 9; the minimum-norm least-squares solution, which is the right
/// pseudo-inverse solution when A has full row rank), and return the wheel speeds (eq 10).
/// x = A^+ y (minimum-norm least squares, Eigen's CompleteOrthogonalDecomposition) without heap
/// allocation; bit-identical to CompleteOrthogonalDecomposition(a).solve(y).
Eigen::Matrix<double, 11, 1> pseudo_inverse_solve(const Eigen::Matrix<double, 12, 11>& a,
                                                  const Eigen::Matrix<double, 12, 1>& y);

WheelSyncResult synchronise_wheels(const RoverParameters& p, double psi, double phi, double vx,
                                   double wx, double wy, double psi_dot, double phi_dot);

}  // namespace ernest::dynamics
