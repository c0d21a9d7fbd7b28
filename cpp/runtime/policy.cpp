#include "ernest/runtime/policy.hpp"

#include <ATen/Parallel.h>
#include <openssl/evp.h>
#include <torch/script.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "ernest/common/validation.hpp"
#include "sha256_hex.hpp"

namespace ernest::runtime {

const char* to_string(PolicyError::Kind kind) {
  switch (kind) {
    case PolicyError::Kind::MissingFile: return "missing file";
    case PolicyError::Kind::CorruptFile: return "corrupt file";
    case PolicyError::Kind::MissingMetadata: return "missing metadata";
    case PolicyError::Kind::LayoutMismatch: return "layout mismatch";
    case PolicyError::Kind::InputSize: return "input size";
    case PolicyError::Kind::OutputSize: return "output size";
    case PolicyError::Kind::Inference: return "inference";
    case PolicyError::Kind::ChecksumMismatch: return "checksum mismatch";
  }
  return "?";
}

void PolicyExpectations::validate() const {
  scales.validate();
  limits.validate();
  require_positive("PolicyExpectations", "policy_rate_hz", policy_rate_hz);
  require_in_range("PolicyExpectations", "rel_tol", rel_tol, 0.0, 0.1);
}

void PolicyOptions::validate() const {
  require_in_range("PolicyOptions", "warmup_calls", warmup_calls, 0, 1e6);
  require_in_range("PolicyOptions", "intra_op_threads", intra_op_threads, 1, 256);
  require_in_range("PolicyOptions", "latency_window", latency_window, 16, 1e7);
}

namespace {

// One informative line of a (often very long) libtorch error message: the last "XxxError: ..."
// line of a TorchScript traceback, else the first line.
std::string first_line(const std::string& s) {
  std::string first, last_error;
  size_t pos = 0;
  while (pos <= s.size()) {
    size_t end = s.find('\n', pos);
    if (end == std::string::npos) end = s.size();
    std::string line = s.substr(pos, end - pos);
    const size_t b = line.find_first_not_of(" \t");
    line = b == std::string::npos ? std::string() : line.substr(b);
    if (!line.empty()) {
      if (first.empty()) first = line;
      const size_t colon = line.find(": ");
      const std::string head = colon == std::string::npos ? std::string() : line.substr(0, colon);
      auto ends = [&](const std::string& t) {
        return head.size() >= t.size() && head.compare(head.size() - t.size(), t.size(), t) == 0;
      };
      if (!head.empty() && head.find(' ') == std::string::npos && (ends("Error") || ends("Exception")))
        last_error = line;
    }
    pos = end + 1;
  }
  return last_error.empty() ? first : last_error;
}

[[noreturn]] void mismatch(const std::string& path, const std::string& what) {
  throw PolicyError(PolicyError::Kind::LayoutMismatch,
                    path + ": policy metadata does not match the runtime's observation layout: " + what);
}

bool close(double a, double b, double rel) {
  return std::abs(a - b) <= rel * std::max({1.0, std::abs(a), std::abs(b)});
}

std::vector<double> number_array(const nlohmann::json& root, const char* key, const std::string& path) {
  const auto it = root.find(key);
  if (it == root.end() || !it->is_array()) mismatch(path, std::string("field '") + key + "' is missing or not an array");
  std::vector<double> out;
  for (const auto& e : *it) {
    if (!e.is_number()) mismatch(path, std::string("field '") + key + "' has a non-number entry");
    out.push_back(e.get<double>());
  }
  return out;
}

// RFC 8259 via nlohmann::json (strict: no NaN/inf/hex, checked surrogates, locale-independent),
// plus a rule RFC 8259 leaves open: a member name repeated in one object is an error, not "the
// last one wins" (two different obs_scale tables in one file must not pass silently).
nlohmann::json parse_strict(const std::string& text) {
  std::vector<std::set<std::string>> keys;  // member names of each open object
  auto cb = [&](int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (event == E::object_start) keys.emplace_back();
    else if (event == E::object_end && !keys.empty()) keys.pop_back();
    else if (event == E::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second)
      throw std::invalid_argument("duplicate member name \"" + parsed.get<std::string>() + "\"");
    return true;
  };
  return nlohmann::json::parse(text, cb);
}

void compare_vector(const std::string& path, const char* key, const std::vector<double>& got,
                    const Eigen::VectorXd& want, double rel) {
  if (got.size() != static_cast<size_t>(want.size()))
    mismatch(path, std::string(key) + " has " + std::to_string(got.size()) + " values, expected " +
                       std::to_string(want.size()));
  for (size_t i = 0; i < got.size(); ++i)
    if (!close(got[i], want[static_cast<Eigen::Index>(i)], rel)) {
      std::ostringstream os;
      os << key << "[" << i << "] = " << got[i] << ", expected " << want[static_cast<Eigen::Index>(i)];
      if (std::string(key) == "obs_scale")
        os << " (" << sensing::observation_names()[i]
           << "): the policy was trained with another observation scale table than "
              "sensing::ObservationScales";
      mismatch(path, os.str());
    }
}

}  // namespace

std::string weights_sha256(const torch::jit::Module& module) {
  static_assert(std::endian::native == std::endian::little, "the digest hashes little-endian float32");
  std::map<std::string, at::Tensor> tensors;  // name order, like sorted() in Python
  for (const auto& p : module.named_parameters(/*recurse=*/true)) tensors[p.name] = p.value;
  for (const auto& b : module.named_buffers(/*recurse=*/true)) tensors[b.name] = b.value;
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), &EVP_MD_CTX_free);
  if (!ctx || EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("weights_sha256: OpenSSL SHA-256 unavailable");
  for (const auto& [name, value] : tensors) {
    const at::Tensor t = value.detach().to(torch::kCPU, torch::kFloat32).contiguous();
    std::string head = name + "\n";
    for (int64_t d = 0; d < t.dim(); ++d) head += (d ? "," : "") + std::to_string(t.size(d));
    head += "\n";
    EVP_DigestUpdate(ctx.get(), head.data(), head.size());
    EVP_DigestUpdate(ctx.get(), t.data_ptr<float>(), static_cast<size_t>(t.numel()) * sizeof(float));
  }
  return finish_hex(ctx.get());
}

