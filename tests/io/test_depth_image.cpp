// Float depth (io/depth_image.h): 32-bit float TIFF and OpenEXR in metres, 16-bit TIFF in
// units, written by libtiff and OpenEXR here in the layouts tools write; read back exactly (all
// lossless), invalid values to 0, every other kind of file refused naming it, nothing printed,
// from several threads at once too; and the dataset readers that list depth files (TUM-style
// lists, 7-Scenes frame folders, Redwood depth/) reading them as metres.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "io/dataset.h"
#include "io/depth_image.h"
#include "io/image_io.h"
#include "tests/io/float_depth_fixture.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void WriteBytes(const fs::path& p, const std::string& bytes) {
  fs::create_directories(p.parent_path());
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}
void WriteText(const fs::path& p, const std::string& text) { WriteBytes(p, text); }

bool Contains(const std::string& s, const std::string& what) {
  return s.find(what) != std::string::npos;
}

// Failed with `code`, naming the file and saying `why`.
void ExpectRefused(const Status& s, StatusCode code, const fs::path& file, const std::string& why) {
  ASSERT_FALSE(s.ok()) << "expected " << file << " to be refused (" << why << ")";
  EXPECT_EQ(s.code(), code) << s.message();
  EXPECT_TRUE(Contains(s.message(), file.string())) << s.message();
  EXPECT_TRUE(Contains(s.message(), why)) << s.message();
}

// Reads `path` (header, then the whole image), expecting that neither prints anything; with
// `header_refuses`, that the header alone already refuses it as the decode does.
Status ReadQuietly(const fs::path& path, bool header_refuses = true) {
  testing::internal::CaptureStderr();
  const Status header = ReadDepthHeader(path.string()).status();
  const Status read = ReadDepthImage(path.string(), 1000.0).status();
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << path;
  if (header_refuses) {
    EXPECT_EQ(header.ok(), read.ok()) << header.message() << " / " << read.message();
    if (!header.ok()) {
      EXPECT_EQ(header.message(), read.message());
    }
  }
  return read;
}

// Values of every magnitude a depth camera sees, not round in binary, and a few that are.
DepthImage Ramp(int width, int height) {
  DepthImage d(width, height);
  for (int i = 0; i < width * height; ++i)
    d.data[size_t(i)] = 0.1f + 0.0123457f * float(i) + float(i % 7) * 1e-5f;
  d.data[0] = 0.5f;
  d.data[1] = 1e-30f;  // tiny, still positive
  d.data[2] = 65.535f;
  d.data[3] = 3.0e5f;  // beyond any camera: kept (fusion's depth range ignores it)
  return d;
}

DepthImage WithInvalidValues(int width, int height) {
  DepthImage d = Ramp(width, height);
  d.data[4] = std::numeric_limits<float>::quiet_NaN();
  d.data[5] = std::numeric_limits<float>::infinity();
  d.data[6] = -std::numeric_limits<float>::infinity();
  d.data[7] = -1.25f;
  d.data[8] = -0.f;
  d.data[9] = 0.f;
  d.data[10] = -std::numeric_limits<float>::denorm_min();
  return d;
}

void ExpectSameMetres(const DepthImage& read, const DepthImage& written) {
  ASSERT_EQ(read.width, written.width);
  ASSERT_EQ(read.height, written.height);
  for (size_t i = 0; i < written.data.size(); ++i) {
    const float w = written.data[i];
    const float expected = w > 0.f && std::isfinite(w) ? w : 0.f;
    ASSERT_EQ(read.data[i], expected) << "pixel " << i << " written " << w;
    ASSERT_FALSE(std::signbit(read.data[i])) << "pixel " << i;
  }
}

TEST(DepthImage, TypeComesFromTheExtension) {
  EXPECT_EQ(DepthFileTypeOf("a/b.tif"), DepthFileType::kTiff);
  EXPECT_EQ(DepthFileTypeOf("a/b.TIFF"), DepthFileType::kTiff);
  EXPECT_EQ(DepthFileTypeOf("b.Exr"), DepthFileType::kExr);
  EXPECT_EQ(DepthFileTypeOf("b.png"), DepthFileType::kPng);
  EXPECT_EQ(DepthFileTypeOf("b.depth"), DepthFileType::kPng);  // anything else: PNG, as before
}

