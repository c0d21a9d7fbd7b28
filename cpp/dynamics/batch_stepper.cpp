#include "ernest/dynamics/batch_stepper.hpp"

#include <string>

#include "ernest/common/exclusive_use.hpp"
#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::dynamics {

BatchStepper::BatchStepper(std::vector<std::shared_ptr<RoverSim>> sims, int threads)
    : sims_(std::move(sims)), threads_(threads) {
  require_in_range("BatchStepper", "threads", threads, 1, 256);
  require(!sims_.empty(), "BatchStepper: needs at least one RoverSim");
  for (const auto& s : sims_) require(s != nullptr, "BatchStepper: a RoverSim is null");
  for (size_t i = 0; i < sims_.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      require(sims_[i] != sims_[j], "BatchStepper: the same RoverSim appears twice");
  errors_.resize(sims_.size());
  for (int w = 1; w < threads_; ++w) pool_.emplace_back([this, w] { worker_loop(w); });
}

BatchStepper::~BatchStepper() {
  {
    std::lock_guard<std::mutex> lk(mu_);
    stop_ = true;
  }
  start_cv_.notify_all();
  for (auto& t : pool_) t.join();
}

RoverSim& BatchStepper::sim(int i) {
  require(i >= 0 && i < size(), "BatchStepper.sim: index out of range");
  return *sims_[static_cast<size_t>(i)];
}

std::shared_ptr<RoverSim> BatchStepper::sim_ptr(int i) const {
  require(i >= 0 && i < size(), "BatchStepper.sim: index out of range");
  return sims_[static_cast<size_t>(i)];
}

void BatchStepper::run_share(int worker) {
  const InterruptScope::Join join(scope_);  // stop with the caller on Ctrl-C
  for (size_t i = static_cast<size_t>(worker); i < sims_.size(); i += static_cast<size_t>(threads_)) {
    try {
      RoverSim& s = *sims_[i];
      if (commands_) s.set_command_vector(commands_ + i * RoverSim::kCommandSize);
      s.step_n(n_steps_);
      if (observations_) s.observation(observations_ + i * RoverSim::kObservationSize);
    } catch (...) {
      errors_[i] = std::current_exception();
    }
  }
}

void BatchStepper::worker_loop(int worker) {
  unsigned long seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lk(mu_);
      start_cv_.wait(lk, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    run_share(worker);
    {
      std::lock_guard<std::mutex> lk(mu_);
      if (--pending_ == 0) done_cv_.notify_one();
    }
  }
}

void BatchStepper::step(const double* commands, int n_steps, double* observations) {
  const ExclusiveUse busy(in_use_, "BatchStepper.step");
  require(n_steps >= 0, "BatchStepper.step: n_steps must be >= 0");
  for (auto& e : errors_) e = nullptr;
  commands_ = commands;
  observations_ = observations;
  n_steps_ = n_steps;
  scope_ = InterruptScope::current();
  {
    std::lock_guard<std::mutex> lk(mu_);
    pending_ = threads_ - 1;
    ++generation_;
  }
  start_cv_.notify_all();
  run_share(0);
  {
    std::unique_lock<std::mutex> lk(mu_);
    done_cv_.wait(lk, [&] { return pending_ == 0; });
  }
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
