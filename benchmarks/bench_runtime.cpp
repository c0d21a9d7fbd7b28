// Onboard runtime benchmark (target: "policy inference in the C++ runtime <= 50 us").
//   ./run bench runtime            or   bench_runtime [--policy FILE] [--repeats N]
// 1. Inference latency of runtime::Policy::command (the paper-size actor 45-512-512-3 of §4.1
//    wrapped like rl/export.py's ExportedPolicy: normalisation, tanh, action ranges), one thread,
//    inference mode: median and 99th percentile over 20000 calls with varying observations,
//    median over repeats. Reference in the same run: the same network as three dense Eigen
//    matrix-vector products (the arithmetic floor on this core), ratio runtime / reference.
// 2. CPU share of the 400 Hz onboard loop on one core: ControlLoop over the simulator interface on
//    a rock field for 60 s of loop time; the time spent in tick() outside wait_next_tick() (where
//    the simulator steps) divided by the loop time; per-tick median, p99 and max; and the policy's
//    latency inside that loop (one call every 0.5 s with the simulator in between: cold caches).
#include <torch/script.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "ernest/envs/rover_env.hpp"
#include "ernest/runtime/control_loop.hpp"
#include "ernest/runtime/policy.hpp"
#include "ernest/runtime/sim_interface.hpp"

using namespace ernest;
using Clock = std::chrono::steady_clock;

namespace {

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}
double median(std::vector<double> v) { return percentile(std::move(v), 0.5); }

std::string array(const Eigen::VectorXd& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) os << (i ? "," : "") << v[i];
  return os.str() + "]";
}

struct Mlp {
  torch::Tensor w1, b1, w2, b2, w3, b3;
};

// The §4.1 actor (2 x 512 ReLU, 3 tanh) with ExportedPolicy's normalisation and action scaling.
std::string write_paper_actor(const std::string& path, Mlp& net) {
  torch::manual_seed(0);
  const double k1 = 1.0 / std::sqrt(45.0), k2 = 1.0 / std::sqrt(512.0);
  net.w1 = torch::rand({512, 45}) * 2 * k1 - k1;
  net.b1 = torch::rand({512}) * 2 * k1 - k1;
  net.w2 = torch::rand({512, 512}) * 2 * k2 - k2;
  net.b2 = torch::rand({512}) * 2 * k2 - k2;
  net.w3 = torch::rand({3, 512}) * 2 * k2 - k2;
  net.b3 = torch::rand({3}) * 2 * k2 - k2;
  const sensing::ActionLimits l;
  const Eigen::VectorXd d = sensing::ObservationScales{}.divisors();
  torch::Tensor s = torch::empty({45});
  for (int i = 0; i < 45; ++i) s[i] = d[i];
  torch::jit::Module m("__torch__.PaperActor");
  m.register_buffer("w1", net.w1);
  m.register_buffer("b1", net.b1);
  m.register_buffer("w2", net.w2);
  m.register_buffer("b2", net.b2);
  m.register_buffer("w3", net.w3);
  m.register_buffer("b3", net.b3);
  m.register_buffer("obs_offset", torch::zeros({45}));
  m.register_buffer("obs_scale", s);
  m.register_buffer("lo", torch::tensor({0.0f, float(-l.yaw_rate_max), float(-l.roll_rate_max)}));
  m.register_buffer("hi", torch::tensor({float(l.vx_max), float(l.yaw_rate_max), float(l.roll_rate_max)}));
  m.define(
      "def forward(self, obs):\n"
      "  x = (obs - self.obs_offset) / self.obs_scale\n"
      "  h = torch.relu(torch.linear(x, self.w1, self.b1))\n"
      "  h = torch.relu(torch.linear(h, self.w2, self.b2))\n"
      "  u = torch.tanh(torch.linear(h, self.w3, self.b3))\n"
      "  return self.lo + (u + 1.0) * 0.5 * (self.hi - self.lo)\n");
  std::ostringstream meta;
  meta << "{\"format\":\"ernest-policy-v1\",\"layout_version\":\"ernest-obs-v1\",\"obs_dim\":45,"
       << "\"act_dim\":3,\"policy_rate_hz\":2.0,\"obs_offset\":" << array(Eigen::VectorXd::Zero(45))
       << ",\"obs_scale\":" << array(d) << ",\"action_low\":"
       << array(Eigen::Vector3d(0, -l.yaw_rate_max, -l.roll_rate_max)) << ",\"action_high\":"
       << array(Eigen::Vector3d(l.vx_max, l.yaw_rate_max, l.roll_rate_max)) << "}";
  m.save(path, {{"ernest_metadata.json", meta.str()}});
  return path;
}

