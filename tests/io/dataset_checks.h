// Checks every dataset reader must pass, shared by the readers' tests.
#pragma once

#include <gtest/gtest.h>

#include <optional>
#include <thread>
#include <vector>

#include "io/dataset.h"

namespace voxplan::test {

// fuse decodes frames ahead on worker threads: loads from four threads at once give the frames
// one thread loads.
inline void ExpectThreadedLoadsMatchOneThread(const Dataset& ds) {
  const size_t n = ds.info().num_frames;
  std::vector<Frame> one;
  for (size_t i = 0; i < n; ++i) one.push_back(ds.Load(i).value());
  std::vector<std::optional<Frame>> many(n);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (size_t i = t; i < n; i += 4) {
        Result<Frame> f = ds.Load(i);
        if (f.ok()) many[i] = std::move(f).value();
      }
    });
  for (std::thread& t : threads) t.join();
  for (size_t i = 0; i < n; ++i) {
    ASSERT_TRUE(many[i].has_value()) << i;
    EXPECT_EQ(many[i]->depth.data, one[i].depth.data) << i;
    EXPECT_EQ(many[i]->color.data, one[i].color.data) << i;
  }
}

}  // namespace voxplan::test