TEST(DepthImage, FloatTiffAndExrReadBackExactlyInMetres) {
  test::TempDir dir("depth_image");
  const DepthImage depth = WithInvalidValues(37, 23);
  for (const char* name : {"d.tif", "d.tiff", "d.exr"}) {
    SCOPED_TRACE(name);
    const fs::path path = dir / name;
    test::WriteFloatDepth(path, depth);
    testing::internal::CaptureStderr();
    auto header = ReadDepthHeader(path.string());
    DepthFileHeader from_read;
    // The depth scale does not apply to float depth: any value, even a bad one, is ignored.
    auto read = ReadDepthImage(path.string(), 1000.0, &from_read);
    auto read_no_scale = ReadDepthImage(path.string(), 0.0);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    ASSERT_TRUE(header.ok()) << header.status().message();
    ASSERT_TRUE(read.ok()) << read.status().message();
    ASSERT_TRUE(read_no_scale.ok()) << read_no_scale.status().message();
    EXPECT_EQ(header->width, 37);
    EXPECT_EQ(header->height, 23);
    EXPECT_TRUE(header->metres);
    EXPECT_EQ(header->bits, 32);
    EXPECT_EQ(header->Encoding(),
              std::string("32-bit float ") + (Contains(name, "exr") ? "EXR" : "TIFF"));
    EXPECT_EQ(from_read.Encoding(), header->Encoding());
    ExpectSameMetres(*read, depth);
    ExpectSameMetres(*read_no_scale, depth);
  }
}

std::vector<float> Plane(const DepthImage& d) { return {d.data.begin(), d.data.end()}; }

TEST(DepthImage, EveryLosslessLayoutReadsTheSameMetres) {
  test::TempDir dir("depth_image");
  const DepthImage depth = WithInvalidValues(37, 23);  // no side a multiple of a tile's
  struct TiffCase {
    const char* name;
    test::TiffLayout layout;
  };
  std::vector<TiffCase> tiffs = {
      {"none.tif", {COMPRESSION_NONE}},
      {"lzw_rows1.tif", {COMPRESSION_LZW, PREDICTOR_NONE, 0, 1}},
      {"deflate_fp.tif", {COMPRESSION_ADOBE_DEFLATE, PREDICTOR_FLOATINGPOINT}},
      {"packbits.tif", {COMPRESSION_PACKBITS}},
      {"zstd.tif", {COMPRESSION_ZSTD}},
      {"big_endian.tif", {COMPRESSION_NONE, PREDICTOR_NONE, 0, 5, true}},
      // (Not big-endian with the floating-point predictor: Debian 12's libtiff 4.5.0 writes its
      // bytes wrong, as an independent decoder shows.)
      {"big_endian_lzw.tif", {COMPRESSION_LZW, PREDICTOR_NONE, 0, 0, true}},
      {"tiles16.tif", {COMPRESSION_NONE, PREDICTOR_NONE, 16}},
      {"tiles32_deflate.tif", {COMPRESSION_ADOBE_DEFLATE, PREDICTOR_FLOATINGPOINT, 32}},
      {"tiles_big_endian.tif", {COMPRESSION_LZW, PREDICTOR_NONE, 16, 0, true}},
      {"directory_first.tif",
       {COMPRESSION_LZW, PREDICTOR_NONE, 0, 4, false, PLANARCONFIG_CONTIG, true}},
      // One sample per pixel: the separate planar configuration is the same layout.
      {"planar_separate.tif",
       {COMPRESSION_NONE, PREDICTOR_NONE, 0, 0, false, PLANARCONFIG_SEPARATE}},
  };
  for (const TiffCase& c : tiffs) {
    SCOPED_TRACE(c.name);
    test::WriteTiff(dir / c.name, 37, 23, 1, 32, SAMPLEFORMAT_IEEEFP, depth.data.data(), c.layout);
    auto read = ReadQuietly(dir / c.name);
    ASSERT_TRUE(read.ok()) << read.message();
    ExpectSameMetres(*ReadDepthImage((dir / c.name).string(), 1000.0), depth);
  }
  struct ExrCase {
    const char* name;
    test::ExrLayout layout;
  };
  const std::vector<ExrCase> exrs = {
      {"none.exr", {Imf::NO_COMPRESSION}},
      {"rle.exr", {Imf::RLE_COMPRESSION}},
      {"zips.exr", {Imf::ZIPS_COMPRESSION}},
      {"zip.exr", {Imf::ZIP_COMPRESSION}},
      {"piz.exr", {Imf::PIZ_COMPRESSION}},
      {"origin.exr", {Imf::ZIP_COMPRESSION, 0, -3, 12}},  // the data window need not start at 0
      {"tiles16.exr", {Imf::NO_COMPRESSION, 16}},
      {"tiles32_zip.exr", {Imf::ZIP_COMPRESSION, 32}},
      {"tiles_piz_origin.exr", {Imf::PIZ_COMPRESSION, 16, 5, -7}},
  };
  for (const ExrCase& c : exrs) {
    SCOPED_TRACE(c.name);
    test::WriteExr(dir / c.name, 37, 23, {"Y"}, {Plane(depth)}, Imf::FLOAT, c.layout);
    auto header = ReadDepthHeader((dir / c.name).string());
    ASSERT_TRUE(header.ok()) << header.status().message();
    EXPECT_EQ(header->width, 37);
    EXPECT_EQ(header->height, 23);
    auto read = ReadQuietly(dir / c.name);
    ASSERT_TRUE(read.ok()) << read.message();
    ExpectSameMetres(*ReadDepthImage((dir / c.name).string(), 1000.0), depth);
  }
}

