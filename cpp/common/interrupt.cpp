#include "ernest/common/interrupt.hpp"

namespace ernest {

namespace {
thread_local InterruptScope* tl_scope = nullptr;
}

InterruptScope::InterruptScope(Check check, std::chrono::nanoseconds interval)
    : check_(check),
      interval_(interval),
      next_(std::chrono::steady_clock::now() + interval),
      owner_(std::this_thread::get_id()),
      previous_(tl_scope) {
  tl_scope = this;
}

InterruptScope::~InterruptScope() { tl_scope = previous_; }

InterruptScope* InterruptScope::current() { return tl_scope; }

InterruptScope::Join::Join(InterruptScope* scope) : previous_(tl_scope) { tl_scope = scope; }

InterruptScope::Join::~Join() { tl_scope = previous_; }

void InterruptScope::poll() {
  if (stopped()) throw Interrupted("interrupted");
  if (std::this_thread::get_id() != owner_ || check_ == nullptr) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_) return;
  next_ = now + interval_;
  if (check_()) {
    stopped_.store(true, std::memory_order_relaxed);
    throw Interrupted("interrupted");
  }
}

}  // namespace ernest
