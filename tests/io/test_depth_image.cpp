// Float depth (io/depth_image.h): 32-bit float TIFF and OpenEXR in metres, 16-bit TIFF in
// units, written by OpenCV here; read back exactly (both are lossless), invalid values to 0,
// every other kind of file refused naming it, nothing printed; and the dataset readers that list
// depth files (TUM-style lists, 7-Scenes frame folders, Redwood depth/) reading them as metres.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
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

TEST(DepthImage, ExrHalfFloatAndALoneRedChannel) {
  test::TempDir dir("depth_image");
  const DepthImage depth = Ramp(16, 9);
  // Half floats: metres rounded to 11 bits, read as OpenCV widens them (exactly).
  const fs::path half = dir / "half.exr";
  test::WriteWithOpenCv(half, test::ToMat(depth),
                        {cv::IMWRITE_EXR_TYPE, cv::IMWRITE_EXR_TYPE_HALF});
  auto h = ReadDepthImage(half.string(), 1000.0);
  ASSERT_TRUE(h.ok()) << h.status().message();
  EXPECT_EQ(ReadDepthHeader(half.string())->Encoding(), "16-bit float EXR");
  const cv::Mat widened = cv::imread(half.string(), cv::IMREAD_UNCHANGED);
  for (size_t i = 5; i < depth.data.size(); ++i) {
    EXPECT_EQ(h->data[i], widened.at<float>(int(i) / 16, int(i) % 16)) << i;
    EXPECT_NEAR(h->data[i], depth.data[i], depth.data[i] * 1e-3f) << i;
  }
  // OpenCV writes its one channel as Y; an uncompressed file renamed to R (as other tools
  // write a lone channel) reads the same; a lone Z (which OpenCV 4.6 reads as zeros) and
  // anything else is refused naming the channel.
  const fs::path plain = dir / "plain.exr";
  test::WriteWithOpenCv(plain, test::ToMat(depth),
                        {cv::IMWRITE_EXR_COMPRESSION, cv::IMWRITE_EXR_COMPRESSION_NO});
  std::string bytes = ReadBytes(plain);
  const size_t chlist = bytes.find(std::string("channels\0chlist\0", 16));
  ASSERT_NE(chlist, std::string::npos);
  const size_t name = chlist + 16 + 4;
  ASSERT_EQ(bytes.substr(name, 2), std::string("Y\0", 2));
  bytes[name] = 'R';
  WriteBytes(dir / "red.exr", bytes);
  auto red = ReadDepthImage((dir / "red.exr").string(), 1000.0);
  ASSERT_TRUE(red.ok()) << red.status().message();
  ExpectSameMetres(*red, depth);
  bytes[name] = 'Z';
  WriteBytes(dir / "z.exr", bytes);
  ExpectRefused(ReadQuietly(dir / "z.exr"), StatusCode::kUnsupported, dir / "z.exr",
                "channel is named 'Z'");
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
}

TEST(DepthImage, RefusesOtherKindsNamingTheFile) {
  test::TempDir dir("depth_image");
  const cv::Mat gray8(6, 5, CV_8UC1, cv::Scalar(7));
  const cv::Mat rgb16(6, 5, CV_16UC3, cv::Scalar(1, 2, 3));
  const cv::Mat rgbf(6, 5, CV_32FC3, cv::Scalar(1, 2, 3));
  const cv::Mat doubles(6, 5, CV_64FC1, cv::Scalar(1.5));
  const cv::Mat ints(6, 5, CV_32SC1, cv::Scalar(1500));
  const cv::Mat signed16(6, 5, CV_16SC1, cv::Scalar(1500));
  struct Case {
    const char* name;
    const cv::Mat* m;
    const char* why;
  } cases[] = {
      {"gray8.tif", &gray8, "found 8-bit unsigned integer samples"},
      {"rgb16.tif", &rgb16, "single-channel, found 3 samples per pixel"},
      {"rgbf.tiff", &rgbf, "single-channel, found 3 samples per pixel"},
      {"doubles.tif", &doubles, "found 64-bit float samples"},
      {"ints.tif", &ints, "found 32-bit signed integer samples"},
      {"signed16.tif", &signed16, "found 16-bit signed integer samples"},
      {"rgbf.exr", &rgbf, "must have one channel, found 3 (B G R)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    test::WriteWithOpenCv(dir / c.name, *c.m);
    ExpectRefused(ReadQuietly(dir / c.name), StatusCode::kUnsupported, dir / c.name, c.why);
  }
  // Not what its name says: a PNG named .tif, a TIFF named .exr, text, an empty file.
  const fs::path png = dir / "really_png.tif";
  const uint16_t units[4] = {1, 2, 3, 4};
  ASSERT_TRUE(WritePngRaw(png.string(), 2, 2, 1, 16, units).ok());
  ExpectRefused(ReadQuietly(png), StatusCode::kCorruptData, png, "not a TIFF file");
  test::WriteFloatDepth(dir / "t.tif", Ramp(4, 3));
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

TEST(DepthImage, TruncatedAndCorruptFilesAreRefusedQuietly) {
  test::TempDir dir("depth_image");
  const DepthImage depth = Ramp(64, 40);
  for (const char* name : {"d.tif", "d.exr"}) {
    SCOPED_TRACE(name);
    test::WriteFloatDepth(dir / name, depth);
    const std::string bytes = ReadBytes(dir / name);
    for (size_t keep : {size_t(6), size_t(40), bytes.size() / 3, bytes.size() - 9}) {
      const fs::path cut = dir / ("cut_" + std::to_string(keep) + "_" + name);
      WriteBytes(cut, bytes.substr(0, keep));
      // EXR: the header's chunk table already shows the file is cut short (so OpenEXR never
      // throws, and OpenCV never prints); TIFF: its strips are found short when decoded.
      const Status s = ReadQuietly(cut, Contains(name, "exr"));
      ASSERT_FALSE(s.ok()) << cut << " (" << keep << " of " << bytes.size() << " bytes) read";
      EXPECT_EQ(s.code(), StatusCode::kCorruptData) << s.message();
      EXPECT_TRUE(Contains(s.message(), cut.string())) << s.message();
    }
  }
  // Compressed EXR data that does not decode: all chunks in the file, so only OpenCV finds it
  // (and prints a line of its own, io/README.md); refused naming the file.
  DepthImage smooth(64, 64);
  for (size_t i = 0; i < smooth.data.size(); ++i) smooth.data[i] = 1.f + 0.001f * float(i % 64 / 8);
  test::WriteFloatDepth(dir / "smooth.exr", smooth);
  std::string zipped = ReadBytes(dir / "smooth.exr");
  for (size_t i = zipped.size() * 2 / 3; i < zipped.size() * 2 / 3 + 20; ++i) zipped[i] ^= 0x5a;
  WriteBytes(dir / "garbled.exr", zipped);
  ASSERT_TRUE(ReadDepthHeader((dir / "garbled.exr").string()).ok());
  testing::internal::CaptureStderr();
  ExpectRefused(ReadDepthImage((dir / "garbled.exr").string(), 1000.0).status(),
                StatusCode::kCorruptData, dir / "garbled.exr", "OpenCV could not decode");
  testing::internal::GetCapturedStderr();
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
  test::WriteWithOpenCv(root / "depth/0.tif", cv::Mat(24, 32, CV_8UC1, cv::Scalar(3)));
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