TEST(DepthImage, ExrHalfFloatAndAnyChannelName) {
  test::TempDir dir("depth_image");
  const DepthImage depth = Ramp(16, 9);
  // Half floats: metres rounded to 11 bits, read back widened exactly.
  for (int tile : {0, 16}) {
    SCOPED_TRACE(tile);
    const fs::path half_exr = dir / ("half" + std::to_string(tile) + ".exr");
    test::WriteExr(half_exr, 16, 9, {"Y"}, {Plane(depth)}, Imf::HALF, {Imf::ZIP_COMPRESSION, tile});
    auto h = ReadDepthImage(half_exr.string(), 1000.0);
    ASSERT_TRUE(h.ok()) << h.status().message();
    EXPECT_EQ(ReadDepthHeader(half_exr.string())->Encoding(), "16-bit float EXR");
    for (size_t i = 0; i < depth.data.size(); ++i) {
      const float widened = float(half(depth.data[i]));
      EXPECT_EQ(h->data[i], widened > 0.f && std::isfinite(widened) ? widened : 0.f) << i;
      if (i >= 5) {
        EXPECT_NEAR(h->data[i], depth.data[i], depth.data[i] * 1e-3f) << i;
      }
    }
  }
  // A lone channel reads the same whatever it is named: Y (as OpenCV writes it), R, Z (a
  // common name for depth), a layer's Depth.Z.
  for (const char* name : {"Y", "R", "Z", "ViewLayer.Depth.Z"}) {
    SCOPED_TRACE(name);
    const fs::path path = dir / (std::string("channel_") + name + ".exr");
    test::WriteExr(path, 16, 9, {name}, {Plane(depth)}, Imf::FLOAT, {Imf::NO_COMPRESSION});
    auto read = ReadQuietly(path);
    ASSERT_TRUE(read.ok()) << read.message();
    ExpectSameMetres(*ReadDepthImage(path.string(), 1000.0), depth);
  }
}

TEST(DepthImage, SixteenBitTiffUsesTheDepthScaleLikeAPng) {
  test::TempDir dir("depth_image");
  std::vector<uint16_t> units;
  for (int i = 0; i < 11 * 7; ++i) units.push_back(uint16_t(i * 851 % 65536));
  units[3] = 65535;
  const fs::path tif = dir / "d.tif", png = dir / "d.png";
  test::WriteDepthTiff16(tif, 11, 7, units);
  ASSERT_TRUE(WritePngRaw(png.string(), 11, 7, 1, 16, units.data()).ok());
  auto header = ReadDepthHeader(tif.string());
  ASSERT_TRUE(header.ok()) << header.status().message();
  EXPECT_FALSE(header->metres);
  EXPECT_EQ(header->Encoding(), "16-bit TIFF");
  EXPECT_EQ(ReadDepthHeader(png.string())->Encoding(), "16-bit PNG");
  for (double scale : {1000.0, 5000.0, 6553.5}) {
    auto from_tif = ReadDepthImage(tif.string(), scale);
    auto from_png = ReadDepthPng(png.string(), scale);
    ASSERT_TRUE(from_tif.ok()) << from_tif.status().message();
    ASSERT_TRUE(from_png.ok()) << from_png.status().message();
    EXPECT_EQ(from_tif->data, from_png->data) << scale;  // the same floats, bit for bit
  }
  ExpectRefused(ReadDepthImage(tif.string(), 0.0).status(), StatusCode::kInvalidArgument, tif,
                "depth scale must be positive");
  // Other layouts: the same floats as the PNG.
  const test::TiffLayout layouts[] = {
      {COMPRESSION_NONE, PREDICTOR_NONE, 0, 0, true},  // big-endian samples
      {COMPRESSION_ADOBE_DEFLATE, PREDICTOR_HORIZONTAL},
      {COMPRESSION_LZW, PREDICTOR_HORIZONTAL, 16, 0, true},  // tiles, big-endian
      {COMPRESSION_NONE, PREDICTOR_NONE, 0, 2, false, PLANARCONFIG_CONTIG, true},
  };
  auto from_png = ReadDepthPng(png.string(), 5000.0);
  ASSERT_TRUE(from_png.ok()) << from_png.status().message();
  for (size_t k = 0; k < std::size(layouts); ++k) {
    SCOPED_TRACE(k);
    const fs::path other = dir / ("layout" + std::to_string(k) + ".tif");
    test::WriteDepthTiff16(other, 11, 7, units, layouts[k]);
    auto from_tif = ReadDepthImage(other.string(), 5000.0);
    ASSERT_TRUE(from_tif.ok()) << from_tif.status().message();
    EXPECT_EQ(from_tif->data, from_png->data);
  }
}

