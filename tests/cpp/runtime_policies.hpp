// TorchScript test policies with the metadata rl/export.py writes, built with libtorch's
// compiler (no Python needed); shared by test_runtime and test_runtime_alloc.
#pragma once

#include <torch/script.h>
#include <unistd.h>

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>

#include "ernest/sensing/observation.hpp"

namespace ernest::testing_policies {

namespace fs = std::filesystem;

inline fs::path tmpdir() {
  static const fs::path d = [] {
    fs::path p = fs::temp_directory_path() / ("ernest_test_runtime_" + std::to_string(::getpid()));
    fs::create_directories(p);
    return p;
  }();
  return d;
}

inline std::string vec_json(const Eigen::VectorXd& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) os << (i ? ", " : "") << v[i];
  os << "]";
  return os.str();
}

// Metadata as python/ernest_cpp/rl/export.py writes it, for the runtime's layout; `edit` may
// replace one field's JSON text.
inline std::string metadata_json(const std::string& field = "", const std::string& value = "") {
  const sensing::ObservationScales sc;
  const sensing::ActionLimits l;
  std::map<std::string, std::string> f = {
      {"format", "\"ernest-policy-v1\""},
      {"layout_version", "\"ernest-obs-v" + std::to_string(sensing::kObservationLayoutVersion) + "\""},
      {"obs_dim", "45"},
      {"act_dim", "3"},
      {"policy_rate_hz", "2.0"},
      {"obs_offset", vec_json(Eigen::VectorXd::Zero(45))},
      {"obs_scale", vec_json(sc.divisors())},
      {"action_low", vec_json(Eigen::Vector3d(0.0, -l.yaw_rate_max, -l.roll_rate_max))},
      {"action_high", vec_json(Eigen::Vector3d(l.vx_max, l.yaw_rate_max, l.roll_rate_max))},
      {"observation_names", "[\"heading_deviation\"]"}};
  if (!field.empty()) f[field] = value;
  std::string s = "{";
  bool first = true;
  for (const auto& [k, v] : f) {
    if (v.empty()) continue;  // empty value = drop the field
    s += (first ? "\"" : ", \"") + k + "\": " + v;
    first = false;
  }
  return s + "}";
}

// Save a TorchScript module with the given forward body (and buffers) and metadata.
inline std::string save_module(const std::string& name, const std::string& src,
                        const std::map<std::string, torch::Tensor>& buffers,
                        const std::string* meta = nullptr) {
  torch::jit::Module m("__torch__.TestPolicy_" + name);
  for (const auto& [k, t] : buffers) m.register_buffer(k, t);
  m.define(src);
  const std::string path = (tmpdir() / (name + ".pt")).string();
  const std::string md = metadata_json();
  torch::jit::ExtraFilesMap extra;
  if (!meta) extra["ernest_metadata.json"] = md;
  else if (!meta->empty()) extra["ernest_metadata.json"] = *meta;
  m.save(path, extra);
  return path;
}

// Returns the first three PHYSICAL observation entries as the command.
inline std::string identity_policy(const std::string& name = "identity", const std::string* meta = nullptr) {
  return save_module(name, "def forward(self, x):\n  return x[0:3] * 1.0\n", {}, meta);
}

// Constant command c (Vx, yaw rate, roll rate), whatever the input.
inline std::string constant_policy(const std::string& name, const Eigen::Vector3d& c) {
  return save_module(name, "def forward(self, x):\n  return self.c + 0.0 * x[0:3]\n",
                     {{"c", torch::tensor({float(c[0]), float(c[1]), float(c[2])})}});
}

}  // namespace ernest::testing_policies
