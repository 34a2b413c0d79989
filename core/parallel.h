#pragma once
// The one parallel policy: oneTBB hides behind these functions. The caller decides the
// thread count with a ThreadLimit in scope (the CLI's --threads); library code only splits work.
#include <cstddef>
#include <functional>
#include <memory>

namespace voxplan {

// Calls fn(begin, end) on disjoint chunks covering [0, n), chunks of at least `grain` items.
void ParallelFor(size_t n, size_t grain, const std::function<void(size_t, size_t)>& fn);

// Items 0..n-1 made by produce(i) and used by consume(i) in order, on the calling thread, with
// up to `ahead` items made on worker tasks while an earlier one is used (a frame decoded while
// the one before it is integrated). produce may run on any thread, for different items at once;
// consume(i) sees all that produce(i) wrote. When consume returns false, nothing more is
// produced or consumed: the items in progress are finished (their results dropped) before this
// returns. The caller holds the results: at most ahead + 1 items are between produce and the end
// of their consume, so a ring of ahead + 1 slots indexed i % (ahead + 1) suffices. With ahead 0,
// or one thread, produce(i) and consume(i) simply alternate on the calling thread. An exception
// from either is rethrown here once the workers are done.
void ProduceAhead(size_t n, size_t ahead, const std::function<void(size_t i)>& produce,
                  const std::function<bool(size_t i)>& consume);

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