Eigen::MatrixXf to_eigen(const torch::Tensor& t) {
  const torch::Tensor c = t.contiguous();
  const long r = c.size(0), k = c.dim() > 1 ? c.size(1) : 1;
  Eigen::MatrixXf m(r, k);
  for (long i = 0; i < r; ++i)
    for (long j = 0; j < k; ++j) m(i, j) = c.dim() > 1 ? c[i][j].item<float>() : c[i].item<float>();
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  std::string policy_path;
  int repeats = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--policy" && i + 1 < argc) policy_path = argv[++i];
    else if (a == "--repeats" && i + 1 < argc) repeats = std::stoi(argv[++i]);
  }
  Mlp net;
  const std::string tmp = (std::filesystem::temp_directory_path() / "ernest_bench_actor.pt").string();
  const bool own = policy_path.empty();
  if (own) policy_path = write_paper_actor(tmp, net);

  // ---- 1. inference latency
  runtime::PolicyOptions po;
  po.latency_window = 20000;
  runtime::Policy policy(policy_path, {}, po);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::vector<sensing::ObservationVector> inputs(256);
  for (auto& o : inputs)
    for (int i = 0; i < 45; ++i) o[i] = u(rng);
  std::vector<double> med, p99;
  double sink = 0.0;
  for (int r = 0; r < repeats; ++r) {
    policy.reset_latency();
    for (int k = 0; k < 20000; ++k) sink += policy.command(inputs[k % inputs.size()])[0];
    const runtime::LatencyStats s = policy.latency();
    med.push_back(s.median_us);
    p99.push_back(s.p99_us);
  }
  // Reference: the same arithmetic as dense Eigen float mat-vecs (the floor on this core).
  double ref_us = 0.0;
  if (own) {
    const Eigen::MatrixXf W1 = to_eigen(net.w1), W2 = to_eigen(net.w2), W3 = to_eigen(net.w3);
    const Eigen::VectorXf B1 = to_eigen(net.b1), B2 = to_eigen(net.b2), B3 = to_eigen(net.b3);
    const Eigen::VectorXd d = sensing::ObservationScales{}.divisors();
    Eigen::VectorXf x(45), h1(512), h2(512), y(3);
    std::vector<double> ref;
    for (int r = 0; r < repeats; ++r) {
      std::vector<double> t(20000);
      for (int k = 0; k < 20000; ++k) {
        const auto t0 = Clock::now();
        const auto& o = inputs[k % inputs.size()];
        for (int i = 0; i < 45; ++i) x[i] = static_cast<float>(o[i] * d[i] / d[i]);
        h1.noalias() = W1 * x;
        h1 = (h1 + B1).cwiseMax(0.0f);
        h2.noalias() = W2 * h1;
        h2 = (h2 + B2).cwiseMax(0.0f);
        y.noalias() = W3 * h2;
        y = (y + B3).array().tanh();
        sink += y[0];
        t[k] = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
      }
      ref.push_back(median(t));
    }
    ref_us = median(ref);
  }
  const double m = median(med), q = median(p99);
  std::printf("runtime inference (%s, 1 thread): median %.1f us, p99 %.1f us (median of %d x 20000 calls)\n",
              own ? "paper actor 45-512-512-3" : policy_path.c_str(), m, q, repeats);
  if (own)
    std::printf("reference: same network as Eigen float mat-vecs: median %.1f us; ratio runtime/reference %.2f\n",
                ref_us, m / ref_us);
  std::printf("target median <= 50 us: %s\n", m <= 50.0 ? "met" : "NOT met");

  // ---- 2. CPU share of the 400 Hz loop
  envs::EnvOptions eo;
  eo.scenario.kind = envs::ScenarioKind::RockField;
  eo.episode_duration = 60.0;
  envs::RoverEnv env(dynamics::RoverParameters{}, eo);
  env.reset(5);
  runtime::SimRoverInterface io(env);
  runtime::ControlLoop loop(io, policy, env.parameters(), env.scenario().path,
                            runtime::LoopOptions::from_env(env));
  loop.set_fts_bias(env.fts_bias());
  loop.set_logger([](double, const std::string&) {});
  policy.reset_latency();
  const long ticks = 60 * 400;
  std::vector<double> tick_us(static_cast<size_t>(ticks));
  double prev = 0.0;
  const auto w0 = Clock::now();
  for (long k = 0; k < ticks; ++k) {
    loop.tick();
    tick_us[static_cast<size_t>(k)] = (loop.busy_seconds() - prev) * 1e6;
    prev = loop.busy_seconds();
  }
  const double wall = std::chrono::duration<double>(Clock::now() - w0).count();
  const double loop_time = ticks / 400.0;
  std::printf("400 Hz loop on the simulator interface, rock field, %.0f s of loop time:\n", loop_time);
  std::printf("  tick (loop work, excluding the simulator step): median %.2f us, p99 %.2f us, max %.1f us\n",
              median(tick_us), percentile(tick_us, 0.99), *std::max_element(tick_us.begin(), tick_us.end()));
  std::printf("  CPU share of one core: %.3f %% (%.3f s busy per %.0f s; the 2.5 ms budget per tick)\n",
              100.0 * loop.busy_seconds() / loop_time, loop.busy_seconds(), loop_time);
  std::printf("  with the simulator stepping too: %.1fx real time (wall %.2f s), watchdog trips %d\n",
              loop_time / wall, wall, loop.watchdog().trips());
  const runtime::LatencyStats in_loop = policy.latency();
  std::printf("  inference inside the loop (every 0.5 s, simulator steps in between, caches cold): "
              "median %.1f us, p99 %.1f us over %lld calls\n",
              in_loop.median_us, in_loop.p99_us, static_cast<long long>(in_loop.count));
  if (own) std::filesystem::remove(tmp);
  return sink == 12345.678 ? 1 : 0;
}
