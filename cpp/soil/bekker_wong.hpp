// Bekker–Wong wheel–soil contact with the DARTS modifications (seed 004 §3.3, eqs 12–32).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ernest/soil/soil_parameters.hpp"

namespace ernest::soil {

/// Rigid cylindrical wheel of radius r and width b (ERNEST: Table 1, r = 0.17 m, b = 0.13 m).
struct WheelGeometry {
  double radius = 0.17;  ///< r [m]
  double width = 0.13;   ///< b [m]
  void validate() const;
};

/// Kinematic inputs in the contact frame of seed 004 Fig. 7: x forward (yawed with the wheel, not
/// tilted), y lateral (along the axle), z up. Positive wheel spin rolls the wheel towards +x.
struct ContactState {
  double sinkage = 0.0;  ///< h: penetration of the reference contact point [m]; <= 0 means no contact
  double vx = 0.0;       ///< longitudinal velocity of the wheel centre [m/s]
  double vy = 0.0;       ///< lateral velocity of the wheel centre [m/s]
  double vcx = 0.0;      ///< longitudinal velocity of the contact point w.r.t. the terrain [m/s]
  double vcy = 0.0;      ///< lateral velocity of the contact point w.r.t. the terrain [m/s]
};

/// Forces on the wheel in the contact frame, applied at the contact patch, plus diagnostics.
struct WheelSoilForce {
  double fx = 0.0, fy = 0.0, fz = 0.0;  ///< eqs 30–32 [N]; fz floored at 0 (see the .cpp)
  /// r^2 b \int tau_x dtheta [N m]: the motor torque that balances the soil's shear about the axle
  /// (the soil applies -axle_torque in the sense of positive wheel spin).
  double axle_torque = 0.0;
  double slip = 0.0;      ///< s of eq 12 (regularised, clamped to [-1, 1])
  double theta_f = 0.0;   ///< entry angle, eq 13 [rad]
  double theta_m = 0.0;   ///< angle of maximum normal stress, eq 14 [rad]
  double theta_r = 0.0;   ///< exit angle, eq 15 [rad]
  double sinkage = 0.0;   ///< sinkage used (clamped to [0, r]) [m]
};

/// The model as linear in the shear levels of eqs 28–29: with s_x = clamp(-v_cx / eps_contact_x)
/// and s_y = clamp(-v_cy / eps_contact_y), evaluate() gives fx = fx_pressure + s_x fx_shear,
/// fy = s_y fy_shear, fz = max(0, fz_pressure + s_x fz_shear), axle_torque = s_x torque_shear.
/// The simulator integrates the shear implicitly at a level it solves for, so it needs the parts.
struct SoilSplit {
  double fx_pressure = 0.0;   ///< -sign(v_x) r b \int sigma sin (eq 30: compaction resistance) [N]
  double fz_pressure = 0.0;   ///< r b \int sigma cos (eq 32 without shear, not floored) [N]
  double fx_shear = 0.0;      ///< r b \int tau_x cos at unit shear level (eq 30) [N]
  double fz_shear = 0.0;      ///< sign(v_x) r b \int tau_x sin at unit level (eq 32) [N]
  double torque_shear = 0.0;  ///< r^2 b \int tau_x at unit level (axle torque) [N m]
  double fy_shear = 0.0;      ///< r b \int tau_y at unit level, bulldozing included (eq 31) [N]
  double slip = 0.0, theta_f = 0.0, theta_m = 0.0, theta_r = 0.0, sinkage = 0.0;  ///< as WheelSoilForce
  /// d fz_pressure / d sinkage at the same slip and velocities [N/m] (eq 17 differentiated under
  /// the integral; 0 out of contact and beyond the radius). Not set by split_pressure().
  double dfz_pressure_dh = 0.0;
};

/// Immutable, thread-safe evaluator: parameters are validated and derived constants and the
/// Gauss–Legendre rule are computed once, so evaluate() never allocates.
class BekkerWongModel {
 public:
  /// Default quadrature: Gauss–Legendre points per panel (three panels, [theta_r, 0], [0, theta_m],
  /// [theta_m, theta_f]); chosen by the convergence study in benchmarks/RESULTS.md.
  static constexpr int kDefaultPointsPerPanel = 4;
  static constexpr int kMaxPointsPerPanel = 32;

  BekkerWongModel(const SoilParameters& soil, const WheelGeometry& wheel,
                  int points_per_panel = kDefaultPointsPerPanel);

  /// Forces for one wheel. Throws std::invalid_argument on a non-finite input. Sinkage above the
  /// radius is clamped to r (theta_f = 90 deg): the model has no meaning past the axle.
  WheelSoilForce evaluate(const ContactState& state) const;

  /// The parts of evaluate() in one pass over the contact patch (see SoilSplit).
  SoilSplit split(const ContactState& state) const;
  /// split() with the slip ratio given instead of computed from eq 12 (clamped to [-1, 1]). The
  /// simulator solves eq 12 implicitly, at the velocities of the end of its step, so it chooses
  /// the slip and checks it against eq 12 afterwards (cpp/dynamics/rover_step.cpp).
  SoilSplit split(const ContactState& state, double slip) const;
  /// split(state, slip) without the shear: only fx_pressure, fz_pressure and the angles are set
  /// (bit-identical to split()'s), at about 70 % of the cost (no shear exponentials). The
  /// simulator differences eq 32's pressure part over the sinkage with it for n < 1, where
  /// SoilSplit::dfz_pressure_dh is not accurate (its integrand is singular at the ends).
  SoilSplit split_pressure(const ContactState& state, double slip) const;

  /// Eq 12 with this model's eps_slip and slip_clamp_first (as evaluate() and split() use it).
  double slip_ratio(double vx, double vcx) const;

  /// Batch evaluation for the simulator's hot loop. `states` rows are
  /// (sinkage, vx, vy, vcx, vcy); `forces` rows receive (fx, fy, fz, axle_torque).
  void evaluate_batch(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 5, Eigen::RowMajor>>& states,
                      Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>> forces) const;

  const SoilParameters& soil() const { return soil_; }
  const WheelGeometry& wheel() const { return wheel_; }
  int points_per_panel() const { return static_cast<int>(nodes_.size()); }

 private:
  // shear = false: the pressure parts only (split_pressure).
  SoilSplit integrate(const ContactState& state, bool lateral, const double* slip,
                      bool shear = true) const;

  SoilParameters soil_;
  WheelGeometry wheel_;
  std::vector<double> nodes_, weights_;  // Gauss–Legendre rule on [-1, 1]
  double k_eq_;                          // r^n (k_c / b + k_phi), eq 17
  double tan_phi_, d1_, d2_;             // eqs 25–27
};

/// Slip ratio of eq 12 (regularised, clamped to [-1, 1]); exposed for tests and the rig.
/// clamp_first: SoilParameters::slip_clamp_first (ours, default) or the printed order (false).
double slip_ratio(double vx, double vcx, double eps_slip, bool clamp_first = true);

}  // namespace ernest::soil
