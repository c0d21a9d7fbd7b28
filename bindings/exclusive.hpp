// One thread at a time for bound objects whose C++ class has no guard of its own
// (cpp/common/exclusive_use.hpp has the same rule and message for RoverSim and BatchStepper).
// A binding that releases the GIL lets a second Python thread enter the same object, and the
// C++ workspaces (IK, ODE worlds, OpenCV matchers, map buffers) would then be corrupted. Each
// guarded method marks the object's address busy for the length of the call; a second thread
// gets ConcurrentUse (RuntimeError) instead of waiting, like RoverSim. A call may mark several
// addresses (an owner and the objects it hands out by reference, e.g. StereoMapper and its map).
#pragma once

#include <initializer_list>
#include <mutex>
#include <unordered_set>
#include <utility>
#include <vector>

#include "ernest/common/exclusive_use.hpp"

namespace ernest::bindings {

class Busy {
 public:
  Busy(const char* what, std::initializer_list<const void*> objects)
      : Busy(what, std::vector<const void*>(objects)) {}
  Busy(const char* what, std::vector<const void*> objects) {
    std::lock_guard<std::mutex> lock(mutex());
    for (const void* o : objects)
      if (o != nullptr && set().count(o) != 0) throw concurrent_use(what);
    for (const void* o : objects)
      if (o != nullptr && set().insert(o).second) held_.push_back(o);
  }
  ~Busy() {
    std::lock_guard<std::mutex> lock(mutex());
    for (const void* o : held_) set().erase(o);
  }
  Busy(const Busy&) = delete;
  Busy& operator=(const Busy&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::unordered_set<const void*>& set() {
    static std::unordered_set<const void*> s;
    return s;
  }
  std::vector<const void*> held_;
};

/// A member function as a binding that holds Busy on its object for the call.
template <class C, class R, class... A>
auto guarded(const char* what, R (C::*f)(A...)) {
  return [what, f](C& self, A... a) -> R {
    const Busy busy(what, {&self});
    return (self.*f)(std::forward<A>(a)...);
  };
}
template <class C, class R, class... A>
auto guarded(const char* what, R (C::*f)(A...) const) {
  return [what, f](const C& self, A... a) -> R {
    const Busy busy(what, {&self});
    return (self.*f)(std::forward<A>(a)...);
  };
}

/// A free function whose first argument is the object it works on (e.g. execute_joint_path(sim,
/// ...)), as a binding that holds Busy on that object.
template <class C, class R, class... A>
auto guarded(const char* what, R (*f)(C&, A...)) {
  return [what, f](C& object, A... a) -> R {
    const Busy busy(what, {&object});
    return f(object, std::forward<A>(a)...);
  };
}

}  // namespace ernest::bindings
