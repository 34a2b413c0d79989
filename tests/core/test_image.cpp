// Image's pixel storage: cache-line aligned (Raycast streams whole-line rows into it) and an
// ordinary container otherwise.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/image.h"

namespace voxplan {
namespace {

bool OnCacheLine(const void* p) { return reinterpret_cast<std::uintptr_t>(p) % 64 == 0; }

// Sizes from one pixel to past glibc's mmap threshold, allocated, grown, copied and freed in
// an interleaved order, so every offset malloc hands out is met: each buffer starts on a cache
// line, keeps its pixels, and frees cleanly (ASan and glibc's checks catch a wrong offset).
TEST(Image, PixelsStartOnACacheLineAndKeepTheirValues) {
  std::vector<Image<uint8_t>> bytes;
  std::vector<Image<Eigen::Vector3f>> vectors;
  for (int w : {1, 3, 16, 17, 157, 640}) {
    for (int h : {1, 5, 117, 480}) {
      bytes.emplace_back(w, h, uint8_t(w + h));
      vectors.emplace_back(w, h, Eigen::Vector3f(float(w), float(h), 1.f));
      ASSERT_TRUE(OnCacheLine(bytes.back().data.data()));
      ASSERT_TRUE(OnCacheLine(vectors.back().data.data()));
    }
    bytes.erase(bytes.begin());  // frees between allocations: malloc reuses odd places
  }
  for (Image<uint8_t>& image : bytes) {
    const uint8_t fill = image.data.front();
    image.data.push_back(fill);  // reallocates
    const Image<uint8_t> copy = image;
    EXPECT_TRUE(OnCacheLine(image.data.data()));
    EXPECT_TRUE(OnCacheLine(copy.data.data()));
    EXPECT_EQ(std::count(copy.data.begin(), copy.data.end(), fill),
              std::ptrdiff_t(copy.data.size()));
  }
  for (const Image<Eigen::Vector3f>& image : vectors) {
    const Eigen::Vector3f expected(float(image.width), float(image.height), 1.f);
    for (const Eigen::Vector3f& v : image.data) ASSERT_EQ(v, expected);
  }
}

}  // namespace
}  // namespace voxplan
