#pragma once
// Owned images. Depth is float metres (0 = invalid); colour is packed RGBX, 4 bytes per pixel,
// so SIMD kernels can gather a pixel with one 32-bit load.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <vector>

namespace voxplan {

// Pixels start on a cache line, so rows of whole lines can be written with streaming stores
// (Raycast's outputs). Over-allocated from malloc and aligned by hand, the offset kept in the
// byte before the pixels: the aligned operator new (memalign) left glibc's heap fragmented,
// peak RSS of a 200-frame fusion 61 -> 256 MB.
template <typename T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr size_t kAlignment = 64;
  static_assert(alignof(T) <= kAlignment);
  CacheLineAllocator() = default;
  template <typename U>
  CacheLineAllocator(const CacheLineAllocator<U>&) {}
  T* allocate(size_t n) {
    if (n > (std::numeric_limits<size_t>::max() - kAlignment) / sizeof(T)) throw std::bad_alloc();
    auto* raw = static_cast<unsigned char*>(std::malloc(n * sizeof(T) + kAlignment));
    if (!raw) throw std::bad_alloc();
    // The offset, 1 to 64 (16 to 64 from glibc), fits the byte before the pixels.
    const size_t offset = kAlignment - reinterpret_cast<uintptr_t>(raw) % kAlignment;
    raw[offset - 1] = static_cast<unsigned char>(offset);
    return reinterpret_cast<T*>(raw + offset);
  }
  void deallocate(T* p, size_t) {
    auto* pixels = reinterpret_cast<unsigned char*>(p);
    std::free(pixels - pixels[-1]);
  }
  template <typename U>
  bool operator==(const CacheLineAllocator<U>&) const {
    return true;
  }
};

template <typename T>
struct Image {
  int width = 0;
  int height = 0;
  std::vector<T, CacheLineAllocator<T>> data;  // row-major, width * height

  Image() = default;
  Image(int w, int h, T fill = T{}) : width(w), height(h), data(size_t(w) * size_t(h), fill) {}
  bool empty() const { return data.empty(); }
  T& at(int u, int v) { return data[size_t(v) * size_t(width) + size_t(u)]; }
  const T& at(int u, int v) const { return data[size_t(v) * size_t(width) + size_t(u)]; }
};

using DepthImage = Image<float>;
using ColorImage = Image<uint32_t>;
using LabelImage = Image<uint32_t>;

inline uint32_t PackRgb(uint8_t r, uint8_t g, uint8_t b) {
  return uint32_t(r) | (uint32_t(g) << 8) | (uint32_t(b) << 16);
}
inline uint8_t Red(uint32_t c) { return uint8_t(c & 0xff); }
inline uint8_t Green(uint32_t c) { return uint8_t((c >> 8) & 0xff); }
inline uint8_t Blue(uint32_t c) { return uint8_t((c >> 16) & 0xff); }

}  // namespace voxplan
