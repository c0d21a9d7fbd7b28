// The Asterix multi-modal rover of seed 000 (§5 "Asterix Platform") and its wheel kinematics
// (eqs 20–23), integrated with Boost.Numeric.Odeint.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <stdexcept>

namespace ernest::opt {

/// Joint order of every Asterix joint-space vector: centre steering, then rear roll.
inline constexpr int kSteering = 0;
inline constexpr int kRoll = 1;
inline constexpr int kAsterixJoints = 2;

/// Asterix model parameters in SI units. The paper gives only the mass (7.8 kg), the joint layout
/// (four wheels, centre steering joint, rear roll joint), the kinematics (eqs 20–23) and the wheel
/// motor torque constant (1.45 N m/A); every other value is OUR CHOICE for a rover of that size
/// (≈ 0.4 m wheelbase, 0.15 m wheels), documented field by field.
///
/// Sign conventions: theta (steering) > 0 turns the front body clockwise relative to the rear, which
/// makes eq 22 hold as printed: heading rate = (V_r / l_x) tan(-theta/2). `l_x` is the distance from
/// the steering joint to each axle: for an articulated vehicle with the joint midway between the
/// axles, the no-skid derivation gives exactly eq 22's form only with that reading (with l_x the
/// full axle-to-axle distance the rate would be twice as large).
struct AsterixParameters {
  double mass = 7.8;                 ///< [kg] (paper §5)
  double wheel_radius = 0.075;       ///< R [m] (ours)
  double l_x = 0.20;                 ///< steering joint to axle [m] (ours; wheelbase 2 l_x)
  double half_track = 0.15;          ///< lateral wheel offset from the axle centre [m] (ours)
  double forward_speed = 0.05;       ///< V_r during gaits and transitions [m/s] (ours)
  double steering_limit = 0.60;      ///< |theta| <= [rad] (ours, ≈ 34°)
  double roll_limit = 0.35;          ///< |roll| <= [rad] (ours, ≈ 20°)
  double steering_velocity_limit = 0.60;      ///< [rad/s] (ours)
  double roll_velocity_limit = 0.60;          ///< [rad/s] (ours)
  double steering_acceleration_limit = 1.50;  ///< [rad/s^2], Naive trapezoid (ours)
  double roll_acceleration_limit = 1.50;      ///< [rad/s^2], Naive trapezoid (ours)
  // Actuator model for the energy of eqs 25–27 (ours; see metrics.hpp).
  double steering_inertia = 0.06;    ///< half-body yaw inertia about the joint + reflected rotor [kg m^2]
  double roll_inertia = 0.02;        ///< rear body roll inertia + reflected rotor [kg m^2]
  double joint_viscous = 0.4;        ///< gearbox viscous friction [N m s/rad]
  double joint_coulomb = 0.25;       ///< gearbox Coulomb friction [N m]
  /// Torque per radian of rear roll needed to shift the load (wheel-walking lifts a wheel at about
  /// m g half_track / 4 ≈ 2.9 N m, reached near 0.35 rad) [N m/rad].
  double roll_stiffness = 8.0;
  double rolling_resistance = 0.10;  ///< C_rr of a wheel on sand [-] (ours)
  double wheel_torque_constant = 1.45;  ///< k_t [N m/A] (paper §5, eq 26)
  double gravity = 9.81;             ///< [m/s^2]

