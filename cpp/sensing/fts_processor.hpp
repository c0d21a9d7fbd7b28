// Force–torque processing of seed 004 §4.2: per-axis first-order low-pass at the sensor rate,
// subtraction of calibration biases, subtraction of the four-sensor mean. Shared by the
// environments and the onboard runtime (one implementation).
#pragma once

#include <Eigen/Core>

namespace ernest::sensing {

/// Four six-axis wrenches, one row per sensor (front-left, front-right, rear-left, rear-right),
/// columns (Fx, Fy, Fz, Tx, Ty, Tz) in each sensor's frame [N, N m].
using Wrenches = Eigen::Matrix<double, 4, 6, Eigen::RowMajor>;

struct FtsFilterOptions {
  double sample_rate = 400.0;  ///< [Hz], sensor rate on ERNEST
  double cutoff = 0.5;         ///< [Hz], first-order low-pass cutoff
  void validate() const;
};

/// Stateful filter chain. Not thread-safe (one per rover); update() never allocates.
class FtsProcessor {
 public:
  explicit FtsProcessor(const FtsFilterOptions& options = {});

  /// Start the filter at `initial` (no start-up transient), e.g. the first sample.
  void reset(const Eigen::Ref<const Wrenches>& initial);
  /// One sensor sample: y += alpha (x - y), alpha = 1 - exp(-2 pi f_c / f_s) (exact
  /// discretisation of the RC filter, time constant 1 / (2 pi f_c)). Rejects non-finite input.
  void update(const Eigen::Ref<const Wrenches>& raw);
  /// Calibration biases (filtered readings recorded with the wheels hanging, §4.2).
  void set_bias(const Eigen::Ref<const Wrenches>& bias);

  const Wrenches& filtered() const { return filtered_; }
  const Wrenches& bias() const { return bias_; }
  /// filtered - bias, minus the mean over the four sensors of each axis (what the policy sees).
  Wrenches processed() const;
  double alpha() const { return alpha_; }
  const FtsFilterOptions& options() const { return options_; }
  bool initialised() const { return initialised_; }

 private:
  FtsFilterOptions options_;
  double alpha_;
  Wrenches filtered_ = Wrenches::Zero();
  Wrenches bias_ = Wrenches::Zero();
  bool initialised_ = false;
};

}  // namespace ernest::sensing
