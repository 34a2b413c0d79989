#include <gtest/gtest.h>

#include <atomic>
#include <vector>

#include "core/parallel.h"

namespace voxplan {
namespace {

TEST(Parallel, CoversEveryIndexExactlyOnce) {
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    EXPECT_EQ(MaxThreads(), threads);
    std::vector<std::atomic<int>> hits(10007);
    ParallelFor(hits.size(), 13, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) hits[i]++;
    });
    for (const auto& h : hits) ASSERT_EQ(h.load(), 1);
  }
}

TEST(Parallel, EmptyRangeCallsNothing) {
  bool called = false;
  ParallelFor(0, 1, [&](size_t, size_t) { called = true; });
  EXPECT_FALSE(called);
}

}  // namespace
}  // namespace voxplan
