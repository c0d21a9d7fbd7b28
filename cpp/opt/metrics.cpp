// Per-transition metrics (metrics.hpp, seed 000 eqs 24–28): cost of transport, energy, distance,
// maximum acceleration, heading.
#include "ernest/opt/metrics.hpp"

#include <algorithm>
#include <cmath>

#include "ernest/common/validation.hpp"
#include "ernest/opt/gait.hpp"

namespace ernest::opt {

void MetricsOptions::validate() const {
  require_in_range("MetricsOptions", "telemetry_rate", telemetry_rate, 1.0, 1e5);
  require_in_range("MetricsOptions", "energy_step", energy_step, 1e-6, 1.0);
  integration.validate();
}

namespace {
double joint_inertia(const AsterixParameters& p, int j) {
  return j == kSteering ? p.steering_inertia : p.roll_inertia;
}
}  // namespace

TransitionMetrics evaluate_metrics(const TransitionProblem& problem, const TransitionResult& r,
                                   const MetricsOptions& options) {
  problem.validate();
  options.validate();
  require(r.joints() == problem.joints(), "evaluate_metrics: result and problem joints differ");
  const AsterixParameters& p = problem.rover;
  const AsterixKinematics kin(p);
  const int nj = problem.joints();
  const double T = r.duration;
  TransitionMetrics m;
  m.duration = T;

  // Workspace: G1(t1) from the origin, the executed transition, and the eq 7 target.
  m.start_pose = gait_pose(kin, problem.from, 0.0, problem.t1, Pose2{}, options.integration);
  auto steering = [&r](double tau, double& th, double& rate) {
    double acc;
    r.evaluate(kSteering, tau, th, rate, acc);
  };
  const Pose2 moved = kin.integrate(steering, 0.0, T, Pose2{}, options.integration);
  m.end_pose = compose(m.start_pose, moved);
  const double sigma = r.end_phase;
  m.target_pose = compose(m.start_pose, gait_pose(kin, problem.to, sigma - T, sigma, Pose2{},
                                                  options.integration));
  m.heading_change = m.end_pose.heading - m.start_pose.heading;
  m.heading_deviation = m.end_pose.heading - m.target_pose.heading;
  m.position_deviation =
      std::hypot(m.end_pose.x - m.target_pose.x, m.end_pose.y - m.target_pose.y);
  m.distance = std::hypot(m.end_pose.x - m.start_pose.x, m.end_pose.y - m.start_pose.y);

  // Boundary residuals (eqs 2–5).
  for (int j = 0; j < nj; ++j) {
    double q, dq, ddq, g, dg, ddg;
    r.evaluate(j, 0.0, q, dq, ddq);
    problem.from.evaluate(j, problem.t1, g, dg, ddg);
    m.start_position_residual = std::max(m.start_position_residual, std::abs(q - g));
    m.start_velocity_residual = std::max(m.start_velocity_residual, std::abs(dq - dg));
    r.evaluate(j, T, q, dq, ddq);
    problem.to.evaluate(j, sigma, g, dg, ddg);
    m.end_position_residual = std::max(m.end_position_residual, std::abs(q - g));
    m.end_velocity_residual = std::max(m.end_velocity_residual, std::abs(dq - dg));
  }

  // Maximum joint acceleration between consecutive telemetry samples of the executed motion.
  m.max_acceleration = Eigen::VectorXd::Zero(nj);
  const double dt = 1.0 / options.telemetry_rate;
  const int K = static_cast<int>(std::ceil(T / dt));
  for (int j = 0; j < nj; ++j) {
    auto pos = [&](int k) {
      double q, dq, ddq;
      r.executed(problem, j, problem.t1 + k * dt, q, dq, ddq);
      return q;
    };
    double prev = pos(-1), cur = pos(0);
    for (int k = 0; k <= K; ++k) {
      const double next = pos(k + 1);
      m.max_acceleration[j] =
          std::max(m.max_acceleration[j], std::abs(next - 2.0 * cur + prev) / (dt * dt));
      prev = cur;
      cur = next;
    }
  }

  // Energy (eqs 25–27) with the actuator model documented in metrics.hpp.
  const int steps = std::max(1, static_cast<int>(std::ceil(T / options.energy_step)));
  const double h = T / steps;
  const double wheel_force = p.rolling_resistance * p.mass * p.gravity / 4.0;
  for (int k = 0; k < steps; ++k) {
    const double tau = (k + 0.5) * h;
    for (int j = 0; j < nj; ++j) {
      double q, dq, ddq;
      r.evaluate(j, tau, q, dq, ddq);
      double torque = joint_inertia(p, j) * ddq + p.joint_viscous * dq +
                      p.joint_coulomb * std::tanh(dq / 0.01);
      if (j == kRoll) torque += p.roll_stiffness * q;
      m.energy_articulation += std::max(0.0, torque * dq) * h;
    }
    double th, rate, acc;
    r.evaluate(kSteering, tau, th, rate, acc);
    const auto omega = kin.wheel_speeds(th, rate);
    for (double w : omega) m.energy_wheels += wheel_force * std::abs(p.wheel_radius * w) * h;
  }
  for (int j = 0; j < nj; ++j) {
    double q, dq, ddq, g, dg, ddg;
    r.evaluate(j, 0.0, q, dq, ddq);
    problem.from.evaluate(j, problem.t1, g, dg, ddg);
    m.energy_articulation += std::max(0.0, 0.5 * joint_inertia(p, j) * (dq * dq - dg * dg));
    r.evaluate(j, T, q, dq, ddq);
    problem.to.evaluate(j, sigma, g, dg, ddg);
    m.energy_articulation += std::max(0.0, 0.5 * joint_inertia(p, j) * (dg * dg - dq * dq));
  }
  m.energy = m.energy_articulation + m.energy_wheels;
  m.cost_of_transport = m.distance > 0.0 ? m.energy / (p.mass * p.gravity * m.distance) : kInf;
  return m;
}

}  // namespace ernest::opt
