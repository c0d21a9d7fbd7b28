// BatchStepper (batch_stepper.hpp): N rovers stepped on the thread pool, one try-lock per call,
// commands in and state vectors out as dense row-major arrays.
#include "ernest/dynamics/batch_stepper.hpp"

#include <algorithm>
#include <string>

#include "ernest/common/exclusive_use.hpp"
#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::dynamics {

namespace {
std::vector<std::shared_ptr<RoverSim>> checked(std::vector<std::shared_ptr<RoverSim>> sims,
                                               int threads) {
  require_in_range("BatchStepper", "threads", threads, 1, 256);
  require(!sims.empty(), "BatchStepper: needs at least one RoverSim");
  for (const auto& s : sims) require(s != nullptr, "BatchStepper: a RoverSim is null");
  for (size_t i = 0; i < sims.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      require(sims[i] != sims[j], "BatchStepper: the same RoverSim appears twice");
  return sims;
}
}  // namespace

BatchStepper::BatchStepper(std::vector<std::shared_ptr<RoverSim>> sims, int threads)
    : sims_(checked(std::move(sims), threads)), pool_(threads), errors_(sims_.size()),
      order_(sims_.size()), cost_(sims_.size(), 0) {
  for (int i = 0; i < size(); ++i) order_[static_cast<size_t>(i)] = i;
}

RoverSim& BatchStepper::sim(int i) {
  require(i >= 0 && i < size(), "BatchStepper.sim: index out of range");
  return *sims_[static_cast<size_t>(i)];
}

std::shared_ptr<RoverSim> BatchStepper::sim_ptr(int i) const {
  require(i >= 0 && i < size(), "BatchStepper.sim: index out of range");
  return sims_[static_cast<size_t>(i)];
}

void BatchStepper::step(const double* commands, int n_steps, double* states) {
  const ExclusiveUse busy(in_use_, "BatchStepper.step");
  require(n_steps >= 0, "BatchStepper.step: n_steps must be >= 0");
  for (auto& e : errors_) e = nullptr;
  // Each rover's failure is kept (never thrown into the pool, which would stop handing out the
  // other rovers): every rover steps, then the first failure by index is rethrown.
  pool_.parallel_for(size(), [&](int k) {
    const int i = order_[static_cast<size_t>(k)];
    try {
      RoverSim& s = *sims_[static_cast<size_t>(i)];
      const auto solves = [&s] {
        return s.solver_stats().sparse_solves + s.solver_stats().dense_solves;
      };
      const std::uint64_t before = solves();
      if (commands) s.set_command_vector(commands + i * RoverSim::kCommandSize);
      s.step_n(n_steps);
      cost_[static_cast<size_t>(i)] = solves() - before;
      if (states) s.state_vector(states + i * RoverSim::kStateVectorSize);
    } catch (...) {
      errors_[static_cast<size_t>(i)] = std::current_exception();
    }
  });
  // Longest first next time (ties by index: the order, not the results, depends on the costs).
  std::sort(order_.begin(), order_.end(), [&](int a, int b) {
    const std::uint64_t ca = cost_[static_cast<size_t>(a)], cb = cost_[static_cast<size_t>(b)];
    return ca != cb ? ca > cb : a < b;
  });
  for (size_t i = 0; i < errors_.size(); ++i) {
    if (!errors_[i]) continue;
    try {
      std::rethrow_exception(errors_[i]);
    } catch (const SimulationDiverged& e) {
      throw SimulationDiverged("rover " + std::to_string(i) + ": " + e.what());
    }
  }
}

}  // namespace ernest::dynamics
