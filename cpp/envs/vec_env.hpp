// N independent RoverEnv episodes stepped in parallel on a thread pool: one call per batch step
// (the Python vector environment releases the GIL around it).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "ernest/common/thread_pool.hpp"
#include "ernest/envs/rover_env.hpp"

namespace ernest::envs {

using ObservationBatch = Eigen::Matrix<double, Eigen::Dynamic, sensing::kObservationSize, Eigen::RowMajor>;
using ActionBatch = Eigen::Matrix<double, Eigen::Dynamic, sensing::kActionSize, Eigen::RowMajor>;

/// Gymnasium's "next-step" autoreset: the step after an episode ended resets that environment
/// (reset_next()) instead of stepping it, returning its first observation with reward 0 and
/// `reset` set; every other environment steps normally.
class VecRoverEnv {
 public:
  VecRoverEnv(const dynamics::RoverParameters& params, const EnvOptions& options, int num_envs,
              int num_threads);

  /// Reset every environment: env i from seeds[i]. Returns the observations (num_envs x 45).
  ObservationBatch reset(const std::vector<std::uint64_t>& seeds);
  /// One policy step of every environment. actions: num_envs x 3 in [-1, 1].
  /// Interrupted (Ctrl-C from Python, common/interrupt.hpp) between two environments' steps: the
  /// batch is then partly stepped, so step() refuses (std::logic_error) until the next reset().
  void step(const Eigen::Ref<const ActionBatch>& actions, Eigen::Ref<ObservationBatch> observations,
            std::vector<StepResult>& results, std::vector<char>& was_reset);

  int size() const { return static_cast<int>(envs_.size()); }
  RoverEnv& env(int i);
  int threads() const { return pool_.threads(); }

 private:
  std::vector<std::unique_ptr<RoverEnv>> envs_;
  ThreadPool pool_;
  bool interrupted_ = false;  // a step or reset stopped part way: reset() first
  // The order the pool hands environments out in, costliest first (longest-processing-time
  // scheduling: the batch ends when its slowest thread does): environments that reset in the
  // next call first (a reset builds a new world, ~5 policy steps' work), then by the wall time of
  // their last step. Only the schedule depends on it, never a result (each env owns its world).
  std::vector<int> order_;
  std::vector<std::int64_t> cost_ns_;
  void reorder();
  void step_one(int i, const Eigen::Ref<const ActionBatch>& actions,
                Eigen::Ref<ObservationBatch> observations, std::vector<StepResult>& results,
                std::vector<char>& was_reset);
};

}  // namespace ernest::envs
