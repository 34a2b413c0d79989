#pragma once
// IntegrateFrame over borrowed pixels: the same integration (same checks, same bits) reading
// depth and colour in place from memory another owner holds, such as the numpy arrays the
// Python bindings pass without a copy. Apart from integrate.h so that adding it rebuilt nothing.
#include <cstdint>

#include "core/image.h"
#include "fusion/integrate.h"

namespace voxplan {

// Row-major pixels, width * height of them from `data`, rows packed (no padding); not owned.
template <typename T>
struct ImageView {
  const T* data = nullptr;  // nullptr: no image (colour: integrate depth only)
  int width = 0;
  int height = 0;
  bool empty() const { return data == nullptr; }
};

template <typename T>
ImageView<T> ViewOf(const Image<T>& image) {
  return {image.empty() ? nullptr : image.data.data(), image.width, image.height};
}

// IntegrateFrame of integrate.h on views: depth in metres (0 = invalid), colour packed RGBX
// (core/image.h) or empty. The pixels must stay unchanged until it returns.
Result<IntegrateStats> IntegrateFrame(ImageView<float> depth, ImageView<uint32_t> color,
                                      const PinholeCamera& camera, const Pose3f& T_W_C,
                                      const IntegrateParams& params, TsdfVolume& volume);

}  // namespace voxplan
