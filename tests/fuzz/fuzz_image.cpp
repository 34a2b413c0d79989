// The depth and colour image loaders (io/image_io.h) on arbitrary bytes: the PNG header reader,
// the 16-bit depth decoder and the PNG/JPEG colour decoder. Each must return an image whose size
// matches its pixels, or a Status; never crash, leak or allocate without bound.
#include <cstdint>
#include <cstdlib>

#include "io/image_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace voxplan;
  const std::string path = fuzz::InputFile(data, size, "image.png");
  const Result<PngHeader> header = ReadPngHeader(path);
  const Result<DepthImage> depth = ReadDepthPng(path, 1000.0);
  if (depth.ok()) {
    if (depth->data.size() != size_t(depth->width) * size_t(depth->height)) std::abort();
    // A decodable depth PNG has a readable header describing it.
    if (!header.ok() || header->width != depth->width || header->height != depth->height)
      std::abort();
  }
  const Result<ColorImage> color = ReadColorImage(path);
  if (color.ok() && color->data.size() != size_t(color->width) * size_t(color->height))
    std::abort();
  return 0;
}