PolicyMetadata check_metadata(const std::string& text, const PolicyExpectations& expect,
                              const std::string& path) {
  expect.validate();
  nlohmann::json root;
  try {
    root = parse_strict(text);
  } catch (const std::exception& e) {  // nlohmann::json::parse_error or a duplicate member
    throw PolicyError(PolicyError::Kind::MissingMetadata,
                      path + ": " + Policy::kMetadataFile + " is not valid JSON (" + e.what() + ")");
  }
  if (!root.is_object())
    throw PolicyError(PolicyError::Kind::MissingMetadata,
                      path + ": " + Policy::kMetadataFile + " is not a JSON object");
  PolicyMetadata m;
  m.json = text;
  auto str = [&](const char* key) {
    const auto v = root.find(key);
    if (v == root.end() || !v->is_string()) mismatch(path, std::string("field '") + key + "' is missing or not a string");
    return v->get<std::string>();
  };
  auto num = [&](const char* key) {
    const auto v = root.find(key);
    if (v == root.end() || !v->is_number()) mismatch(path, std::string("field '") + key + "' is missing or not a number");
    return v->get<double>();
  };
  // sizes are whole numbers: 45.5 must not read as 45
  auto integer = [&](const char* key) {
    const auto v = root.find(key);
    if (v == root.end() || !v->is_number_integer())
      mismatch(path, std::string("field '") + key + "' is missing or not an integer");
    return v->get<std::int64_t>();
  };
  auto hex64 = [&](const char* key) {
    const auto h = root.find(key);
    if (h == root.end()) return std::string();
    if (!h->is_string() || h->get_ref<const std::string&>().size() != 64 ||
        h->get_ref<const std::string&>().find_first_not_of("0123456789abcdef") != std::string::npos)
      mismatch(path, std::string("field '") + key + "' is not a 64-digit lower-case hex string");
    return h->get<std::string>();
  };
  m.format = str("format");
  if (m.format != "ernest-policy-v1") mismatch(path, "format '" + m.format + "', expected 'ernest-policy-v1'");
  m.layout_version = str("layout_version");
  const auto& legacy = expect.legacy_layout_versions;
  if (m.layout_version != expect.layout_version &&
      std::find(legacy.begin(), legacy.end(), m.layout_version) == legacy.end())
    mismatch(path, "layout_version '" + m.layout_version + "', the runtime builds '" +
                       expect.layout_version + "'");
  const std::int64_t obs_dim = integer("obs_dim"), act_dim = integer("act_dim");
  if (obs_dim != sensing::kObservationSize)
    mismatch(path, "obs_dim " + std::to_string(obs_dim) + ", the runtime builds " +
                       std::to_string(sensing::kObservationSize) + " values");
  if (act_dim != sensing::kActionSize)
    mismatch(path, "act_dim " + std::to_string(act_dim) + ", the runtime expects " +
                       std::to_string(sensing::kActionSize) + " commands");
  m.obs_dim = static_cast<int>(obs_dim);
  m.act_dim = static_cast<int>(act_dim);
  m.policy_rate_hz = num("policy_rate_hz");
  if (!close(m.policy_rate_hz, expect.policy_rate_hz, expect.rel_tol)) {
    std::ostringstream os;
    os << "policy_rate_hz " << m.policy_rate_hz << ", the runtime runs the policy at "
       << expect.policy_rate_hz << " Hz";
    mismatch(path, os.str());
  }
  m.obs_offset = number_array(root, "obs_offset", path);
  m.obs_scale = number_array(root, "obs_scale", path);
  m.action_low = number_array(root, "action_low", path);
  m.action_high = number_array(root, "action_high", path);
  compare_vector(path, "obs_offset", m.obs_offset, Eigen::VectorXd::Zero(sensing::kObservationSize),
                 expect.rel_tol);
  compare_vector(path, "obs_scale", m.obs_scale, expect.scales.divisors(), expect.rel_tol);
  const sensing::ActionLimits& l = expect.limits;
  compare_vector(path, "action_low", m.action_low, Eigen::Vector3d(0.0, -l.yaw_rate_max, -l.roll_rate_max),
                 expect.rel_tol);
  compare_vector(path, "action_high", m.action_high,
                 Eigen::Vector3d(l.vx_max, l.yaw_rate_max, l.roll_rate_max), expect.rel_tol);
  m.weights_sha256 = hex64("weights_sha256");
  m.policy_sha256 = hex64("policy_sha256");
  if (const auto names = root.find("observation_names"); names != root.end() && names->is_array())
    for (const auto& n : *names)
      if (n.is_string()) m.observation_names.push_back(n.get<std::string>());
  return m;
}

