// The depth PNG fast path (io/png_fast.h) against the PNG specification and libpng: the SSE2
// unfilter against the scalar reference, hand-built PNGs (every filter type, split IDATs,
// ancillary chunks) decoded to the samples they were built from, every irregular file declined
// and left to libpng (whose results and messages ReadDepthPng keeps), the shared datasets'
// depth frames decoded as libpng decodes them; and JPEG colour as libjpeg's packed RGB.
#include <gtest/gtest.h>
#include <jpeglib.h>
#include <png.h>
#include <zlib.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "io/image_io.h"
#include "io/png_fast.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

fs::path Rgbd() { return test::SharedDataDir() / "rgbd"; }

Bytes ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void WriteFile(const fs::path& p, const Bytes& bytes) {
  std::ofstream out(p, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// ---------------------------------------------------------------------------------------------
// A PNG writer with every choice in the test's hands.

void Put32(Bytes& b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(uint8_t(v >> s));
}
void Chunk(Bytes& png, const char* type, const Bytes& data, bool good_crc = true) {
  Put32(png, uint32_t(data.size()));
  const size_t start = png.size();
  png.insert(png.end(), type, type + 4);
  png.insert(png.end(), data.begin(), data.end());
  uLong crc = crc32(0, png.data() + start, uInt(png.size() - start));
  if (!good_crc) crc ^= 1;
  Put32(png, uint32_t(crc));
}

uint8_t PaethPredictor(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return uint8_t(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

// Rows of big-endian 16-bit samples filtered with the given type per row (forward filters).
Bytes FilterRows(const Bytes& image, size_t width, size_t height, const std::vector<int>& types) {
  const size_t n = 2 * width;
  Bytes out;
  for (size_t y = 0; y < height; ++y) {
    const uint8_t* cur = image.data() + y * n;
    const uint8_t* prev = y ? cur - n : nullptr;
    out.push_back(uint8_t(types[y]));
    for (size_t i = 0; i < n; ++i) {
      const int a = i >= 2 ? cur[i - 2] : 0, b = prev ? prev[i] : 0,
                c = (prev && i >= 2) ? prev[i - 2] : 0;
      const int pred = types[y] == 1   ? a
                       : types[y] == 2 ? b
                       : types[y] == 3 ? (a + b) / 2
                       : types[y] == 4 ? PaethPredictor(a, b, c)
                                       : 0;
      out.push_back(uint8_t(cur[i] - pred));
    }
  }
  return out;
}

struct PngSpec {
  size_t width = 37, height = 29;
  int bit_depth = 16, color_type = 0, interlace = 0;
  size_t idat_pieces = 1;            // the zlib stream split over this many IDAT chunks
  bool text_before = false;          // an ancillary tEXt chunk before the IDATs
  bool text_after = false;           // and one between the IDATs and IEND
  bool plte = false;                 // a PLTE chunk (critical) before the IDATs
  bool bad_idat_crc = false;         // the last IDAT's CRC off by one bit
  bool bad_text_crc = false;         // the tEXt chunk's CRC off by one bit
  bool no_iend = false;              // the file ends after the IDATs
  bool trailing_zlib_bytes = false;  // bytes after the zlib stream, inside the IDAT
  int drop_rows = 0;                 // the stream holds this many rows fewer
  int window_bits = 15;              // zlib window (15: 32 KiB)
  int bad_filter_row = -1;           // this row gets filter type 5
};

// The image's big-endian samples and the PNG built from them.
struct BuiltPng {
  Bytes samples, file;
};

BuiltPng Build(const PngSpec& s, uint32_t seed) {
  std::mt19937 rng(seed);
  BuiltPng out;
  out.samples.resize(2 * s.width * s.height);
  // Smooth depth with noise and holes, so all predictors matter.
  for (size_t y = 0; y < s.height; ++y)
    for (size_t x = 0; x < s.width; ++x) {
      uint32_t v = uint32_t(1500 + 7 * x + 11 * y + rng() % 40);
      if (rng() % 17 == 0) v = 0;
      if (rng() % 23 == 0) v = rng() & 0xffff;
      out.samples[2 * (y * s.width + x)] = uint8_t(v >> 8);
      out.samples[2 * (y * s.width + x) + 1] = uint8_t(v);
    }
  std::vector<int> types(s.height);
  for (size_t y = 0; y < s.height; ++y) types[y] = int(rng() % 5);
  Bytes raw = FilterRows(out.samples, s.width, s.height, types);
  if (s.bad_filter_row >= 0) raw[size_t(s.bad_filter_row) * (2 * s.width + 1)] = 5;
  raw.resize(raw.size() - size_t(s.drop_rows) * (2 * s.width + 1));

  z_stream z{};
  deflateInit2(&z, 6, Z_DEFLATED, s.window_bits, 8, Z_DEFAULT_STRATEGY);
  Bytes stream(deflateBound(&z, uLong(raw.size())) + 16);
  z.next_in = raw.data();
  z.avail_in = uInt(raw.size());
  z.next_out = stream.data();
  z.avail_out = uInt(stream.size());
  deflate(&z, Z_FINISH);
  stream.resize(z.total_out);
  deflateEnd(&z);
  if (s.trailing_zlib_bytes) stream.insert(stream.end(), {1, 2, 3});

  Bytes& png = out.file;
  png = {137, 80, 78, 71, 13, 10, 26, 10};
  Bytes ihdr;
  Put32(ihdr, uint32_t(s.width));
  Put32(ihdr, uint32_t(s.height));
  ihdr.insert(ihdr.end(),
              {uint8_t(s.bit_depth), uint8_t(s.color_type), 0, 0, uint8_t(s.interlace)});
  Chunk(png, "IHDR", ihdr);
  const Bytes text = {'C', 'o', 'm', 'm', 'e', 'n', 't', 0, 'h', 'i'};
  if (s.text_before) Chunk(png, "tEXt", text, !s.bad_text_crc);
  if (s.plte) Chunk(png, "PLTE", {0, 0, 0, 255, 255, 255});
  const size_t piece = (stream.size() + s.idat_pieces - 1) / s.idat_pieces;
  for (size_t p = 0; p < stream.size(); p += piece) {
    const size_t end = std::min(stream.size(), p + piece);
    Chunk(png, "IDAT", Bytes(stream.begin() + long(p), stream.begin() + long(end)),
          !(s.bad_idat_crc && end == stream.size()));
  }
  if (s.text_after) Chunk(png, "tEXt", text);
  if (!s.no_iend) Chunk(png, "IEND", {});
  return out;
}

std::vector<float> Metres(const Bytes& samples, double scale) {
  std::vector<float> m(samples.size() / 2);
  for (size_t i = 0; i < m.size(); ++i)
    m[i] = float(double((unsigned(samples[2 * i]) << 8) | samples[2 * i + 1]) * (1.0 / scale));
  return m;
}

bool Fast(const Bytes& file, DepthImage& depth, double scale = 1000.0) {
  return png_fast::DecodeDepthPng(file.data(), file.size(), 16384, scale, depth);
}

// libpng's own decode of a 16-bit gray PNG, in metres as ReadDepthPng converts (the oracle for
// real files). Empty when libpng refuses the file.
void PngError(png_structp png, png_const_charp) { std::longjmp(png_jmpbuf(png), 1); }
void PngWarning(png_structp, png_const_charp) {}
bool LibpngRows(FILE* f, Bytes& bytes, png_uint_32& w, png_uint_32& h) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, PngError, PngWarning);
  png_infop info = png_create_info_struct(png);
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_init_io(png, f);
  png_read_info(png, info);
  w = png_get_image_width(png, info);
  h = png_get_image_height(png, info);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const size_t row_bytes = png_get_rowbytes(png, info);
  bytes.assign(row_bytes * h, 0);
  rows.resize(h);
  for (png_uint_32 y = 0; y < h; ++y) rows[y] = bytes.data() + y * row_bytes;
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}
std::vector<float> LibpngMetres(const fs::path& path, double scale) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return {};
  Bytes bytes;
  png_uint_32 w = 0, h = 0;
  const bool ok = LibpngRows(f, bytes, w, h);
  std::fclose(f);
  return ok ? Metres(bytes, scale) : std::vector<float>{};
}

// ---------------------------------------------------------------------------------------------

TEST(PngFast, Sse2UnfilterMatchesTheScalarReference) {
  std::mt19937 rng(7);
  for (int t = 0; t < 2000; ++t) {
    const size_t w = 1 + rng() % 90, h = 1 + rng() % 37;
    Bytes filtered(h * (2 * w + 1));
    for (uint8_t& b : filtered) b = uint8_t(rng());
    // Mostly one type per image now and then, so groups of eight rows of one type occur too.
    const int only = int(rng() % 7);
    for (size_t y = 0; y < h; ++y)
      filtered[y * (2 * w + 1)] = uint8_t(only < 5 ? only : int(rng() % 5));
    Bytes a(2 * w * h), b(2 * w * h);
    ASSERT_TRUE(png_fast::UnfilterScalar(filtered.data(), 2 * w, h, 2, a.data()));
    ASSERT_TRUE(png_fast::UnfilterGray16(filtered.data(), w, h, b.data()));
    ASSERT_EQ(a, b) << w << " x " << h;
  }
  Bytes filtered(9 * 11, 0), out(9 * 10);
  filtered[3 * 11] = 5;  // filter type 5 in row 3 of 9
  EXPECT_FALSE(png_fast::UnfilterGray16(filtered.data(), 5, 9, out.data()));
  EXPECT_FALSE(png_fast::UnfilterScalar(filtered.data(), 10, 9, 2, out.data()));
}

TEST(PngFast, ConvertsToMetresAsTheScalarLoop) {
  Bytes samples(2 * 1001);
  std::mt19937 rng(3);
  for (uint8_t& b : samples) b = uint8_t(rng());
  for (double scale : {1000.0, 5000.0, 6553.5, 1.0}) {
    std::vector<float> out(1001);
    png_fast::BigEndianToMetres(samples.data(), out.size(), scale, out.data());
    const std::vector<float> want = Metres(samples, scale);
    EXPECT_EQ(std::memcmp(out.data(), want.data(), out.size() * sizeof(float)), 0) << scale;
  }
}

TEST(PngFast, DecodesWellFormedFilesToTheirSamples) {
  const std::vector<PngSpec> specs = [] {
    std::vector<PngSpec> v(6);
    v[1].idat_pieces = 5;
    v[2].text_before = v[2].text_after = true;
    v[3].width = 1;
    v[3].height = 1;
    v[4].width = 640;
    v[4].height = 19;  // groups of 8 rows and a tail
    v[5].width = 8;
    v[5].height = 64;
    return v;
  }();
  uint32_t seed = 1;
  for (const PngSpec& s : specs) {
    const BuiltPng png = Build(s, seed++);
    DepthImage depth;
    ASSERT_TRUE(Fast(png.file, depth, 5000.0)) << s.width << " x " << s.height;
    EXPECT_EQ(depth.width, int(s.width));
    EXPECT_EQ(depth.height, int(s.height));
    const std::vector<float> want = Metres(png.samples, 5000.0);
    ASSERT_EQ(depth.data.size(), want.size());
    EXPECT_EQ(std::memcmp(depth.data.data(), want.data(), want.size() * sizeof(float)), 0);
  }
}

TEST(PngFast, DeclinesEveryIrregularFileAndReadDepthPngGivesLibpngsAnswer) {
  const test::TempDir dir("voxplan-png-fast");
  struct Case {
    const char* name;
    PngSpec spec;
    bool libpng_reads;  // libpng's own decode succeeds (warnings ignored, as ReadDepthPng does)
  };
  std::vector<Case> cases;
  auto add = [&](const char* name, bool libpng_reads, auto tweak) {
    PngSpec s;
    tweak(s);
    cases.push_back({name, s, libpng_reads});
  };
  add("bad_idat_crc", false, [](PngSpec& s) { s.bad_idat_crc = true; });
  add("bad_text_crc", true, [](PngSpec& s) { s.text_before = s.bad_text_crc = true; });
  add("plte", true, [](PngSpec& s) { s.plte = true; });
  add("no_iend", false, [](PngSpec& s) { s.no_iend = true; });
  add("trailing_zlib_bytes", true, [](PngSpec& s) { s.trailing_zlib_bytes = true; });
  add("short_stream", false, [](PngSpec& s) { s.drop_rows = 3; });
  add("small_window", true, [](PngSpec& s) { s.window_bits = 9; });
  add("filter_type_5", false, [](PngSpec& s) { s.bad_filter_row = 4; });
  add("interlaced_header", false, [](PngSpec& s) { s.interlace = 1; });
  uint32_t seed = 100;
  for (const Case& c : cases) {
    const BuiltPng png = Build(c.spec, seed++);
    DepthImage depth;
    EXPECT_FALSE(Fast(png.file, depth)) << c.name;
    EXPECT_TRUE(depth.empty()) << c.name;
    const fs::path path = dir / (std::string(c.name) + ".png");
    WriteFile(path, png.file);
    const std::vector<float> libpng = LibpngMetres(path, 1000.0);
    EXPECT_EQ(!libpng.empty(), c.libpng_reads) << c.name;
    // Whatever libpng makes of it, ReadDepthPng makes of it.
    Result<DepthImage> read = ReadDepthPng(path.string(), 1000.0);
    if (!libpng.empty()) {
      ASSERT_TRUE(read.ok()) << c.name << ": " << read.status().message();
      ASSERT_EQ(read->data.size(), libpng.size()) << c.name;
      EXPECT_EQ(std::memcmp(read->data.data(), libpng.data(), libpng.size() * sizeof(float)), 0)
          << c.name;
    } else {
      ASSERT_FALSE(read.ok()) << c.name;
      EXPECT_NE(read.status().message().find(path.string()), std::string::npos)
          << c.name << ": " << read.status().message();
    }
  }
  // Not 16-bit gray: declined, and refused by ReadDepthPng as before.
  PngSpec eight;
  eight.bit_depth = 8;
  const BuiltPng png8 = Build(eight, 50);
  DepthImage unused;
  EXPECT_FALSE(Fast(png8.file, unused));
  WriteFile(dir / "eight.png", png8.file);
  Result<DepthImage> read8 = ReadDepthPng((dir / "eight.png").string(), 1000.0);
  ASSERT_FALSE(read8.ok());
  EXPECT_NE(read8.status().message().find("16-bit single-channel"), std::string::npos)
      << read8.status().message();
  // Truncated anywhere: declined, and libpng's refusal names the file.
  const BuiltPng png = Build(PngSpec{}, 9);
  for (size_t cut : {size_t(8), size_t(40), png.file.size() / 2, png.file.size() - 1}) {
    Bytes part(png.file.begin(), png.file.begin() + long(cut));
    DepthImage depth;
    EXPECT_FALSE(Fast(part, depth)) << cut;
    const fs::path path = dir / ("cut" + std::to_string(cut) + ".png");
    WriteFile(path, part);
    Result<DepthImage> read = ReadDepthPng(path.string(), 1000.0);
    ASSERT_FALSE(read.ok()) << cut;
    EXPECT_NE(read.status().message().find(path.string()), std::string::npos);
  }
}

TEST(PngFast, SharedDepthFramesDecodeAsLibpngDecodesThem) {
  std::vector<std::pair<fs::path, double>> files;
  for (int i = 0; i < 400; i += 23) {
    char name[64];
    std::snprintf(name, sizeof(name), "frame-%06d.depth.png", i);
    files.push_back({Rgbd() / "7scenes_redkitchen" / name, 1000.0});
  }
  for (int id = 1; id <= 200; id += 19)
    files.push_back(
        {Rgbd() / "iclnuim_office_traj0" / "depth" / (std::to_string(id) + ".png"), 5000.0});
  for (const char* other :
       {"replica_office0/office0/results/depth000000.png",
        "3dmatch_sun3d5/seq-01/frame-000000.depth.png", "open3d_livingroom5/depth/00000.png",
        "open3d_livingroom5/other_formats/TUM_depth.png"})
    files.push_back({Rgbd() / other, 1000.0});
  size_t taken = 0;
  for (const auto& [path, scale] : files) {
    if (!fs::exists(path)) continue;  // a layout this test does not know
    const std::vector<float> want = LibpngMetres(path, scale);
    ASSERT_FALSE(want.empty()) << path;
    Result<DepthImage> read = ReadDepthPng(path.string(), scale);
    ASSERT_TRUE(read.ok()) << read.status().message();
    ASSERT_EQ(read->data.size(), want.size()) << path;
    EXPECT_EQ(std::memcmp(read->data.data(), want.data(), want.size() * sizeof(float)), 0) << path;
    const Bytes file = ReadFile(path);
    DepthImage fast;
    taken += Fast(file, fast, scale) ? 1 : 0;
  }
  EXPECT_GE(taken, 29u);  // the datasets' depth frames take the fast path
}

// libjpeg's packed RGB of a JPEG, as PackRgb words.
struct JpegError {
  jpeg_error_mgr pub;
  std::jmp_buf jmp;
};
void JpegExit(j_common_ptr cinfo) {
  std::longjmp(reinterpret_cast<JpegError*>(cinfo->err)->jmp, 1);
}
std::vector<uint32_t> LibjpegRgb(const fs::path& path) {
  const Bytes file = ReadFile(path);
  jpeg_decompress_struct cinfo;
  JpegError err;
  cinfo.err = jpeg_std_error(&err.pub);
  err.pub.error_exit = JpegExit;
  std::vector<uint32_t> out;
  Bytes row;
  if (setjmp(err.jmp)) {
    jpeg_destroy_decompress(&cinfo);
    return {};
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, file.data(), file.size());
  jpeg_read_header(&cinfo, TRUE);
  cinfo.out_color_space = JCS_RGB;
  jpeg_start_decompress(&cinfo);
  row.resize(size_t(cinfo.output_width) * 3);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW r = row.data();
    jpeg_read_scanlines(&cinfo, &r, 1);
    for (size_t x = 0; x < cinfo.output_width; ++x)
      out.push_back(PackRgb(row[3 * x], row[3 * x + 1], row[3 * x + 2]));
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return out;
}

TEST(PngFast, JpegColourIsLibjpegsPackedRgb) {
  for (const fs::path& path : {Rgbd() / "7scenes_redkitchen" / "frame-000000.color.jpg",
                               Rgbd() / "7scenes_redkitchen" / "frame-000321.color.jpg",
                               Rgbd() / "iclnuim_office_traj0" / "rgb" / "1.jpg",
                               Rgbd() / "iclnuim_office_traj0" / "rgb" / "150.jpg"}) {
    const std::vector<uint32_t> want = LibjpegRgb(path);
    ASSERT_FALSE(want.empty()) << path;
    Result<ColorImage> color = ReadColorImage(path.string());
    ASSERT_TRUE(color.ok()) << color.status().message();
    ASSERT_EQ(color->data.size(), want.size());
    EXPECT_TRUE(std::equal(want.begin(), want.end(), color->data.begin())) << path;
  }
}

}  // namespace
}  // namespace voxplan
