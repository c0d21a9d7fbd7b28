// A small persistent thread pool: parallel_for over indices, blocking until all are done.
// Exceptions thrown by the task are captured and the first is rethrown in the caller.
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace ernest {

class InterruptScope;

class ThreadPool {
 public:
  /// threads <= 1 runs everything in the calling thread.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// fn(i) for i in [0, n), spread over the workers (the caller works too).
  void parallel_for(int n, const std::function<void(int)>& fn);
  int threads() const { return static_cast<int>(workers_.size()) + 1; }

 private:
  void work(int worker);
  void run_indices();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_cv_, done_cv_;
  const std::function<void(int)>* task_ = nullptr;
  InterruptScope* scope_ = nullptr;  // the caller's, joined by the workers
  int n_ = 0, next_ = 0, busy_ = 0;
  unsigned generation_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
};

}  // namespace ernest
