#include "ernest/runtime/telemetry.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace ernest::runtime {

const char* Telemetry::header() {
  // Each column names its unit; the actions are the policy's normalised outputs in [-1, 1].
  return "time [s],x [m],y [m],z [m],roll [rad],pitch [rad],yaw [rad],gimbal_yaw [rad],"
         "gimbal_roll [rad],load_fl [N],load_fr [N],load_rl [N],load_rr [N],action_vx [-],"
         "action_yaw [-],action_roll [-],cmd_vx [m/s],cmd_yaw_rate [rad/s],cmd_roll_rate [rad/s],"
         "power [W],energy [J],fault [-]";
}

Telemetry::Telemetry(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "w");
  if (!file_) throw std::runtime_error("telemetry: cannot write " + path + ": " + std::strerror(errno));
  note(std::fprintf(file_, "%s\n", header()) < 0);
}

Telemetry::~Telemetry() {
  if (file_) std::fclose(file_);
}

void Telemetry::note(bool failed) {
  if (failed && error_ == 0) error_ = errno != 0 ? errno : EIO;
}

void Telemetry::record(const TelemetryRow& r) {
  static const SensorFrame empty{};
  const SensorFrame& f = r.frame ? *r.frame : empty;
  if (!file_) return;
  const int n = std::fprintf(file_,
               "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
               "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d\n",
               r.time, f.position.x(), f.position.y(), f.position.z(), f.roll, f.pitch, f.yaw,
               f.gimbal_yaw, f.gimbal_roll, f.wheel_load[0], f.wheel_load[1], f.wheel_load[2],
               f.wheel_load[3], r.action[0], r.action[1], r.action[2], r.command[0], r.command[1],
               r.command[2], f.power, f.energy, r.fault);
  note(n < 0);
  ++rows_;
}

void Telemetry::flush() {
  if (file_) note(std::fflush(file_) != 0);
}

void Telemetry::close() {
  if (file_) {
    note(std::fflush(file_) != 0 || std::ferror(file_) != 0);
    note(std::fclose(file_) != 0);
    file_ = nullptr;
  }
  if (error_ != 0)
    throw std::runtime_error("telemetry: cannot write " + path_ + ": " + std::strerror(error_));
}

}  // namespace ernest::runtime
