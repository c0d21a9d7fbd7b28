// Steps N independent rovers on a pool of threads; commands in and observations out as dense
// row-major arrays, one call per batch step (for the environments and the Python bindings).
#pragma once

#include <atomic>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "ernest/dynamics/rover_sim.hpp"

namespace ernest {
class InterruptScope;
}

namespace ernest::dynamics {

class BatchStepper {
 public:
  /// threads >= 1; rover i always runs on worker i % threads (the calling thread is worker 0),
  /// so results never depend on scheduling: every rover owns its ODE world.
  BatchStepper(std::vector<std::shared_ptr<RoverSim>> sims, int threads);
  ~BatchStepper();
  BatchStepper(const BatchStepper&) = delete;
  BatchStepper& operator=(const BatchStepper&) = delete;

  int size() const { return static_cast<int>(sims_.size()); }
  int threads() const { return threads_; }
  RoverSim& sim(int i);
  std::shared_ptr<RoverSim> sim_ptr(int i) const;

  /// commands: size() x RoverSim::kCommandSize (see RoverSim::set_command_vector), or nullptr to
  /// keep the current commands; n_steps physics steps for every rover; observations (may be
  /// nullptr): size() x RoverSim::kObservationSize. If rovers fail, all the others still step;
  /// then the first failure (by rover index) is rethrown, SimulationDiverged naming the rover.
  /// One thread at a time: a second concurrent call throws ConcurrentUse. Interrupted (Ctrl-C
  /// from Python, common/interrupt.hpp): every rover stops after a whole step, possibly after
  /// different numbers of steps (each RoverSim's time says); all stay usable.
  void step(const double* commands, int n_steps, double* observations);

 private:
  void run_share(int worker);
  void worker_loop(int worker);

  std::vector<std::shared_ptr<RoverSim>> sims_;
  int threads_;
  std::vector<std::thread> pool_;
  std::vector<std::exception_ptr> errors_;
  std::mutex mu_;
  std::condition_variable start_cv_, done_cv_;
  unsigned long generation_ = 0;
  int pending_ = 0;
  bool stop_ = false;
  const double* commands_ = nullptr;
  double* observations_ = nullptr;
  int n_steps_ = 0;
  InterruptScope* scope_ = nullptr;  // the caller's (common/interrupt.hpp), joined by the workers
  std::atomic<bool> in_use_{false};  // step() from one thread at a time (exclusive_use.hpp)
};

}  // namespace ernest::dynamics