TEST(DepthImage, RefusesOtherKindsNamingTheFile) {
  test::TempDir dir("depth_image");
  const std::vector<uint8_t> zeros(6 * 5 * 3 * 8, 0);  // enough for any of these
  struct Case {
    const char* name;
    int samples, bits;
    uint16_t format;
    const char* why;
  } cases[] = {
      {"gray8.tif", 1, 8, SAMPLEFORMAT_UINT, "found 8-bit unsigned integer samples"},
      {"rgb16.tif", 3, 16, SAMPLEFORMAT_UINT, "single-channel, found 3 samples per pixel"},
      {"rgbf.tiff", 3, 32, SAMPLEFORMAT_IEEEFP, "single-channel, found 3 samples per pixel"},
      {"doubles.tif", 1, 64, SAMPLEFORMAT_IEEEFP, "found 64-bit float samples"},
      {"ints.tif", 1, 32, SAMPLEFORMAT_INT, "found 32-bit signed integer samples"},
      {"uints.tif", 1, 32, SAMPLEFORMAT_UINT, "found 32-bit unsigned integer samples"},
      {"signed16.tif", 1, 16, SAMPLEFORMAT_INT, "found 16-bit signed integer samples"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    test::WriteTiff(dir / c.name, 5, 6, c.samples, c.bits, c.format, zeros.data());
    ExpectRefused(ReadQuietly(dir / c.name), StatusCode::kUnsupported, dir / c.name, c.why);
  }
  const std::vector<float> plane(5 * 6, 1.5f);
  test::WriteExr(dir / "rgbf.exr", 5, 6, {"B", "G", "R"}, {plane, plane, plane});
  ExpectRefused(ReadQuietly(dir / "rgbf.exr"), StatusCode::kUnsupported, dir / "rgbf.exr",
                "must have one channel, found 3 (B G R)");
  test::WriteExr(dir / "uint.exr", 5, 6, {"Z"}, {plane}, Imf::UINT);
  ExpectRefused(ReadQuietly(dir / "uint.exr"), StatusCode::kUnsupported, dir / "uint.exr",
                "channel Z must hold float metres (32- or 16-bit), found 32-bit unsigned integers");
  // Tiles far larger than the image (a corrupt or hostile header): refused before allocating.
  std::vector<float> small(16 * 16, 1.f);
  test::WriteTiff(dir / "huge_tiles.tif", 16, 16, 1, 32, SAMPLEFORMAT_IEEEFP, small.data(),
                  {COMPRESSION_LZW, PREDICTOR_NONE, 2048});
  ExpectRefused(ReadQuietly(dir / "huge_tiles.tif"), StatusCode::kCorruptData,
                dir / "huge_tiles.tif", "TIFF tiles of 2048x2048 pixels for a 16x16 image");
  test::WriteExr(dir / "huge_tiles.exr", 16, 16, {"Y"}, {small}, Imf::FLOAT,
                 {Imf::ZIP_COMPRESSION, 2048});
  ExpectRefused(ReadQuietly(dir / "huge_tiles.exr"), StatusCode::kCorruptData,
                dir / "huge_tiles.exr", "OpenEXR tiles of 2048x2048 pixels for a 16x16 image");
  // Not what its name says: a PNG named .tif, a TIFF named .exr, text, an empty file.
  const fs::path png = dir / "really_png.tif";
  const uint16_t units[4] = {1, 2, 3, 4};
  ASSERT_TRUE(WritePngRaw(png.string(), 2, 2, 1, 16, units).ok());
  ExpectRefused(ReadQuietly(png), StatusCode::kCorruptData, png, "not a TIFF file");
  test::WriteFloatDepth(dir / "t.tif", Ramp(4, 3));
  ASSERT_TRUE(ReadDepthImage((dir / "t.tif").string(), 1000.0).ok());
  WriteBytes(dir / "tiff.exr", ReadBytes(dir / "t.tif"));
  ExpectRefused(ReadQuietly(dir / "tiff.exr"), StatusCode::kCorruptData, dir / "tiff.exr",
                "not an OpenEXR file");
  WriteText(dir / "text.exr", "hello\n");
  ExpectRefused(ReadQuietly(dir / "text.exr"), StatusCode::kCorruptData, dir / "text.exr",
                "not an OpenEXR file");
  WriteText(dir / "empty.tif", "");
  ExpectRefused(ReadQuietly(dir / "empty.tif"), StatusCode::kCorruptData, dir / "empty.tif",
                "not a TIFF file");
  ExpectRefused(ReadDepthImage((dir / "missing.exr").string(), 1000.0).status(),
                StatusCode::kNotFound, dir / "missing.exr", "not found");
}

// Strip (or tile) k's offset in a TIFF, as libtiff reads it.
uint64_t StripOffset(const fs::path& path, uint32_t k = 0) {
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  EXPECT_NE(tif, nullptr) << path;
  if (!tif) return 0;
  const uint64_t offset = TIFFGetStrileOffset(tif, k);
  TIFFClose(tif);
  return offset;
}

// `path` with strip k's zlib header garbled (a deflate TIFF), as `out`.
void BreakZlibStrip(const fs::path& path, uint32_t k, const fs::path& out) {
  std::string bytes = ReadBytes(path);
  const uint64_t at = StripOffset(path, k);
  ASSERT_LT(at + 2, bytes.size());
  bytes[at] ^= 0x5a, bytes[at + 1] ^= 0x5a;
  WriteBytes(out, bytes);
}

TEST(DepthImage, TruncatedAndCorruptFilesAreRefusedQuietly) {
  test::TempDir dir("depth_image");
  const DepthImage depth = Ramp(64, 40);
  // TIFF with its directory first (so that cutting it cuts pixels), uncompressed and LZW; as
  // libtiff writes it (directory last); EXR (whose header's chunk table shows the cut).
  test::WriteTiff(dir / "first.tif", 64, 40, 1, 32, SAMPLEFORMAT_IEEEFP, depth.data.data(),
                  {COMPRESSION_NONE, PREDICTOR_NONE, 0, 8, false, PLANARCONFIG_CONTIG, true});
  test::WriteTiff(dir / "first_lzw.tif", 64, 40, 1, 32, SAMPLEFORMAT_IEEEFP, depth.data.data(),
                  {COMPRESSION_LZW, PREDICTOR_NONE, 0, 8, false, PLANARCONFIG_CONTIG, true});
  test::WriteTiff(dir / "first_tiles.tif", 64, 40, 1, 32, SAMPLEFORMAT_IEEEFP, depth.data.data(),
                  {COMPRESSION_NONE, PREDICTOR_NONE, 16, 0, false, PLANARCONFIG_CONTIG, true});
  test::WriteFloatDepth(dir / "d.tif", depth);
  test::WriteFloatDepth(dir / "d.exr", depth);
  ASSERT_LT(StripOffset(dir / "first.tif"), 1000u);  // the directory came first
  for (const char* name : {"first.tif", "first_lzw.tif", "first_tiles.tif", "d.tif", "d.exr"}) {
    SCOPED_TRACE(name);
    const std::string bytes = ReadBytes(dir / name);
    ASSERT_TRUE(ReadQuietly(dir / name).ok());
    for (size_t keep : {size_t(6), size_t(40), bytes.size() / 3, bytes.size() - 9}) {
      const fs::path cut = dir / ("cut_" + std::to_string(keep) + "_" + name);
      WriteBytes(cut, bytes.substr(0, keep));
      // EXR: the header's chunk table already shows the file is cut short; TIFF: a directory
      // cut is refused by the header, pixels cut when libtiff decodes them.
      const Status s = ReadQuietly(cut, Contains(name, "exr"));
      ASSERT_FALSE(s.ok()) << cut << " (" << keep << " of " << bytes.size() << " bytes) read";
      EXPECT_EQ(s.code(), StatusCode::kCorruptData) << s.message();
      EXPECT_TRUE(Contains(s.message(), cut.string())) << s.message();
      if (Contains(name, "first") && keep > 1000) {
        EXPECT_TRUE(Contains(s.message(), "does not decode (corrupt or truncated pixel data)"))
            << s.message();
      }
    }
  }
  // Compressed pixels that do not decode, every chunk or strip in the file: only decoding finds
  // them, refused naming the file with the library's reason, and nothing printed.
  DepthImage smooth(64, 64);
  for (size_t i = 0; i < smooth.data.size(); ++i) smooth.data[i] = 1.f + 0.001f * float(i % 64 / 8);
  for (int tile : {0, 16}) {
    SCOPED_TRACE(tile);
    const fs::path zip = dir / ("smooth" + std::to_string(tile) + ".exr");
    test::WriteExr(zip, 64, 64, {"Y"}, {Plane(smooth)}, Imf::FLOAT, {Imf::ZIP_COMPRESSION, tile});
    std::string zipped = ReadBytes(zip);
    for (size_t i = zipped.size() * 2 / 3; i < zipped.size() * 2 / 3 + 20; ++i) zipped[i] ^= 0x5a;
    const fs::path garbled = dir / ("garbled" + std::to_string(tile) + ".exr");
    WriteBytes(garbled, zipped);
    ASSERT_TRUE(ReadDepthHeader(garbled.string()).ok());
    ExpectRefused(ReadQuietly(garbled, false), StatusCode::kCorruptData, garbled,
                  "OpenEXR cannot decode it (corrupt or truncated pixel data)");
  }
  // A deflate strip whose zlib header is wrong.
  test::WriteTiff(dir / "deflate.tif", 64, 64, 1, 32, SAMPLEFORMAT_IEEEFP, smooth.data.data(),
                  {COMPRESSION_ADOBE_DEFLATE});
  BreakZlibStrip(dir / "deflate.tif", 0, dir / "bad_zlib.tif");
  ExpectRefused(ReadQuietly(dir / "bad_zlib.tif", false), StatusCode::kCorruptData,
                dir / "bad_zlib.tif", "TIFF strip 0 of ");
  const std::string message =
      ReadDepthImage((dir / "bad_zlib.tif").string(), 1000.0).status().message();
  EXPECT_TRUE(Contains(message, "(libtiff: ")) << message;  // libtiff's reason, not printed
  // Headers claiming more than 16384 pixels a side are refused before anything is decoded.
  std::string exr = ReadBytes(dir / "d.exr");
  const size_t window = exr.find(std::string("dataWindow\0box2i\0", 17));
  ASSERT_NE(window, std::string::npos);
  const int32_t huge = 1 << 20;
  std::memcpy(&exr[window + 17 + 4 + 8], &huge, 4);  // xMax
  WriteBytes(dir / "huge.exr", exr);
  ExpectRefused(ReadQuietly(dir / "huge.exr"), StatusCode::kCorruptData, dir / "huge.exr",
                "each side must be 1 to 16384 pixels");
}

// Datasets decode frames on several threads at once (Dataset::Load): every thread's errors are
// its own (each names its file and its strip), the good files read right, nothing is printed.
TEST(DepthImage, ThreadsDecodeAndRefuseQuietly) {
  test::TempDir dir("depth_image_threads");
  const DepthImage depth = Ramp(32, 48);
  constexpr uint32_t kFiles = 8;  // strips of 4 rows: 12 strips
  std::vector<fs::path> good, bad;
  for (uint32_t k = 0; k < kFiles; ++k) {
    const fs::path tif = dir / ("good" + std::to_string(k) + ".tif");
    test::WriteTiff(tif, 32, 48, 1, 32, SAMPLEFORMAT_IEEEFP, depth.data.data(),
                    {COMPRESSION_ADOBE_DEFLATE, PREDICTOR_NONE, 0, 4});
    good.push_back(tif);
    good.push_back(dir / ("good" + std::to_string(k) + ".exr"));
    test::WriteFloatDepth(good.back(), depth);
    bad.push_back(dir / ("bad" + std::to_string(k) + ".tif"));
    BreakZlibStrip(tif, k, bad.back());
  }
  std::vector<std::string> failures[4];
  testing::internal::CaptureStderr();
  {
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&, t] {
        for (int round = 0; round < 10; ++round)
          for (uint32_t i = 0; i < kFiles; ++i) {
            const uint32_t k = (i + uint32_t(t) * 3) % kFiles;
            const Status s = ReadDepthImage(bad[k].string(), 1000.0).status();
            const std::string expected =
                bad[k].string() + ": TIFF strip " + std::to_string(k) + " of 12 does not decode";
            if (s.ok() || s.message().rfind(expected, 0) != 0 ||
                !Contains(s.message(), "(libtiff: "))
              failures[t].push_back(bad[k].string() + " -> " + s.message());
            for (const fs::path& g : {good[2 * k], good[2 * k + 1]}) {
              auto read = ReadDepthImage(g.string(), 1000.0);
              if (!read.ok() || read->data != depth.data)
                failures[t].push_back(g.string() + " misread: " + read.status().message());
            }
          }
      });
    for (std::thread& thread : threads) thread.join();
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  for (const auto& f : failures) {
    EXPECT_TRUE(f.empty()) << f.size() << " failures, the first: " << f.front();
  }
}

