#include "core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <atomic>
#include <exception>
#include <vector>

namespace voxplan {

void ParallelFor(size_t n, size_t grain, const std::function<void(size_t, size_t)>& fn) {
  if (n == 0) return;
  if (grain == 0) grain = 1;
  if (n <= grain || MaxThreads() == 1) {
    fn(0, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain),
                    [&](const tbb::blocked_range<size_t>& r) { fn(r.begin(), r.end()); });
}

void ProduceAhead(size_t n, size_t ahead, const std::function<void(size_t i)>& produce,
                  const std::function<bool(size_t i)>& consume) {
  if (ahead == 0 || MaxThreads() == 1) {
    for (size_t i = 0; i < n; ++i) {
      produce(i);
      if (!consume(i)) return;
    }
    return;
  }
  // Each item is made once, by whoever claims it first: a worker task, or the calling thread
  // when it needs the item (or has nothing else to do) before a worker got to it.
  enum : uint8_t { kWaiting, kRunning, kDone };
  const size_t slots = ahead + 1;
  std::unique_ptr<std::atomic<uint8_t>[]> state(new std::atomic<uint8_t>[n]);
  for (size_t i = 0; i < n; ++i) state[i].store(kWaiting, std::memory_order_relaxed);
  std::vector<std::exception_ptr> errors(slots);  // item i's in slot i % slots
  std::atomic<bool> stop{false};
  const auto claim = [&](size_t i) {
    uint8_t waiting = kWaiting;
    return state[i].compare_exchange_strong(waiting, kRunning, std::memory_order_acquire);
  };
  const auto make = [&](size_t i) {  // a claimed item
    try {
      produce(i);
    } catch (...) {
      errors[i % slots] = std::current_exception();
    }
    state[i].store(kDone, std::memory_order_release);
    state[i].notify_all();
  };

  tbb::task_group group;
  std::exception_ptr failure;
  size_t scheduled = 0;
  for (size_t k = 0; k < n; ++k) {
    for (; scheduled < n && scheduled <= k + ahead; ++scheduled) {
      const size_t i = scheduled;
      group.run([&, i] {
        if (!stop.load(std::memory_order_relaxed) && claim(i)) make(i);
      });
    }
    if (claim(k)) make(k);
    // While a worker makes item k, make the next waiting one here rather than wait idle.
    for (size_t j = k + 1; j < scheduled && state[k].load(std::memory_order_acquire) != kDone; ++j)
      if (claim(j)) make(j);
    for (uint8_t s; (s = state[k].load(std::memory_order_acquire)) != kDone;)
      state[k].wait(s, std::memory_order_acquire);
    if (errors[k % slots]) {
      failure = errors[k % slots];
      break;
    }
    bool more = false;
    try {
      more = consume(k);
    } catch (...) {
      failure = std::current_exception();
    }
    if (!more) break;
  }
  stop.store(true, std::memory_order_relaxed);
  group.wait();  // the tasks catch everything: nothing is thrown here
  if (failure) std::rethrow_exception(failure);
}

struct ThreadLimit::Impl {
  tbb::global_control control;
};

ThreadLimit::ThreadLimit(int threads)
    : impl_(new Impl{tbb::global_control(tbb::global_control::max_allowed_parallelism,
                                         size_t(threads > 0 ? threads : HardwareThreads()))}) {}
ThreadLimit::~ThreadLimit() = default;

int MaxThreads() {
  return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}
int HardwareThreads() { return tbb::info::default_concurrency(); }

}  // namespace voxplan
