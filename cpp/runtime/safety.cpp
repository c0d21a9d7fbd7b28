#include "ernest/runtime/safety.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ernest/common/validation.hpp"

namespace ernest::runtime {

void LimitOptions::validate() const {
  velocity.validate();
  if (joint_margin) require_in_range("LimitOptions", "joint_margin", *joint_margin, 0.0, 0.5);
  require_positive("LimitOptions", "max_wheel_speed", max_wheel_speed);
}

Eigen::Vector3d limit_command(const Eigen::Vector3d& c, double psi, double phi,
                              const dynamics::RoverParameters& p, const LimitOptions& o) {
  if (!c.allFinite() || !std::isfinite(psi) || !std::isfinite(phi)) return Eigen::Vector3d::Zero();
  Eigen::Vector3d out(std::clamp(c[0], 0.0, o.velocity.vx_max),
                      std::clamp(c[1], -o.velocity.yaw_rate_max, o.velocity.yaw_rate_max),
                      std::clamp(c[2], -o.velocity.roll_rate_max, o.velocity.roll_rate_max));
  if (o.joint_margin) {
    const double margin = *o.joint_margin;
    if ((psi >= p.yaw_limit - margin && out[1] > 0.0) ||
        (psi <= -p.yaw_limit + margin && out[1] < 0.0))
      out[1] = 0.0;
    if ((phi >= p.roll_limit - margin && out[2] > 0.0) ||
        (phi <= -p.roll_limit + margin && out[2] < 0.0))
      out[2] = 0.0;
  }
  return out;
}

const char* to_string(Fault f) {
  switch (f) {
    case Fault::None: return "none";
    case Fault::StaleFts: return "stale force-torque data";
    case Fault::StalePose: return "stale pose";
    case Fault::StaleJoints: return "stale joint encoders";
    case Fault::NonFinite: return "non-finite sensor data";
    case Fault::Inference: return "inference failed";
    case Fault::Observation: return "observation failed";
  }
  return "?";
}

void WatchdogOptions::validate() const {
  require_positive("WatchdogOptions", "max_age", max_age);
  require_in_range("WatchdogOptions", "recovery_time", recovery_time, 0.0, 60.0);
}

Fault check_frame(const SensorFrame& f, double now, const WatchdogOptions& o, std::string& why) {
  auto stale = [&](double stamp, Fault fault, const char* what) {
    if (std::isfinite(stamp) && now - stamp <= o.max_age) return false;
    std::ostringstream os;
    os << what << " is " << (now - stamp) * 1e3 << " ms old (limit " << o.max_age * 1e3 << " ms)";
    why = os.str();
    (void)fault;
    return true;
  };
  if (stale(f.fts_stamp, Fault::StaleFts, "force-torque data")) return Fault::StaleFts;
  if (stale(f.pose_stamp, Fault::StalePose, "pose estimate")) return Fault::StalePose;
  if (stale(f.joint_stamp, Fault::StaleJoints, "joint encoders")) return Fault::StaleJoints;
  auto bad = [&](bool finite, const char* what) {
    if (finite) return false;
    why = std::string("non-finite ") + what;
    return true;
  };
  bool wheels = true;
  for (double w : f.wheel_speed) wheels = wheels && std::isfinite(w);
  if (bad(f.fts.allFinite(), "force-torque sample") || bad(f.position.allFinite(), "position") ||
      bad(f.orientation.coeffs().allFinite(), "orientation") ||
      bad(std::isfinite(f.roll) && std::isfinite(f.pitch) && std::isfinite(f.yaw), "attitude") ||
      bad(f.body_angular_velocity.allFinite(), "angular velocity") ||
      bad(std::isfinite(f.gimbal_yaw) && std::isfinite(f.gimbal_roll), "gimbal angle") ||
      bad(wheels, "wheel speed"))
    return Fault::NonFinite;
  return Fault::None;
}

Watchdog::Watchdog(const WatchdogOptions& options) : options_(options) { options_.validate(); }

bool Watchdog::trip(Fault fault, double now, const std::string& why) {
  (void)now;
  healthy_since_ = -1.0;
  const bool fresh = fault_ == Fault::None;
  if (fresh) ++trips_;
  fault_ = fault;
  reason_ = why;
  return fresh;
}

bool Watchdog::healthy(double now) {
  if (fault_ == Fault::None) return false;
  if (healthy_since_ < 0.0) healthy_since_ = now;
  if (now - healthy_since_ < options_.recovery_time - 1e-12) return false;
  fault_ = Fault::None;
  reason_.clear();
  return true;
}

}  // namespace ernest::runtime