// ---------------------------------------------------------------------------------------------
// Datasets listing float depth files.

// A TUM-style folder: depth.txt naming depth/<k>.<ext>, camera.txt, groundtruth.txt; no colour.
fs::path WriteTumFolder(const fs::path& root, const std::vector<DepthImage>& frames,
                        const std::string& ext) {
  std::string list = "# timestamp filename\n", gt = "# timestamp tx ty tz qx qy qz qw\n";
  for (size_t k = 0; k < frames.size(); ++k) {
    const std::string name = "depth/" + std::to_string(k) + ext;
    test::WriteFloatDepth(root / name, frames[k]);
    const std::string t = std::to_string(1.0 + 0.1 * double(k));
    list += t + " " + name + "\n";
    gt += t + " 0 0 " + std::to_string(0.01 * double(k)) + " 0 0 0 1\n";
  }
  WriteText(root / "depth.txt", list);
  WriteText(root / "groundtruth.txt", gt);
  WriteText(root / "camera.txt", "40 40 15.5 11.5\n");
  return root;
}

TEST(DepthImageDatasets, TumListOfFloatDepthReadsMetres) {
  for (const char* ext : {".tif", ".exr"}) {
    SCOPED_TRACE(ext);
    test::TempDir dir("depth_image_tum");
    const std::vector<DepthImage> frames = {WithInvalidValues(32, 24), Ramp(32, 24)};
    WriteTumFolder(dir.path(), frames, ext);
    auto ds = OpenDataset(dir.path().string());
    ASSERT_TRUE(ds.ok()) << ds.status().message();
    const DatasetInfo& info = (*ds)->info();
    EXPECT_EQ(info.format, DatasetFormat::kTum);
    EXPECT_EQ(info.num_frames, 2u);
    EXPECT_EQ(info.camera.width, 32);
    EXPECT_EQ(info.camera.height, 24);
    EXPECT_TRUE(info.depth_metres);
    EXPECT_EQ(info.depth_encoding,
              std::string("32-bit float ") + (std::string(ext) == ".exr" ? "EXR" : "TIFF"));
    EXPECT_EQ(info.depth_scale, 5000.0);  // TUM's, for 16-bit files; these ignore it
    for (size_t k = 0; k < frames.size(); ++k) {
      auto frame = (*ds)->Load(k);
      ASSERT_TRUE(frame.ok()) << frame.status().message();
      ExpectSameMetres(frame->depth, frames[k]);
      EXPECT_TRUE(frame->T_W_C.has_value());
    }
    // --depth-scale cannot apply: said so.
    DatasetOptions scaled;
    scaled.depth_scale = 1000.0;
    auto with_scale = OpenDataset(dir.path().string(), scaled);
    ASSERT_TRUE(with_scale.ok()) << with_scale.status().message();
    bool warned = false;
    for (const std::string& w : (*with_scale)->info().warnings)
      warned = warned || Contains(w, "the scale applies only to 16-bit depth images");
    EXPECT_TRUE(warned);
    auto same = (*with_scale)->Load(1);
    ASSERT_TRUE(same.ok()) << same.status().message();
    ExpectSameMetres(same->depth, frames[1]);
  }
}

