// One object, one thread at a time: a guard that refuses (instead of waiting) when another thread
// is inside a method of the same object. The Python bindings release the GIL in long calls, so
// two Python threads could otherwise step one simulator at once and crash the process.
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>

namespace ernest {

/// Raised when an object is used from a second thread while a first one is still inside it.
class ConcurrentUse : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The error every one-thread-at-a-time guard raises (here and bindings/exclusive.hpp).
inline ConcurrentUse concurrent_use(const char* what) {
  return ConcurrentUse(std::string(what) +
                       ": the object is in use by another thread; use one object per thread "
                       "or serialise the calls with a lock");
}

/// RAII try-lock on an atomic flag: throws ConcurrentUse naming `what` if the flag is already
/// held. Not re-entrant (a method holding it must not call another guarded method).
class ExclusiveUse {
 public:
  ExclusiveUse(std::atomic<bool>& flag, const char* what) : flag_(flag) {
    if (flag_.exchange(true, std::memory_order_acquire)) throw concurrent_use(what);
  }
  ~ExclusiveUse() { flag_.store(false, std::memory_order_release); }
  ExclusiveUse(const ExclusiveUse&) = delete;
  ExclusiveUse& operator=(const ExclusiveUse&) = delete;

 private:
  std::atomic<bool>& flag_;
};

}  // namespace ernest
