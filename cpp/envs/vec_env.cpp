#include "ernest/envs/vec_env.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <stdexcept>
#include <string>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::envs {

VecRoverEnv::VecRoverEnv(const dynamics::RoverParameters& params, const EnvOptions& options,
                         int num_envs, int num_threads)
    : pool_((require_in_range("VecRoverEnv", "num_threads", num_threads, 1, 256), num_threads)) {
  require_in_range("VecRoverEnv", "num_envs", num_envs, 1, 4096);
  envs_.reserve(num_envs);
  for (int i = 0; i < num_envs; ++i) envs_.push_back(std::make_unique<RoverEnv>(params, options));
  order_.resize(static_cast<size_t>(num_envs));
  std::iota(order_.begin(), order_.end(), 0);
  cost_ns_.assign(static_cast<size_t>(num_envs), 0);
}

void VecRoverEnv::reorder() {
  const auto key = [&](int i) {
    return std::make_pair(envs_[static_cast<size_t>(i)]->done() ? 1 : 0, cost_ns_[static_cast<size_t>(i)]);
  };
  std::sort(order_.begin(), order_.end(), [&](int a, int b) {
    const auto ka = key(a), kb = key(b);
    return ka != kb ? ka > kb : a < b;
  });
}

RoverEnv& VecRoverEnv::env(int i) {
  require_in_range("VecRoverEnv.env", "i", i, 0, size() - 1);
  return *envs_[i];
}

ObservationBatch VecRoverEnv::reset(const std::vector<std::uint64_t>& seeds) {
  require(static_cast<int>(seeds.size()) == size(),
          "VecRoverEnv.reset: need " + std::to_string(size()) + " seeds, got " +
              std::to_string(seeds.size()));
  ObservationBatch obs(size(), sensing::kObservationSize);
  interrupted_ = true;  // until every environment is reset
  pool_.parallel_for(size(), [&](int i) {
    poll_interrupt();  // Ctrl-C between whole environment resets
    obs.row(i) = envs_[i]->reset(seeds[i]).transpose();
  });
  interrupted_ = false;
  return obs;
}

void VecRoverEnv::step(const Eigen::Ref<const ActionBatch>& actions,
                       Eigen::Ref<ObservationBatch> observations, std::vector<StepResult>& results,
                       std::vector<char>& was_reset) {
  if (actions.rows() != size() || observations.rows() != size())
    throw std::invalid_argument("VecRoverEnv.step: actions and observations need " +
                                std::to_string(size()) + " rows");
  require(actions.allFinite(), "VecRoverEnv.step: actions must be finite");
  if (interrupted_)
    throw std::logic_error("VecRoverEnv.step: an earlier step or reset was interrupted part way (some "
                           "environments stepped, others not); call reset() first");
  results.assign(size(), StepResult{});
  was_reset.assign(size(), 0);
  try {
    pool_.parallel_for(size(), [&](int k) {
      const int i = order_[static_cast<size_t>(k)];
      const auto t0 = std::chrono::steady_clock::now();
      step_one(i, actions, observations, results, was_reset);
      cost_ns_[static_cast<size_t>(i)] =
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0)
              .count();
    });
  } catch (const Interrupted&) {
    interrupted_ = true;
    throw;
  }
  reorder();
}

void VecRoverEnv::step_one(int i, const Eigen::Ref<const ActionBatch>& actions,
                           Eigen::Ref<ObservationBatch> observations, std::vector<StepResult>& results,
                           std::vector<char>& was_reset) {
  poll_interrupt();  // Ctrl-C (common/interrupt.hpp): between whole environment steps
  RoverEnv& e = *envs_[i];
  if (e.done()) {
    results[i].observation = e.reset_next();
    was_reset[i] = 1;
  } else {
    results[i] = e.step(actions.row(i).transpose());
  }
  observations.row(i) = results[i].observation.transpose();
}

}  // namespace ernest::envs
