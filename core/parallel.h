#pragma once
// The one parallel policy: oneTBB hides behind these functions. The caller decides the
// thread count with a ThreadLimit in scope (the CLI's --threads); library code only splits work.
#include <cstddef>
#include <functional>
#include <memory>

namespace voxplan {

// Calls fn(begin, end) on disjoint chunks covering [0, n), chunks of at least `grain` items.
void ParallelFor(size_t n, size_t grain, const std::function<void(size_t, size_t)>& fn);

// Caps worker threads while alive; threads <= 0 means all hardware threads.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

int MaxThreads();  // threads ParallelFor may use now
int HardwareThreads();

}  // namespace voxplan
