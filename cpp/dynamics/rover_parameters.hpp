// ERNEST rover model parameters: seed 004 Table 1 geometry plus the values the paper leaves open,
// chosen and documented here as assumptions (marked "Assumption").
#pragma once

#include <Eigen/Core>

namespace ernest::dynamics {

/// Allowed range of Commands' rates [rad/s] and torques [N m] (symmetric): bounds far above what
/// the rover's motors can do, small enough to keep ODE's constraint solve finite.
inline constexpr double kMaxCommandRate = 100.0;
inline constexpr double kMaxCommandTorque = 1e5;

/// Allowed range of synchronise_wheels' forward speed [m/s] (symmetric).
inline constexpr double kMaxSyncSpeed = 100.0;

/// DC motor + Harmonic Drive gearbox (seed 004 §2.1.1: identical actuators, 50:1 for the wheels,
/// 160:1 for the gimbal). Output torque = N * eta * K_tau * I when the motor drives the load.
struct MotorParameters {
  double torque_constant = 0.07;   ///< K_tau [N m/A] (assumption: 82 V brushless class, eq 40)
  double resistance = 0.6;         ///< R winding resistance [Ohm] (assumption, eq 40)
  double gear_ratio = 50.0;        ///< N [-]
  double efficiency = 0.85;        ///< gearbox efficiency eta (assumption, Harmonic Drive)
  double current_limit = 10.0;     ///< |I| <= current_limit [A] (assumption, servo drive setting)
  double rotor_inertia = 2e-5;     ///< [kg m^2] on the motor side (assumption)

  void validate(const char* owner) const;
  /// Largest output torque the current limit allows: N * eta * K_tau * I_max [N m].
  double max_output_torque() const { return gear_ratio * efficiency * torque_constant * current_limit; }
};

/// Electrical quantities of one actuator at one instant (eq 40).
struct MotorElectrical {
  double current = 0.0;  ///< winding current I [A]
  double power = 0.0;    ///< P = I (R I + K_tau omega_motor) [W]; < 0 when back-driven
};

/// Winding current and power (seed 004 eq 40) for an output torque and speed. The gearbox loses
/// (1 - eta) of the power in the direction it flows: motoring needs tau/(N eta) on the rotor,
/// back-driving gives tau eta / N.
MotorElectrical motor_electrical(const MotorParameters& m, double output_torque, double output_speed);

/// Rover frame ("chassis frame" of seed 004 §2.3): x forward, y left, z up; origin at the centre
/// of the four wheel centres in the nominal configuration (gimbal yaw = roll = 0), at axle height.
struct RoverParameters {
  // ---- Table 1 -------------------------------------------------------------------------------
  double wheelbase = 0.86;      ///< [m]
  double track = 0.80;          ///< [m]
  double wheel_radius = 0.17;   ///< [m] (diameter 0.34)
  double wheel_width = 0.13;    ///< [m]

  // ---- mass model (§3.2: bogie assembly vs chassis; values are assumptions, total 75 kg) -------
  double chassis_mass = 51.0;         ///< chassis + mast + avionics, without rear wheel assemblies [kg]
  double bogie_mass = 12.0;           ///< bogie beam + bogie frame, without its wheel assemblies [kg]
  double wheel_assembly_mass = 3.0;   ///< one wheel + hub motor + fork below the FTS [kg]
  /// Chassis CoM (x_c, y_c, z_c) in the rover frame (assumption: behind the centre, high mast).
  Eigen::Vector3d chassis_com{-0.12, 0.0, 0.33};
  /// Bogie CoM height above the axles (z_b of §3.2; CoM in the bogie's median/transverse planes).
  double bogie_com_height = 0.10;
  /// Principal inertias about the CoM [kg m^2] (assumption: boxes of the collision sizes below).
  Eigen::Vector3d chassis_inertia{1.9, 3.2, 4.2};
  Eigen::Vector3d bogie_inertia{0.55, 0.05, 0.55};
  /// Wheel assembly inertia: spin (about the axle, without the reflected rotor) and transverse.
  double wheel_spin_inertia = 0.045;
  double wheel_transverse_inertia = 0.03;

  // ---- Active Gimbal Suspension (§2.2) -----------------------------------------------------
  /// Collocated yaw/roll axes intersect above the front-axle centre (SPEC suggestion), at this
  /// height above the axles [m] (assumption; Table 1 bogie clearance 0.30 m fits below).
  double gimbal_height = 0.25;
  double yaw_limit = 0.7853981633974483;    ///< |psi| <= 45 deg (assumption)
  double roll_limit = 0.5235987755982988;   ///< |phi| <= 30 deg (assumption)
  double stop_stiffness = 2.0e4;            ///< joint stops as spring [N m/rad] (§3.1)
  double stop_damping = 300.0;              ///< ... and damper [N m s/rad]
  double yaw_brake_torque = 300.0;          ///< holding torque of the yaw brake, gimbal off [N m]
  double clutch_align_speed = 0.1745329252; ///< bound of the alignment velocity (10 deg/s)
  double clutch_align_gain = 4.0;           ///< velocity feedback gain of the alignment [1/s]
  double clutch_align_tolerance = 0.0087266463;  ///< pins engage below this misalignment (0.5 deg)

  // ---- actuators -----------------------------------------------------------------------------
  MotorParameters wheel_motor{};                                    ///< 50:1
  MotorParameters gimbal_motor{0.07, 0.6, 160.0, 0.85, 12.0, 2e-5};  ///< 160:1

  // ---- sensors -------------------------------------------------------------------------------
  /// Force–torque sensors sit this far above each wheel centre, axes parallel to the mount's
  /// frame (chassis for the rear wheels, bogie for the front) (assumption; §2.1.2).
  double fts_height = 0.20;

  // ---- collision boxes of the bodies vs rigid obstacles (sizes in the body frame) -------------
  Eigen::Vector3d chassis_box{0.80, 0.55, 0.25};      ///< bottom 0.42 m above ground (Table 1)
  Eigen::Vector3d chassis_box_centre{-0.05, 0.0, 0.375};
  Eigen::Vector3d bogie_box{0.12, 0.66, 0.08};        ///< bottom 0.30 m above ground (Table 1)
  double bogie_box_height = 0.17;                     ///< centre above the axles [m]

  /// Throws std::invalid_argument naming the first invalid field.
  void validate() const;

  double total_mass() const { return chassis_mass + bogie_mass + 4.0 * wheel_assembly_mass; }
  /// Nominal wheel centre i (0 FL, 1 FR, 2 RL, 3 RR) in the rover frame at psi = phi = 0.
  Eigen::Vector3d wheel_centre(int i) const;
  /// Gimbal centre (intersection of the yaw and roll axes) in the rover frame.
  Eigen::Vector3d gimbal_point() const { return {0.5 * wheelbase, 0.0, gimbal_height}; }
  /// Torus of the airless tyre (§2.1.1, §3.3): tube radius b/2, centre-circle radius r - b/2.
  double tyre_tube_radius() const { return 0.5 * wheel_width; }
};

/// Wheel order used everywhere (arrays of four): front-left, front-right, rear-left, rear-right.
enum WheelIndex : int { kFL = 0, kFR = 1, kRL = 2, kRR = 3 };

}  // namespace ernest::dynamics