struct Policy::Impl {
  std::string path;
  PolicyExpectations expect;
  PolicyOptions options;
  PolicyMetadata meta;
  torch::jit::Module module;
  torch::Tensor input;               // [45] float32, reused
  std::vector<torch::jit::IValue> args;
  sensing::ObservationVector divisors;
  std::vector<double> latencies;     // ring buffer [us]
  std::int64_t count = 0;

  Eigen::Vector3d forward(const sensing::ObservationVector& obs, bool timed);
};

Eigen::Vector3d Policy::Impl::forward(const sensing::ObservationVector& obs, bool timed) {
  const auto t0 = std::chrono::steady_clock::now();
  c10::InferenceMode guard;
  float* in = input.data_ptr<float>();
  // Physical observation, rounded like the Gymnasium path: its observation is float32, the
  // Python caller multiplies by the float64 scale table and hands torch float32.
  for (int i = 0; i < sensing::kObservationSize; ++i)
    in[i] = static_cast<float>(static_cast<double>(static_cast<float>(obs[i])) * divisors[i]);
  torch::Tensor out;
  try {
    out = module.forward(args).toTensor();
  } catch (const std::exception& e) {
    throw PolicyError(PolicyError::Kind::Inference, path + ": forward pass failed: " + first_line(e.what()));
  }
  if (out.numel() != sensing::kActionSize)
    throw PolicyError(PolicyError::Kind::OutputSize,
                      path + ": the module returns " + std::to_string(out.numel()) +
                          " values for one observation, expected " +
                          std::to_string(sensing::kActionSize) + " (Vx, yaw rate, roll rate)");
  out = out.to(torch::kDouble).contiguous();
  const double* o = out.data_ptr<double>();
  const Eigen::Vector3d cmd(o[0], o[1], o[2]);
  if (!cmd.allFinite())
    throw PolicyError(PolicyError::Kind::Inference, path + ": the policy returned a non-finite command");
  if (timed) {
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    latencies[static_cast<size_t>(count % static_cast<std::int64_t>(latencies.size()))] = us;
    ++count;
  }
  return cmd;
}

