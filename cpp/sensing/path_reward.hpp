// Desired path and reward of seed 004 §4.3, eqs 33–38.
#pragma once

namespace ernest::sensing {

/// Straight desired path through (x0, y0) with heading theta_d.
struct PathLine {
  double x0 = 0.0, y0 = 0.0, heading = 0.0;
  double a() const;  ///< eq 33: -sin(theta_d)
  double b() const;  ///< eq 34: cos(theta_d)
  double c() const;  ///< eq 35: -a x0 - b y0
  /// eq 36: progress along the path between two chassis positions.
  double progress(double x_prev, double y_prev, double x, double y) const;
  /// eq 37: signed lateral deviation (positive to the left of the path).
  double lateral_deviation(double x, double y) const;
  /// Chassis yaw minus path heading, wrapped to (-pi, pi].
  double heading_deviation(double yaw) const;
  /// Distance travelled along the path from (x0, y0).
  double arc_length(double x, double y) const;
};

struct RewardWeights {
  double w_s = 2.0;       ///< progress weight
  double w_delta = 0.1;   ///< lateral-deviation weight [1/m^2]
  double w_tau = 1e-4;    ///< roll-torque weight [1/(N m)]
  double dt = 0.5;        ///< policy period [s] (2 Hz)
  void validate() const;
};

struct RewardTerms {
  double progress = 0.0;      ///< Delta s [m]
  double lateral = 0.0;       ///< delta [m]
  double progress_term = 0.0; ///< w_s Delta s / Delta t
  double lateral_term = 0.0;  ///< -w_delta delta^2
  double torque_term = 0.0;   ///< -w_tau |tau_phi|
  double reward = 0.0;        ///< eq 38: the sum
};

/// eq 38 from the chassis positions at the previous and current policy steps and the roll-joint
/// torque tau_phi (N m).
RewardTerms compute_reward(const PathLine& path, double x_prev, double y_prev, double x, double y,
                           double roll_torque, const RewardWeights& weights = {});

}  // namespace ernest::sensing
