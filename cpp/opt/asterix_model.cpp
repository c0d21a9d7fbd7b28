// The Asterix rover's wheel kinematics (asterix_model.hpp, seed 000 eqs 20–23): parameters
// checked, the no-skid synchroniser and the pose integrated from the wheels.
#include "ernest/opt/asterix_model.hpp"

#include <array>
#include <cmath>
#include <vector>

#include "ernest/common/validation.hpp"
#include "ernest/opt/ode.hpp"

namespace ernest::opt {

namespace {
constexpr const char* kOwner = "AsterixParameters";
}

void AsterixParameters::validate() const {
  require_in_range(kOwner, "mass", mass, 0.1, 1000.0);
  require_in_range(kOwner, "wheel_radius", wheel_radius, 0.01, 1.0);
  require_in_range(kOwner, "l_x", l_x, 0.02, 5.0);
  require_in_range(kOwner, "half_track", half_track, 0.01, 5.0);
  require_in_range(kOwner, "forward_speed", forward_speed, 0.0, 5.0);
  // |theta/2| < pi/2 keeps tan(theta/2) in eq 22 finite; 2.5 rad is far beyond any real joint.
  require_in_range(kOwner, "steering_limit", steering_limit, 1e-3, 2.5);
  require_in_range(kOwner, "roll_limit", roll_limit, 1e-3, 1.5);
  require_in_range(kOwner, "steering_velocity_limit", steering_velocity_limit, 1e-3, 100.0);
  require_in_range(kOwner, "roll_velocity_limit", roll_velocity_limit, 1e-3, 100.0);
  require_in_range(kOwner, "steering_acceleration_limit", steering_acceleration_limit, 1e-3, 1e3);
  require_in_range(kOwner, "roll_acceleration_limit", roll_acceleration_limit, 1e-3, 1e3);
  require_in_range(kOwner, "steering_inertia", steering_inertia, 0.0, 100.0);
  require_in_range(kOwner, "roll_inertia", roll_inertia, 0.0, 100.0);
  require_in_range(kOwner, "joint_viscous", joint_viscous, 0.0, 1e3);
  require_in_range(kOwner, "joint_coulomb", joint_coulomb, 0.0, 1e3);
  require_in_range(kOwner, "roll_stiffness", roll_stiffness, 0.0, 1e4);
  require_in_range(kOwner, "rolling_resistance", rolling_resistance, 0.0, 2.0);
  require_positive(kOwner, "wheel_torque_constant", wheel_torque_constant);
  require_in_range(kOwner, "gravity", gravity, 0.1, 100.0);
}

void IntegrationOptions::validate() const {
  require_in_range("IntegrationOptions", "abs_tol", abs_tol, 1e-15, 1.0);
  require_in_range("IntegrationOptions", "rel_tol", rel_tol, 1e-15, 1.0);
  require_in_range("IntegrationOptions", "max_steps", max_steps, 1, 1e8);
}

Pose2 compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.heading), s = std::sin(a.heading);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, a.heading + b.heading};
}

Pose2 relative(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.heading), s = std::sin(a.heading);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, b.heading - a.heading};
}

AsterixKinematics::AsterixKinematics(const AsterixParameters& params) : p_(params) {
  p_.validate();
}

double AsterixKinematics::heading_rate(double theta) const {
  // Eq 22, mean over i: (V_r / l_x) tan(-theta/2).
  return p_.forward_speed / p_.l_x * std::tan(-0.5 * theta);
}

std::array<double, 4> AsterixKinematics::wheel_yaw_rates(double theta, double theta_rate) const {
  const double base = heading_rate(theta);
  // Eq 22: (-1)^{i(i+1)/2} = -1, -1, +1, +1 for i = 1..4 (front bodies turn by -theta/2).
  return {base - 0.5 * theta_rate, base - 0.5 * theta_rate, base + 0.5 * theta_rate,
          base + 0.5 * theta_rate};
}

std::array<double, 4> AsterixKinematics::wheel_speeds(double theta, double theta_rate) const {
  // No-skid articulated-frame kinematics (our derivation, joint midway between the axles): with the
  // front body at heading psi - theta/2 and the rear at psi + theta/2, the axle speeds are
  // v_front = V_r - (l_x theta_dot / 2) tan(theta/2), v_rear = V_r + (l_x theta_dot / 2) tan(theta/2)
  // and a wheel at lateral offset +b (left) rolls at v_axle - b * beta_dot_body.
  const double t = std::tan(0.5 * theta);
  const double v_front = p_.forward_speed - 0.5 * p_.l_x * theta_rate * t;
  const double v_rear = p_.forward_speed + 0.5 * p_.l_x * theta_rate * t;
  const auto yaw = wheel_yaw_rates(theta, theta_rate);
  const double b = p_.half_track, r = p_.wheel_radius;
  return {(v_front - b * yaw[0]) / r, (v_front + b * yaw[1]) / r, (v_rear - b * yaw[2]) / r,
          (v_rear + b * yaw[3]) / r};
}

