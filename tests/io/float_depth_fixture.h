#pragma once
// Depth files the way datasets ship them besides 16-bit PNG, written with libtiff and OpenEXR
// for the tests of io/depth_image.h (tests/io) and of `fuse` over them (tests/system): 32-bit
// float TIFF and OpenEXR in metres, 16-bit TIFF in units, in the layouts tools write (strips or
// tiles, compressed or not, either byte order; scanline or tiled EXR, any channel name), and
// whatever else a test wants refused. Include only from tests that link TIFF::TIFF and
// OpenEXR::OpenEXR.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>
#include <gtest/gtest.h>
#include <half.h>
#include <tiffio.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/image.h"

namespace voxplan::test {

// How a TIFF is laid out: libtiff's codes for compression and predictor.
struct TiffLayout {
  uint16_t compression = COMPRESSION_LZW;
  uint16_t predictor = PREDICTOR_NONE;  // PREDICTOR_HORIZONTAL, PREDICTOR_FLOATINGPOINT
  uint32_t tile = 0;                    // tile side (a multiple of 16), 0 for strips
  uint32_t rows_per_strip = 0;          // 0: libtiff's default (strips of about 8 KiB)
  bool big_endian = false;
  uint16_t planar = PLANARCONFIG_CONTIG;
  // The image directory before the pixel data (libtiff puts it after them), so that a file cut
  // short loses pixels, not its directory.
  bool directory_first = false;
};

// Writes `pixels` (row-major, `samples` interleaved per pixel, each of `bits` bits in TIFF sample
// format `format`: SAMPLEFORMAT_UINT, _INT or _IEEEFP) as a TIFF, asserting that it did.
inline void WriteTiff(const std::filesystem::path& path, int width, int height, int samples,
                      int bits, uint16_t format, const void* pixels,
                      const TiffLayout& layout = {}) {
  std::filesystem::create_directories(path.parent_path());
  // w+: a directory written first is read back to add its pixels.
  TIFF* tif = TIFFOpen(path.c_str(), layout.big_endian ? "w+b" : "w+l");
  ASSERT_NE(tif, nullptr) << path;
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, uint32_t(width));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, uint32_t(height));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, uint16_t(samples));
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, uint16_t(bits));
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, format);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, samples == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, layout.planar);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, layout.compression);
  if (layout.predictor != PREDICTOR_NONE) TIFFSetField(tif, TIFFTAG_PREDICTOR, layout.predictor);
  const size_t bytes = size_t(bits / 8), pixel = bytes * size_t(samples);
  const auto* in = static_cast<const uint8_t*>(pixels);
  if (layout.tile) {
    TIFFSetField(tif, TIFFTAG_TILEWIDTH, layout.tile);
    TIFFSetField(tif, TIFFTAG_TILELENGTH, layout.tile);
  } else {
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP,
                 layout.rows_per_strip ? layout.rows_per_strip : TIFFDefaultStripSize(tif, 0));
  }
  if (layout.directory_first) {  // libtiff's sequence for it (TIFFDeferStrileArrayWriting)
    ASSERT_EQ(TIFFDeferStrileArrayWriting(tif), 1);
    ASSERT_EQ(TIFFWriteCheck(tif, layout.tile != 0, "WriteTiff"), 1);
    ASSERT_EQ(TIFFWriteDirectory(tif), 1);
    ASSERT_EQ(TIFFSetDirectory(tif, 0), 1);
  }
  ASSERT_EQ(layout.planar == PLANARCONFIG_SEPARATE ? samples : 1, 1) << "one plane only";
  if (layout.tile) {
    const uint32_t t = layout.tile;
    std::vector<uint8_t> tile(size_t(t) * t * pixel);
    for (uint32_t y = 0; y < uint32_t(height); y += t)
      for (uint32_t x = 0; x < uint32_t(width); x += t) {
        std::fill(tile.begin(), tile.end(), uint8_t(0));
        for (uint32_t r = 0; r < t && y + r < uint32_t(height); ++r)
          std::memcpy(tile.data() + size_t(r) * t * pixel,
                      in + (size_t(y + r) * size_t(width) + x) * pixel,
                      std::min<size_t>(t, size_t(width) - x) * pixel);
        ASSERT_NE(TIFFWriteEncodedTile(tif, TIFFComputeTile(tif, x, y, 0, 0), tile.data(),
                                       tmsize_t(tile.size())),
                  -1);
      }
  } else {
    uint32_t rows = 0;
    TIFFGetField(tif, TIFFTAG_ROWSPERSTRIP, &rows);
    for (uint32_t y = 0; y < uint32_t(height); y += rows) {
      const size_t n = std::min<size_t>(rows, size_t(height) - y) * size_t(width) * pixel;
      const uint8_t* first = in + size_t(y) * size_t(width) * pixel;
      std::vector<uint8_t> strip(first, first + n);  // a copy: libtiff may encode in place
      ASSERT_NE(TIFFWriteEncodedStrip(tif, TIFFComputeStrip(tif, y, 0), strip.data(), tmsize_t(n)),
                -1);
    }
  }
  if (layout.directory_first) {
    ASSERT_EQ(TIFFForceStrileArrayWriting(tif), 1);
  }
  TIFFClose(tif);
}

