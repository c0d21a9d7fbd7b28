// Gaits (gait.hpp, seed 000 eq 1): phase to joint space, and their workspace trajectories
// G(t) (eqs 6–7).
#include "ernest/opt/gait.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "ernest/common/validation.hpp"

namespace ernest::opt {

Gait::Gait(std::string name, double period, Eigen::VectorXd offset, Eigen::VectorXd amplitude,
           Eigen::VectorXd phase)
    : name_(std::move(name)),
      period_(period),
      offset_(std::move(offset)),
      amplitude_(std::move(amplitude)),
      phase_(std::move(phase)) {
  require_positive("Gait", "period", period_);
  require(offset_.size() >= 1, "Gait: at least one joint is required");
  require(amplitude_.size() == offset_.size() && phase_.size() == offset_.size(),
          "Gait: offset, amplitude and phase must have the same length");
  for (int j = 0; j < joints(); ++j) {
    require_finite("Gait", "offset", offset_[j]);
    require_finite("Gait", "amplitude", amplitude_[j]);
    require_finite("Gait", "phase", phase_[j]);
  }
}

void Gait::evaluate(int j, double t, double& q, double& dq, double& ddq) const {
  require(std::isfinite(t), "Gait: the phase time t must be finite");
  const double w = 2.0 * M_PI / period_;
  const double a = w * t + phase_[j];
  const double s = std::sin(a), c = std::cos(a);
  q = offset_[j] + amplitude_[j] * s;
  dq = amplitude_[j] * w * c;
  ddq = -amplitude_[j] * w * w * s;
  require(std::isfinite(ddq), "Gait: the acceleration overflows (period too small)");
}

Eigen::VectorXd Gait::position(double t) const {
  Eigen::VectorXd out(joints());
  double q, dq, ddq;
  for (int j = 0; j < joints(); ++j) {
    evaluate(j, t, q, dq, ddq);
    out[j] = q;
  }
  return out;
}

Eigen::VectorXd Gait::velocity(double t) const {
  Eigen::VectorXd out(joints());
  double q, dq, ddq;
  for (int j = 0; j < joints(); ++j) {
    evaluate(j, t, q, dq, ddq);
    out[j] = dq;
  }
  return out;
}

Eigen::VectorXd Gait::acceleration(double t) const {
  Eigen::VectorXd out(joints());
  double q, dq, ddq;
  for (int j = 0; j < joints(); ++j) {
    evaluate(j, t, q, dq, ddq);
    out[j] = ddq;
  }
  return out;
}

void Gait::check_limits(const Eigen::VectorXd& position_limit,
                        const Eigen::VectorXd& velocity_limit) const {
  require(position_limit.size() == joints() && velocity_limit.size() == joints(),
          "Gait '" + name_ + "': limits must have one entry per joint");
  const double w = 2.0 * M_PI / period_;
  for (int j = 0; j < joints(); ++j) {
    const double peak = std::abs(offset_[j]) + std::abs(amplitude_[j]);
    const double peak_rate = std::abs(amplitude_[j]) * w;
    if (peak > position_limit[j] || peak_rate > velocity_limit[j]) {
      std::ostringstream os;
      os << "Gait '" << name_ << "' joint " << j << " reaches |q| = " << peak << " rad and |dq| = "
         << peak_rate << " rad/s, beyond the limits " << position_limit[j] << " rad, "
         << velocity_limit[j] << " rad/s";
      throw std::invalid_argument(os.str());
    }
  }
}

Gait squirming(const AsterixParameters& p) {
  p.validate();
  return Gait("squirming", 8.0, Eigen::Vector2d(0.0, 0.0),
              Eigen::Vector2d(0.92 * p.steering_limit, 0.0), Eigen::Vector2d(0.5 * M_PI, 0.0));
}

Gait wheel_walking(const AsterixParameters& p) {
  p.validate();
  return Gait("wheel_walking", 10.0, Eigen::Vector2d(0.0, 0.0),
              Eigen::Vector2d(std::min(0.35, 0.9 * p.steering_limit),
                              std::min(0.30, 0.9 * p.roll_limit)),
              Eigen::Vector2d(0.5 * M_PI, M_PI));
}

Pose2 gait_pose(const AsterixKinematics& kin, const Gait& gait, double t_start, double t_end,
                const Pose2& start, const IntegrationOptions& options) {
  require(t_end >= t_start, "gait_pose: t_end must be >= t_start");
  auto steering = [&gait](double t, double& theta, double& rate) {
    double acc;
    gait.evaluate(kSteering, t, theta, rate, acc);
  };
  return kin.integrate(steering, t_start, t_end, start, options);
}

}  // namespace ernest::opt