void AsterixKinematics::pose_rate(double psi, double theta, double theta_rate, double& dx,
                                  double& dy, double& dpsi) const {
  const double h = 0.5 * theta;
  const double f = p_.forward_speed * std::cos(h);                  // along e(psi)
  const double l = 0.5 * p_.l_x * theta_rate * std::tan(h) * std::sin(h);  // along n(psi)
  const double c = std::cos(psi), s = std::sin(psi);
  dx = f * c - l * s;
  dy = f * s + l * c;
  dpsi = heading_rate(theta);
}

double AsterixKinematics::turning_radius(double theta) const {
  require_finite("AsterixKinematics.turning_radius", "theta", theta);
  const double h = 0.5 * std::abs(theta);
  if (h == 0.0) return kInf;
  return p_.l_x * std::cos(h) / std::tan(h);
}

Pose2 AsterixKinematics::integrate(const SteeringFunction& steering, double t0, double t1,
                                   const Pose2& start, const IntegrationOptions& options) const {
  require(t1 >= t0, "AsterixKinematics.integrate: t1 must be >= t0");
  std::array<double, 3> x{start.x, start.y, start.heading};
  auto rhs = [&](const std::array<double, 3>& s, std::array<double, 3>& ds, double t) {
    double theta = 0.0, rate = 0.0;
    steering(t, theta, rate);
    pose_rate(s[2], theta, rate, ds[0], ds[1], ds[2]);
  };
  detail::integrate_checked(rhs, x, t0, t1, options, "AsterixKinematics.integrate");
  return {x[0], x[1], x[2]};
}

WheelStates AsterixKinematics::wheel_states(const Pose2& pose, double theta) const {
  // Reference point C = midpoint of the axle centres; joint P = C + l_x sin(theta/2) n(psi).
  const double h = 0.5 * theta, psi = pose.heading;
  const double px = pose.x - p_.l_x * std::sin(h) * std::sin(psi);
  const double py = pose.y + p_.l_x * std::sin(h) * std::cos(psi);
  const double bf = psi - h, br = psi + h;  // body headings
  const double fx = px + p_.l_x * std::cos(bf), fy = py + p_.l_x * std::sin(bf);
  const double rx = px - p_.l_x * std::cos(br), ry = py - p_.l_x * std::sin(br);
  const double b = p_.half_track;
  WheelStates w;
  w[0] = {fx - b * std::sin(bf), fy + b * std::cos(bf), bf};  // front-left
  w[1] = {fx + b * std::sin(bf), fy - b * std::cos(bf), bf};  // front-right
  w[2] = {rx - b * std::sin(br), ry + b * std::cos(br), br};  // rear-left
  w[3] = {rx + b * std::sin(br), ry - b * std::cos(br), br};  // rear-right
  return w;
}

Pose2 AsterixKinematics::pose_from_wheels(const WheelStates& w) {
  Pose2 p;
  for (const auto& s : w) {
    p.x += 0.25 * s[0];
    p.y += 0.25 * s[1];
    p.heading += 0.25 * s[2];
  }
  return p;
}

WheelStates AsterixKinematics::integrate_wheels(const SteeringFunction& steering, double t0,
                                                double t1, const Pose2& start,
                                                const IntegrationOptions& options) const {
  require(t1 >= t0, "AsterixKinematics.integrate_wheels: t1 must be >= t0");
  double theta0 = 0.0, rate0 = 0.0;
  steering(t0, theta0, rate0);
  const WheelStates w0 = wheel_states(start, theta0);
  std::array<double, 12> x{};
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) x[3 * i + k] = w0[i][k];
  const double r = p_.wheel_radius;
  auto rhs = [&](const std::array<double, 12>& s, std::array<double, 12>& ds, double t) {
    double theta = 0.0, rate = 0.0;
    steering(t, theta, rate);
    const auto omega = wheel_speeds(theta, rate);
    const auto yaw = wheel_yaw_rates(theta, rate);
    for (int i = 0; i < 4; ++i) {
      const double beta = s[3 * i + 2];
      ds[3 * i + 0] = r * omega[i] * std::cos(beta);  // eq 20
      ds[3 * i + 1] = r * omega[i] * std::sin(beta);  // eq 21
      ds[3 * i + 2] = yaw[i];                          // eq 22
    }
  };
  detail::integrate_checked(rhs, x, t0, t1, options, "AsterixKinematics.integrate_wheels");
  WheelStates w;
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) w[i][k] = x[3 * i + k];
  return w;
}

}  // namespace ernest::opt
