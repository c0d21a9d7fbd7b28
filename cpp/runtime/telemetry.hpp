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
  /// Closes the file; a write failure not reported by close() goes unreported.
  ~Telemetry();
  Telemetry(const Telemetry&) = delete;
  Telemetry& operator=(const Telemetry&) = delete;
  /// One row; values are written with 17 significant digits (exact round trip). Never throws (it
  /// runs inside the control loop): a failed write is kept and reported by close().
  void record(const TelemetryRow& row);
  void flush();
  /// Flushes and closes the file; throws std::runtime_error naming the path if any write since
  /// the header failed (a full disk, /dev/full, a file that refuses writes). Idempotent.
  void close();
  /// errno of the first failed write, 0 if none so far (buffered writes fail at flush or close).
  int write_error() const { return error_; }
  long rows() const { return rows_; }
  const std::string& path() const { return path_; }
  static const char* header();

 private:
  void note(bool failed);
  std::string path_;
  std::FILE* file_ = nullptr;
  long rows_ = 0;
  int error_ = 0;
};

}  // namespace ernest::runtime
