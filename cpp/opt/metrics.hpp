// Per-transition metrics of seed 000 §4 "Evaluation Metrics" and §5 (eqs 24–28).
#pragma once

#include <Eigen/Core>
#include <string>

#include "ernest/opt/asterix_model.hpp"
#include "ernest/opt/transition.hpp"

namespace ernest::opt {

struct MetricsOptions {
  /// Rate at which the executed joint trajectory is sampled for the maximum acceleration, like the
  /// paper's "consecutive data points" of the telemetry [Hz] (ours: 50 Hz).
  double telemetry_rate = 50.0;
  double energy_step = 1e-3;  ///< quadrature step of the energy integrals [s]
  IntegrationOptions integration;
  void validate() const;
};

/// Energy model (ours; the paper measured motor torques and currents):
///  - articulation joints (eq 27, E = ∫ τ ω): τ = J q̈ + c q̇ + τ_c tanh(q̇ / 0.01 rad/s)
///    (+ roll_stiffness · q for the roll joint), counting only positive mechanical power (the
///    drives do not regenerate); a velocity jump at either end of the transition costs the kinetic
///    energy ½ J (v_after² − v_before²) when positive;
///  - wheels (eqs 25–26, E = ∫ k_t I ω): the motor current balances the rolling resistance,
///    k_t I = C_rr (m g / 4) R per wheel, so k_t cancels and E_wheel = ∫ Σ_i C_rr (m g / 4) |R ω_i|.
struct TransitionMetrics {
  double duration = 0.0;                 ///< T [s]
  Eigen::VectorXd max_acceleration;      ///< per joint, from telemetry-rate samples [rad/s^2]
  double heading_change = 0.0;           ///< heading after minus before (the paper's metric) [rad]
  double heading_deviation = 0.0;        ///< heading minus the eq 7 target heading [rad]
  double position_deviation = 0.0;       ///< |position − eq 7 target position| [m]
  double distance = 0.0;                 ///< eq 28 with the executed end pose [m]
  double energy_articulation = 0.0;      ///< eq 27 [J]
  double energy_wheels = 0.0;            ///< eq 26 [J]
  double energy = 0.0;                   ///< eq 25 [J]
  double cost_of_transport = 0.0;        ///< eq 24 [-]
  /// Boundary conditions, max over joints: |q(t1) − g1(t1)| (eq 2), |q̇(t1) − ġ1(t1)| (eq 4),
  /// |q(t1+T) − g2(t1+T−φ)| (eq 3), |q̇(t1+T) − ġ2(t1+T−φ)| (eq 5).
  double start_position_residual = 0.0, start_velocity_residual = 0.0;
  double end_position_residual = 0.0, end_velocity_residual = 0.0;
  Pose2 start_pose, end_pose, target_pose;  ///< G1(t1), x(t1+T), eq 7 target
};

TransitionMetrics evaluate_metrics(const TransitionProblem& problem, const TransitionResult& result,
                                   const MetricsOptions& options = {});

}  // namespace ernest::opt
