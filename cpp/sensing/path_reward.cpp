#include "ernest/sensing/path_reward.hpp"

#include <cmath>

#include "ernest/common/validation.hpp"

namespace ernest::sensing {

double PathLine::a() const { return -std::sin(heading); }
double PathLine::b() const { return std::cos(heading); }
double PathLine::c() const { return -a() * x0 - b() * y0; }

double PathLine::progress(double x_prev, double y_prev, double x, double y) const {
  require(std::isfinite(x_prev) && std::isfinite(y_prev) && std::isfinite(x) && std::isfinite(y),
          "PathLine.progress: x_prev, y_prev, x and y must be finite");
  return b() * (x - x_prev) - a() * (y - y_prev);
}

double PathLine::lateral_deviation(double x, double y) const {
  require(std::isfinite(x) && std::isfinite(y), "PathLine.lateral_deviation: x and y must be finite");
  const double d = a() * x + b() * y + c();
  require(std::isfinite(d), "PathLine.lateral_deviation: not finite (PathLine x0, y0 and heading "
                            "must be finite, and the values not near the double range)");
  return d;
}

double PathLine::heading_deviation(double yaw) const {
  require(std::isfinite(yaw), "PathLine.heading_deviation: yaw must be finite");
  double d = std::remainder(yaw - heading, 2.0 * M_PI);  // in [-pi, pi]
  if (d <= -M_PI) d += 2.0 * M_PI;
  return d;
}

double PathLine::arc_length(double x, double y) const { return progress(x0, y0, x, y); }

void RewardWeights::validate() const {
  require_in_range("RewardWeights", "w_s", w_s, 0.0, kInf);
  require_in_range("RewardWeights", "w_delta", w_delta, 0.0, kInf);
  require_in_range("RewardWeights", "w_tau", w_tau, 0.0, kInf);
  // A policy period below a microsecond is no control loop, and w_s / dt overflows near 5e-324.
  require_in_range("RewardWeights", "dt", dt, 1e-6, 3600.0);
}

RewardTerms compute_reward(const PathLine& path, double x_prev, double y_prev, double x, double y,
                           double roll_torque, const RewardWeights& w) {
  require(std::isfinite(x_prev) && std::isfinite(y_prev) && std::isfinite(x) && std::isfinite(y) &&
              std::isfinite(roll_torque),
          "compute_reward: positions and roll_torque must be finite");
  w.validate();
  RewardTerms t;
  t.progress = path.progress(x_prev, y_prev, x, y);
  t.lateral = path.lateral_deviation(x, y);
  t.progress_term = w.w_s * t.progress / w.dt;
  t.lateral_term = -w.w_delta * t.lateral * t.lateral;
  t.torque_term = -w.w_tau * std::abs(roll_torque);
  t.reward = t.progress_term + t.lateral_term + t.torque_term;
  require(std::isfinite(t.reward),
          "compute_reward: the reward overflows (positions, roll_torque or weights too large)");
  return t;
}

}  // namespace ernest::sensing
