#pragma once
// Internal to io: the fast path of ReadDepthPng (image_io.h). A depth PNG as cameras and datasets
// write it (16-bit gray, not interlaced, chunks in order, every CRC and the zlib checksum right)
// is decoded from memory: libdeflate inflates the IDAT stream, an SSE2 kernel undoes the row
// filters eight rows at a time. Anything else, and anything irregular, is declined (false), and
// ReadDepthPng hands the file to libpng as before, so libpng's results and messages stand for
// every file this path does not take. Where it takes a file, its pixels are libpng's.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/image.h"

namespace voxplan::png_fast {

// Undoes PNG row filtering (types 0-4) of `height` rows of `row_bytes` bytes at `bpp` bytes per
// pixel. `filtered` holds each row as its filter-type byte then the row's bytes; `out` receives
// height * row_bytes bytes. False when a row has a filter type above 4 (out is then partly
// written). The reference: one byte at a time, as the PNG specification states it.
bool UnfilterScalar(const uint8_t* filtered, size_t row_bytes, size_t height, int bpp,
                    uint8_t* out);

// The same for 2 bytes per pixel (16-bit gray), eight rows at once in SSE2 lanes where the CPU
// has SSE2 (rows staggered by a pixel, so each row's left neighbour and the row above are
// ready); byte-identical to UnfilterScalar.
bool UnfilterGray16(const uint8_t* filtered, size_t width, size_t height, uint8_t* out);

// Big-endian 16-bit samples to metres, as ReadDepthPng converts: float(double(v) / scale)
// computed as float(double(v) * (1 / scale)); 0 stays 0.
void BigEndianToMetres(const uint8_t* samples, size_t count, double depth_scale, float* out);

// Decodes the PNG in `file` (its whole bytes) into `depth` when it is a 16-bit gray,
// non-interlaced PNG of at most `max_side` pixels a side whose chunks are IHDR first, contiguous
// IDATs, IEND, and ancillary chunks, every CRC right, one complete zlib stream (32 KiB window,
// checksum right) filling the rows exactly. Otherwise false and `depth` untouched.
bool DecodeDepthPng(const uint8_t* file, size_t size, int max_side, double depth_scale,
                    DepthImage& depth);

}  // namespace voxplan::png_fast
