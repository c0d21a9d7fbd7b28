// Steps N independent rovers on a pool of threads; commands in and state vectors out as dense
// row-major arrays, one call per batch step (for the environments and the Python bindings).
#pragma once

#include <atomic>
#include <cstdint>
#include <exception>
#include <memory>
#include <vector>

#include "ernest/common/thread_pool.hpp"
#include "ernest/dynamics/rover_sim.hpp"

namespace ernest::dynamics {

class BatchStepper {
 public:
  /// threads >= 1 (the calling thread is one of them). Rovers are handed out one at a time to
  /// whichever thread is free (ThreadPool's dynamic scheduling: a rover touching rocks takes up
  /// to SimOptions::obstacle_substeps times longer per step than one on open ground, so a fixed
  /// share per thread left one thread waiting for the other). Results never depend on which
  /// thread steps a rover: every rover owns its ODE world and solver data. The costliest rovers
  /// of the last call (its constraint solves: a rover stalled on a rock stays costly) are handed
  /// out first, so that a long rover does not start last while the other thread idles (longest
  /// first: benchmarks/RESULTS.md, "One rover, and the batched stepper").
  BatchStepper(std::vector<std::shared_ptr<RoverSim>> sims, int threads);
  BatchStepper(const BatchStepper&) = delete;
  BatchStepper& operator=(const BatchStepper&) = delete;

  int size() const { return static_cast<int>(sims_.size()); }
  int threads() const { return pool_.threads(); }
  RoverSim& sim(int i);
  std::shared_ptr<RoverSim> sim_ptr(int i) const;

  /// commands: size() x RoverSim::kCommandSize (see RoverSim::set_command_vector), or nullptr to
  /// keep the current commands; n_steps physics steps for every rover; states (may be nullptr):
  /// size() x RoverSim::kStateVectorSize (RoverSim::state_vector()). If rovers fail, all the
  /// others still step;
  /// then the first failure (by rover index) is rethrown, SimulationDiverged naming the rover.
  /// One thread at a time: a second concurrent call throws ConcurrentUse. Interrupted (Ctrl-C
  /// from Python, common/interrupt.hpp): every rover stops after a whole step, possibly after
  /// different numbers of steps (each RoverSim's time says); all stay usable.
  void step(const double* commands, int n_steps, double* states);

 private:
  std::vector<std::shared_ptr<RoverSim>> sims_;
  ThreadPool pool_;
  std::vector<std::exception_ptr> errors_;
  std::vector<int> order_;                // rovers in the order they are handed out
  std::vector<std::uint64_t> cost_;       // constraint solves of each rover in the last call
  std::atomic<bool> in_use_{false};  // step() from one thread at a time (exclusive_use.hpp)
};

}  // namespace ernest::dynamics