TEST(DepthImageDatasets, SequencesDoNotMixUnitsOrSizes) {
  test::TempDir dir("depth_image_mix");
  const fs::path root = WriteTumFolder(dir.path(), {Ramp(32, 24), Ramp(32, 24)}, ".tif");
  // A 16-bit TIFF where float metres are expected: units would be read as metres.
  test::WriteDepthTiff16(root / "depth/1.tif", 32, 24, std::vector<uint16_t>(32 * 24, 1500));
  auto ds = OpenDataset(root.string());
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  ASSERT_TRUE((*ds)->Load(0).ok());
  ExpectRefused((*ds)->Load(1).status(), StatusCode::kCorruptData, root / "depth/1.tif",
                "holds 16-bit TIFF depth (units of 1 / depth scale) but the sequence's first "
                "frame holds 32-bit float TIFF depth (metres)");
  // Another size.
  test::WriteFloatDepth(root / "depth/1.tif", Ramp(30, 24));
  ExpectRefused((*ds)->Load(1).status(), StatusCode::kCorruptData, root / "depth/1.tif",
                "depth is 30x24 but the sequence is 32x24");
  // A PNG listed among TIFFs is refused when the dataset is opened.
  std::vector<uint16_t> units(32 * 24, 1500);
  ASSERT_TRUE(WritePngRaw((root / "depth/2.png").string(), 32, 24, 1, 16, units.data()).ok());
  WriteText(root / "depth.txt", "1.0 depth/0.tif\n1.1 depth/2.png\n");
  ExpectRefused(OpenDataset(root.string()).status(), StatusCode::kUnsupported, root / "depth/2.png",
                "PNG depth in a sequence of TIFF depth images");
  // The first file's kind is checked when the dataset is opened.
  const std::vector<uint8_t> gray8(32 * 24, 3);
  test::WriteTiff(root / "depth/0.tif", 32, 24, 1, 8, SAMPLEFORMAT_UINT, gray8.data());
  WriteText(root / "depth.txt", "1.0 depth/0.tif\n");
  ExpectRefused(OpenDataset(root.string()).status(), StatusCode::kUnsupported, root / "depth/0.tif",
                "8-bit unsigned integer");
}

