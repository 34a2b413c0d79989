#pragma once
// PNG (libpng) and JPEG (libjpeg) decoding and PNG writing for depth and colour images. Every
// error names the file; nothing is printed (libpng/libjpeg messages are captured into the Status).
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/image.h"
#include "core/status.h"

namespace voxplan {

// What a PNG's IHDR says, read without decoding pixels.
struct PngHeader {
  int width = 0;
  int height = 0;
  int bit_depth = 0;  // bits per channel: 1, 2, 4, 8 or 16
  int channels = 0;   // 1 gray, 2 gray+alpha, 3 RGB, 4 RGBA (palette images report 1)
  bool palette = false;
};

// Reads only the signature and IHDR chunk (cheap: a few dozen bytes).
Result<PngHeader> ReadPngHeader(const std::string& path);

// Decodes a 16-bit single-channel PNG into metres: value / depth_scale (units per metre);
// 0 stays 0 (invalid). 8-bit, palette, alpha or multi-channel PNGs are refused.
Result<DepthImage> ReadDepthPng(const std::string& path, double depth_scale);

// Decodes an 8-bit PNG (gray, gray+alpha, RGB, RGBA, palette; 16-bit is down-converted, alpha
// dropped) or a JPEG (gray or colour) into packed RGBX. The format comes from the file's magic
// bytes, not its extension. Truncated or corrupt files are refused (libjpeg's "premature end"
// warning included).
Result<ColorImage> ReadColorImage(const std::string& path);

// The same for an image held in memory (a frame inside a container file); `name` is what errors
// are named by ("scene.sens: frame 12").
Result<ColorImage> DecodeColorImage(const void* data, size_t size, const std::string& name);

// Encodes 8-bit RGB (the X byte dropped) as a baseline JPEG of `quality` (1..100), for files
// that carry JPEG frames (ScanNet .sens) and their test fixtures.
Result<std::string> EncodeJpeg(const ColorImage& color, int quality = 90);

// Writes round(depth * depth_scale) as a 16-bit gray PNG. Invalid depth (<= 0, NaN, inf) is
// written as 0; a finite depth that does not fit in 16 bits is refused rather than clipped, so a
// caller with long-range depth must cap it first. Written to a temporary file in the same folder
// and renamed over `path`.
Status WriteDepthPng16(const std::string& path, const DepthImage& depth, double depth_scale);

// Writes an 8-bit RGB PNG (the X byte is dropped); temporary file then rename.
Status WriteColorPng(const std::string& path, const ColorImage& color);

// Writes raw interleaved samples as a PNG (for fixtures and tools): channels 1..4 (gray, gray+
// alpha, RGB, RGBA), bit_depth 8 or 16; 16-bit samples are host-order uint16_t. `data` holds
// width * height * channels samples. Temporary file then rename.
Status WritePngRaw(const std::string& path, int width, int height, int channels, int bit_depth,
                   const void* data);

}  // namespace voxplan
