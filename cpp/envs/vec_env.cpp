#include "ernest/envs/vec_env.hpp"

#include <stdexcept>
#include <string>

#include "ernest/common/validation.hpp"

namespace ernest::envs {

VecRoverEnv::VecRoverEnv(const dynamics::RoverParameters& params, const EnvOptions& options,
                         int num_envs, int num_threads)
    : pool_((require_in_range("VecRoverEnv", "num_threads", num_threads, 1, 256), num_threads)) {
  require_in_range("VecRoverEnv", "num_envs", num_envs, 1, 4096);
  envs_.reserve(num_envs);
  for (int i = 0; i < num_envs; ++i) envs_.push_back(std::make_unique<RoverEnv>(params, options));
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
  pool_.parallel_for(size(), [&](int i) { obs.row(i) = envs_[i]->reset(seeds[i]).transpose(); });
  return obs;
}

void VecRoverEnv::step(const Eigen::Ref<const ActionBatch>& actions,
                       Eigen::Ref<ObservationBatch> observations, std::vector<StepResult>& results,
                       std::vector<char>& was_reset) {
  require(actions.rows() == size() && observations.rows() == size(),
          "VecRoverEnv.step: actions and observations need " + std::to_string(size()) + " rows");
  require(actions.allFinite(), "VecRoverEnv.step: actions must be finite");
  results.assign(size(), StepResult{});
  was_reset.assign(size(), 0);
  pool_.parallel_for(size(), [&](int i) {
    RoverEnv& e = *envs_[i];
    if (e.done()) {
      results[i].observation = e.reset_next();
      was_reset[i] = 1;
    } else {
      results[i] = e.step(actions.row(i).transpose());
    }
    observations.row(i) = results[i].observation.transpose();
  });
}

}  // namespace ernest::envs