Policy::Policy(const std::string& path, const PolicyExpectations& expect, const PolicyOptions& options)
    : impl_(std::make_unique<Impl>()) {
  expect.validate();
  options.validate();
  Impl& p = *impl_;
  p.path = path;
  p.expect = expect;
  p.options = options;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw PolicyError(PolicyError::Kind::MissingFile, path + ": no such policy file");
  at::set_num_threads(options.intra_op_threads);
  torch::jit::ExtraFilesMap extra{{kMetadataFile, ""}};
  try {
    p.module = torch::jit::load(path, torch::kCPU, extra);
  } catch (const std::exception& e) {
    throw PolicyError(PolicyError::Kind::CorruptFile,
                      path + ": not a loadable TorchScript archive (" + first_line(e.what()) + ")");
  }
  const std::string& text = extra[kMetadataFile];
  if (text.empty())
    throw PolicyError(PolicyError::Kind::MissingMetadata,
                      path + ": the archive has no " + kMetadataFile + " (export it with `ernest export`)");
  p.meta = check_metadata(text, expect, path);
  if (p.meta.weights_sha256.empty()) {
    std::cerr << "warning: " << path << ": no weights_sha256 in its metadata, its weights cannot be "
              << "checked; add it with `ernest stamp-policy " << path << "`\n";
  } else {
    const std::string got = weights_sha256(p.module);
    if (got != p.meta.weights_sha256)
      throw PolicyError(PolicyError::Kind::ChecksumMismatch,
                        path + ": its weights do not match the weights_sha256 in its metadata (file "
                               "altered or corrupt; got " + got.substr(0, 16) + "..., expected " +
                               p.meta.weights_sha256.substr(0, 16) + "...)");
    p.meta.weights_verified = true;
  }
  if (p.meta.policy_sha256.empty()) {
    std::cerr << "warning: " << path << ": no policy_sha256 in its metadata, its code and metadata "
              << "cannot be checked; add it with `ernest stamp-policy " << path << "`\n";
  } else {
    if (policy_sha256(path, p.meta.policy_sha256) != p.meta.policy_sha256)
      throw PolicyError(PolicyError::Kind::ChecksumMismatch,
                        path + ": its archive (code, constants, weights or metadata) does not match "
                               "the policy_sha256 in its metadata (file altered or corrupt)");
    p.meta.policy_verified = true;
  }
  p.module.eval();
  p.divisors = expect.scales.divisors();
  {
    c10::InferenceMode guard;
    p.input = torch::zeros({sensing::kObservationSize}, torch::kFloat32);
  }
  p.args = {p.input};
  p.latencies.assign(static_cast<size_t>(options.latency_window), 0.0);
  // Size check on a real call: a zero observation must give one 3-value command.
  try {
    c10::InferenceMode guard;
    p.module.forward(p.args);
  } catch (const std::exception& e) {
    throw PolicyError(PolicyError::Kind::InputSize,
                      path + ": the module does not accept a " +
                          std::to_string(sensing::kObservationSize) +
                          "-value observation although its metadata says so (" + first_line(e.what()) + ")");
  }
  p.forward(sensing::ObservationVector::Zero(), false);  // output size and finiteness
  for (int i = 0; i < options.warmup_calls; ++i) p.forward(sensing::ObservationVector::Zero(), false);
}

Policy::~Policy() = default;
Policy::Policy(Policy&&) noexcept = default;
Policy& Policy::operator=(Policy&&) noexcept = default;

Eigen::Vector3d Policy::command(const sensing::ObservationVector& observation) {
  return impl_->forward(observation, true);
}

sensing::ActionVector Policy::action(const sensing::ObservationVector& observation) {
  return sensing::command_to_action(command(observation), impl_->expect.limits);
}

const PolicyMetadata& Policy::metadata() const { return impl_->meta; }
const PolicyExpectations& Policy::expectations() const { return impl_->expect; }
const std::string& Policy::path() const { return impl_->path; }

LatencyStats Policy::latency() const {
  LatencyStats s;
  s.count = impl_->count;
  const size_t n = static_cast<size_t>(std::min<std::int64_t>(impl_->count, impl_->latencies.size()));
  if (n == 0) return s;
  std::vector<double> v(impl_->latencies.begin(), impl_->latencies.begin() + static_cast<long>(n));
  std::sort(v.begin(), v.end());
  s.median_us = v[n / 2];
  s.p99_us = v[std::min(n - 1, static_cast<size_t>(std::ceil(0.99 * static_cast<double>(n))) - 1)];
  s.max_us = v.back();
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean_us = sum / static_cast<double>(n);
  return s;
}

void Policy::reset_latency() { impl_->count = 0; }

}  // namespace ernest::runtime
