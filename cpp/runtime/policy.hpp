// TorchScript policy for the onboard loop (seed 004 §4.1–4.2, §5: the trained actor runs on the
// rover's computer). Loads an archive written by `ernest export` (python/ernest_cpp/rl/export.py):
// a module mapping a PHYSICAL observation (the 45 values of §4.2 in SI units, i.e. the normalised
// observation times ObservationScales::divisors()) to a PHYSICAL command (Vx [m/s], yaw rate,
// roll rate [rad/s]), plus the metadata file `ernest_metadata.json`. Every way of being the wrong
// file is reported by a PolicyError naming what is wrong; inference never allocates Eigen memory
// and runs on one intra-op thread in inference mode. Integrity: the metadata's `weights_sha256`
// (SHA-256 of every parameter and buffer, the digest of export.py's weights_sha256) and
// `policy_sha256` (SHA-256 of the whole archive: code, constants, weights and metadata;
// policy_digest.cpp) are recomputed on load; a file without one (written before it existed)
// loads with a warning on stderr. python/ernest_cpp/rl/policy_file.py makes the same checks.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ernest/sensing/observation.hpp"

namespace torch::jit {
struct Module;
}

namespace ernest::runtime {

class PolicyError : public std::runtime_error {
 public:
  enum class Kind {
    MissingFile,      ///< no such file (or not a regular file)
    CorruptFile,      ///< not a loadable TorchScript archive
    MissingMetadata,  ///< no (or unparsable) ernest_metadata.json in the archive
    LayoutMismatch,   ///< metadata disagrees with the runtime's observation/action layout
    InputSize,        ///< the module does not accept the observation vector
    OutputSize,       ///< the module does not return one command of the expected size
    Inference,        ///< a forward pass failed or returned non-finite values
    ChecksumMismatch, ///< the weights or the archive differ from the metadata's digests (altered file)
  };
  PolicyError(Kind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

const char* to_string(PolicyError::Kind kind);

/// What the runtime requires of a policy file: the observation layout it builds and the action
/// limits it enforces. Defaults = the layout of cpp/sensing/observation.hpp.
struct PolicyExpectations {
  std::string layout_version = "ernest-obs-v" + std::to_string(sensing::kObservationLayoutVersion);
  /// Older versions with the same order and size, accepted when their obs_scale is `scales`
  /// (version 1 files exist with two different tables under one name).
  std::vector<std::string> legacy_layout_versions = {"ernest-obs-v1"};
  sensing::ObservationScales scales{};
  sensing::ActionLimits limits{};
  double policy_rate_hz = 2.0;  ///< Table 5
  /// Relative tolerance when comparing stored scales/ranges (float32 round trips, degree
  /// conversions) with ours.
  double rel_tol = 1e-6;
  void validate() const;
};

struct PolicyOptions {
  int warmup_calls = 50;        ///< forward passes before the loop (first calls build the plan)
  int intra_op_threads = 1;     ///< torch intra-op threads (process-wide setting)
  int latency_window = 8192;    ///< latency samples kept for the statistics (ring buffer)
  void validate() const;
};

/// Metadata read from the archive.
struct PolicyMetadata {
  std::string format, layout_version;
  int obs_dim = 0, act_dim = 0;
  double policy_rate_hz = 0.0;
  std::vector<double> obs_offset, obs_scale, action_low, action_high;
  std::vector<std::string> observation_names;
  std::string weights_sha256;      ///< hex digest from the metadata; empty if the file has none
  bool weights_verified = false;   ///< the digest was present and matched the loaded weights
  std::string policy_sha256;       ///< digest of the whole archive; empty if the file has none
  bool policy_verified = false;    ///< that digest was present and matched the archive
  std::string json;  ///< the raw file
};

struct LatencyStats {
  std::int64_t count = 0;  ///< calls measured since load (warm-up excluded)
  double median_us = 0.0, p99_us = 0.0, max_us = 0.0, mean_us = 0.0;  ///< over the window
};

/// Parse and check metadata text against the expectations (exposed for tests); throws
/// PolicyError(MissingMetadata) if unparsable, PolicyError(LayoutMismatch) if it disagrees.
PolicyMetadata check_metadata(const std::string& json_text, const PolicyExpectations& expect,
                              const std::string& path = "<metadata>");

/// SHA-256 (lower-case hex) of a module's parameters and buffers, in name order; per tensor the
/// dotted name, '\n', the shape as comma-separated integers, '\n', the values as little-endian
/// float32. The same bytes as python/ernest_cpp/rl/export.py weights_sha256.
std::string weights_sha256(const torch::jit::Module& module);

/// SHA-256 (lower-case hex) of the policy archive at `path`: every record but
/// .data/serialization_id (torch derives it at each save), uncompressed, in byte-wise name
/// order, each as its name, '\n', its size in decimal, '\n', its bytes; the metadata record
/// with `digest_in_metadata` (which must occur there exactly once) replaced by as many '0'. The
/// same bytes as python/ernest_cpp/rl/policy_file.py policy_sha256. Throws PolicyError.
std::string policy_sha256(const std::string& path, const std::string& digest_in_metadata);

class Policy {
 public:
  static constexpr const char* kMetadataFile = "ernest_metadata.json";

  /// Load, check metadata and sizes, switch to eval/inference, warm up. Throws PolicyError.
  explicit Policy(const std::string& path, const PolicyExpectations& expect = {},
                  const PolicyOptions& options = {});
  ~Policy();
  Policy(Policy&&) noexcept;
  Policy& operator=(Policy&&) noexcept;

  /// Physical command (Vx, yaw rate, roll rate) from a NORMALISED observation (what
  /// sensing::build_observation returns): the module gets float32(obs_i * divisor_i).
  /// Throws PolicyError(Inference) if the forward pass fails or the result is not finite.
  Eigen::Vector3d command(const sensing::ObservationVector& observation);
  /// The same as a normalised action in [-1, 1]^3 (sensing::command_to_action).
  sensing::ActionVector action(const sensing::ObservationVector& observation);

  const PolicyMetadata& metadata() const;
  const PolicyExpectations& expectations() const;
  const std::string& path() const;
  /// Inference latency (the forward pass and the copies in and out) since load.
  LatencyStats latency() const;
  void reset_latency();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ernest::runtime