  /// Throws std::invalid_argument naming the first field outside its allowed range.
  void validate() const;
  /// Joint-space limits in the joint order (steering, roll).
  Eigen::Vector2d position_limit() const { return {steering_limit, roll_limit}; }
  Eigen::Vector2d velocity_limit() const { return {steering_velocity_limit, roll_velocity_limit}; }
  Eigen::Vector2d acceleration_limit() const {
    return {steering_acceleration_limit, roll_acceleration_limit};
  }
  Eigen::Vector2d inertia() const { return {steering_inertia, roll_inertia}; }
};

/// Planar pose of the rover's reference point (the centroid of the four wheel contacts, i.e. eq 23
/// averaged over the wheels) and its heading (the mean of the four wheel yaws beta_i).
struct Pose2 {
  double x = 0.0, y = 0.0, heading = 0.0;
};
/// a ⊕ b: pose b expressed in a's frame, mapped to the world.
Pose2 compose(const Pose2& a, const Pose2& b);
/// a^-1 ⊕ b: pose b relative to pose a.
Pose2 relative(const Pose2& a, const Pose2& b);

/// Steering trajectory for the integrator: fills theta and dtheta/dt at time t.
using SteeringFunction = std::function<void(double t, double& theta, double& theta_rate)>;

/// Tolerances of the adaptive Dormand–Prince integration.
struct IntegrationOptions {
  double abs_tol = 1e-10;
  double rel_tol = 1e-9;
  int max_steps = 20000;  ///< per integration; more raises KinematicsError ("no progress")
  void validate() const;
};

/// Raised when odeint cannot make progress (step-size underflow, too many steps, non-finite state).
class KinematicsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Wheel states of eqs 20–22: x_i, y_i, beta_i for wheels 1..4 = front-left, front-right,
/// rear-left, rear-right (eq 22's sign (-1)^{i(i+1)/2} is -1 for wheels 1, 2 and +1 for 3, 4).
using WheelStates = std::array<std::array<double, 3>, 4>;

/// Immutable kinematic model. Wheels are synchronised to the steering (the "wheel synchroniser"
/// of §5) so the ideal motion has no skid: each axle moves along its body's heading.
class AsterixKinematics {
 public:
  explicit AsterixKinematics(const AsterixParameters& params);
  const AsterixParameters& params() const { return p_; }

  /// Rover heading rate: eq 22 averaged over the four wheels (the ±theta_dot/2 terms cancel).
  double heading_rate(double theta) const;
  /// Per-wheel yaw rates d beta_i/dt of eq 22.
  std::array<double, 4> wheel_yaw_rates(double theta, double theta_rate) const;
  /// Wheel angular speeds omega_i [rad/s] of the synchroniser: R omega_i is the axle speed plus the
  /// body's yaw rate times the wheel's lateral offset (no longitudinal or lateral skid).
  std::array<double, 4> wheel_speeds(double theta, double theta_rate) const;
  /// World-frame velocity of the reference point and heading rate at heading psi:
  /// v = V_r cos(theta/2) e(psi) + (l_x theta_dot / 2) tan(theta/2) sin(theta/2) n(psi).
  void pose_rate(double psi, double theta, double theta_rate, double& dx, double& dy,
                 double& dpsi) const;
  /// Radius of the circle traced by the reference point at constant steering theta != 0:
  /// l_x cos(theta/2) / tan(|theta|/2) (axle centres: l_x / tan(|theta|/2)); inf at theta = 0 (a
  /// straight line).
  double turning_radius(double theta) const;

  /// Pose at t1 from `start` at t0, integrating the averaged eqs 20–23 with an adaptive
  /// Dormand–Prince stepper. Throws KinematicsError when odeint makes no progress.
  Pose2 integrate(const SteeringFunction& steering, double t0, double t1, const Pose2& start,
                  const IntegrationOptions& options = {}) const;
  /// The twelve wheel states of eqs 20–22 integrated literally, starting from the wheel positions
  /// implied by `start` and theta(t0). Used to cross-check integrate() (eq 23).
  WheelStates integrate_wheels(const SteeringFunction& steering, double t0, double t1,
                               const Pose2& start, const IntegrationOptions& options = {}) const;
  /// Wheel contact positions and yaws for a reference pose and steering angle (rigid geometry).
  WheelStates wheel_states(const Pose2& pose, double theta) const;
  /// Eq 23: reference pose from the wheel states (mean position, mean yaw).
  static Pose2 pose_from_wheels(const WheelStates& wheels);

 private:
  AsterixParameters p_;
};

}  // namespace ernest::opt