TEST(DepthImageDatasets, FrameFoldersAndRedwoodFindFloatDepth) {
  test::TempDir dir("depth_image_folders");
  const std::vector<DepthImage> frames = {Ramp(20, 10), WithInvalidValues(20, 10)};
  // 7-Scenes: frame-XXXXXX.depth.exr beside its pose.
  const fs::path seven = dir / "seven";
  for (size_t k = 0; k < frames.size(); ++k) {
    const std::string stem = "frame-00000" + std::to_string(k);
    test::WriteFloatDepth(seven / (stem + ".depth.exr"), frames[k]);
    WriteText(seven / (stem + ".pose.txt"), "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  }
  WriteText(seven / "camera-intrinsics.txt", "30 0 9.5\n0 30 4.5\n0 0 1\n");
  auto s = OpenDataset(seven.string());
  ASSERT_TRUE(s.ok()) << s.status().message();
  EXPECT_EQ((*s)->info().format, DatasetFormat::kSevenScenes);
  EXPECT_EQ((*s)->info().depth_encoding, "32-bit float EXR");
  ASSERT_EQ((*s)->info().num_frames, 2u);
  for (size_t k = 0; k < frames.size(); ++k) {
    auto frame = (*s)->Load(k);
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    ExpectSameMetres(frame->depth, frames[k]);
    EXPECT_TRUE(frame->T_W_C.has_value()) << "the pose beside frame " << k;
  }
  // Redwood: depth/NNNNN.tiff.
  const fs::path redwood = dir / "redwood";
  for (size_t k = 0; k < frames.size(); ++k)
    test::WriteFloatDepth(redwood / "depth" / ("0000" + std::to_string(k) + ".tiff"), frames[k]);
  auto r = OpenDataset(redwood.string());
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ((*r)->info().format, DatasetFormat::kRedwood);
  EXPECT_TRUE((*r)->info().depth_metres);
  for (size_t k = 0; k < frames.size(); ++k) {
    auto frame = (*r)->Load(k);
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    ExpectSameMetres(frame->depth, frames[k]);
  }
}

}  // namespace
}  // namespace voxplan
