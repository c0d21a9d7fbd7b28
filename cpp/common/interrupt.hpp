// Cooperative interruption of long calls (without it Ctrl-C would wait for the whole call, e.g.
// RoverSim.step_n(3e6)). Long loops call poll_interrupt() between units of work that leave their
// object consistent (a physics step, an objective evaluation, an image row). Outside an
// InterruptScope it does nothing but read one thread_local pointer. Inside one, the thread that
// opened the scope asks the scope's check function (the Python bindings: PyErr_CheckSignals under
// the GIL, bindings/interrupt.hpp) at most once per interval; once it answers "stop", every thread
// working for the scope (ThreadPool and BatchStepper workers join it) throws Interrupted at its
// next poll. C++-only users (the onboard runtime) never open a scope.
#pragma once

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

namespace ernest {

/// Thrown by poll_interrupt() once the current scope's check asked to stop. The Python bindings
/// turn it into the exception the signal handler raised (KeyboardInterrupt for Ctrl-C).
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class InterruptScope {
 public:
  /// true = stop. Called only on the thread that opened the scope, never concurrently.
  using Check = bool (*)();
  /// Opens a scope on this thread (nested scopes restore the outer one when closed).
  explicit InterruptScope(Check check,
                          std::chrono::nanoseconds interval = std::chrono::milliseconds(50));
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

  /// The scope this thread works for, or nullptr.
  static InterruptScope* current();
  bool stopped() const { return stopped_.load(std::memory_order_relaxed); }

  /// A worker thread works for `scope` (may be nullptr) until the Join is destroyed.
  class Join {
   public:
    explicit Join(InterruptScope* scope);
    ~Join();
    Join(const Join&) = delete;
    Join& operator=(const Join&) = delete;

   private:
    InterruptScope* previous_;
  };

 private:
  friend void poll_interrupt();
  void poll();

  Check check_;
  std::chrono::nanoseconds interval_;
  std::chrono::steady_clock::time_point next_;
  std::thread::id owner_;
  std::atomic<bool> stopped_{false};
  InterruptScope* previous_;
};

/// Throws Interrupted if the current scope was asked to stop (see above); else returns.
inline void poll_interrupt() {
  if (InterruptScope* s = InterruptScope::current()) s->poll();
}

}  // namespace ernest