// How an EXR is laid out.
struct ExrLayout {
  Imf::Compression compression = Imf::ZIP_COMPRESSION;
  int tile = 0;   // tile side, 0 for scanlines
  int x_min = 0;  // the data window's origin
  int y_min = 0;
};

// Writes one channel per name, each a row-major plane of `width` x `height` values, stored as
// `type` (FLOAT; HALF, rounded as Imath's half(float); UINT, the values truncated), asserting
// that it did.
inline void WriteExr(const std::filesystem::path& path, int width, int height,
                     const std::vector<std::string>& names,
                     const std::vector<std::vector<float>>& planes,
                     Imf::PixelType type = Imf::FLOAT, const ExrLayout& layout = {}) {
  std::filesystem::create_directories(path.parent_path());
  ASSERT_EQ(names.size(), planes.size());
  const Imath::Box2i window(Imath::V2i(layout.x_min, layout.y_min),
                            Imath::V2i(layout.x_min + width - 1, layout.y_min + height - 1));
  Imf::Header header(window, window);
  header.compression() = layout.compression;
  if (layout.tile)
    header.setTileDescription(Imf::TileDescription(unsigned(layout.tile), unsigned(layout.tile)));
  const size_t n = size_t(width) * size_t(height);
  std::vector<std::vector<half>> halves(planes.size());
  std::vector<std::vector<uint32_t>> uints(planes.size());
  Imf::FrameBuffer frame;
  for (size_t c = 0; c < names.size(); ++c) {
    ASSERT_EQ(planes[c].size(), n);
    header.channels().insert(names[c], Imf::Channel(type));
    const void* base = planes[c].data();
    size_t size = sizeof(float);
    if (type == Imf::HALF) {
      for (float v : planes[c]) halves[c].push_back(half(v));
      base = halves[c].data(), size = sizeof(half);
    } else if (type == Imf::UINT) {
      for (float v : planes[c]) uints[c].push_back(uint32_t(v));
      base = uints[c].data(), size = sizeof(uint32_t);
    }
    frame.insert(names[c], Imf::Slice::Make(type, base, window, size, size * size_t(width)));
  }
  try {
    if (layout.tile) {
      Imf::TiledOutputFile out(path.c_str(), header);
      out.setFrameBuffer(frame);
      out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
    } else {
      Imf::OutputFile out(path.c_str(), header);
      out.setFrameBuffer(frame);
      out.writePixels(height);
    }
  } catch (const std::exception& e) {
    FAIL() << path << ": " << e.what();
  }
}

// Float metres as a .tif/.tiff (32-bit float, LZW strips) or .exr (one FLOAT channel Y, ZIP
// compressed): lossless, invalid values kept as written.
inline void WriteFloatDepth(const std::filesystem::path& path, const DepthImage& depth) {
  const std::string ext = path.extension().string();
  if (ext == ".exr" || ext == ".EXR") {
    WriteExr(path, depth.width, depth.height, {"Y"},
             {std::vector<float>(depth.data.begin(), depth.data.end())});
  } else {
    WriteTiff(path, depth.width, depth.height, 1, 32, SAMPLEFORMAT_IEEEFP, depth.data.data());
  }
}

// Raw 16-bit units as a TIFF.
inline void WriteDepthTiff16(const std::filesystem::path& path, int width, int height,
                             const std::vector<uint16_t>& units, const TiffLayout& layout = {}) {
  ASSERT_EQ(units.size(), size_t(width) * size_t(height));
  WriteTiff(path, width, height, 1, 16, SAMPLEFORMAT_UINT, units.data(), layout);
}

}  // namespace voxplan::test
