// CSV telemetry of the onboard loop and of sim-in-the-loop runs: time, pose, joints, wheel loads,
// the policy's action, the command sent, power and the watchdog state, one row per record().
#pragma once

#include <Eigen/Core>
#include <cstdio>
#include <string>

#include "ernest/runtime/rover_interface.hpp"
#include "ernest/sensing/observation.hpp"

namespace ernest::runtime {

struct TelemetryRow {
  double time = 0.0;
  const SensorFrame* frame = nullptr;                          ///< pose, joints, loads, power
  sensing::ActionVector action = sensing::ActionVector::Zero();  ///< normalised action in force
  Eigen::Vector3d command = Eigen::Vector3d::Zero();           ///< (Vx, yaw rate, roll rate) sent
  int fault = 0;                                               ///< runtime::Fault code, 0 = none
};

class Telemetry {
 public:
  /// Opens (truncates) `path` and writes the header; throws std::runtime_error if it cannot.
  explicit Telemetry(const std::string& path);
  ~Telemetry();
  Telemetry(const Telemetry&) = delete;
  Telemetry& operator=(const Telemetry&) = delete;
  /// One row; values are written with 17 significant digits (exact round trip).
  void record(const TelemetryRow& row);
  void flush();
  long rows() const { return rows_; }
  static const char* header();

 private:
  std::FILE* file_ = nullptr;
  long rows_ = 0;
};

}  // namespace ernest::runtime
