#include "core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

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
