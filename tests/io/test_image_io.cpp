#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "io/image_io.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

fs::path Rgbd() { return test::SharedDataDir() / "rgbd"; }

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void WriteBytes(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

// The status failed and its message names `what` (a file, usually).
void ExpectErrorNames(const Status& s, const std::string& what) {
  ASSERT_FALSE(s.ok()) << "expected an error naming " << what;
  EXPECT_NE(s.message().find(what), std::string::npos) << s.message();
}

float Median(std::vector<float> v) {
  v.erase(std::remove(v.begin(), v.end(), 0.f), v.end());
  if (v.empty()) return 0.f;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

TEST(ImageIo, ReadsRealDepthPng) {
  const std::string path = (Rgbd() / "iclnuim_office_traj0/depth/10.png").string();
  testing::internal::CaptureStderr();
  auto depth = ReadDepthPng(path, 5000.0);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  ASSERT_TRUE(depth.ok()) << depth.status().message();
  EXPECT_EQ(depth->width, 640);
  EXPECT_EQ(depth->height, 480);
  const float median = Median({depth->data.begin(), depth->data.end()});
  EXPECT_GT(median, 0.5f);
  EXPECT_LT(median, 6.f);
  auto header = ReadPngHeader(path);
  ASSERT_TRUE(header.ok());
  EXPECT_EQ(header->bit_depth, 16);
  EXPECT_EQ(header->channels, 1);
}

TEST(ImageIo, DepthScaleConvertsUnitsToMetres) {
  test::TempDir dir("image_io");
  std::vector<uint16_t> units = {0, 1, 5000, 65535, 1000, 2500};
  const std::string path = (dir / "d.png").string();
  ASSERT_TRUE(WritePngRaw(path, 3, 2, 1, 16, units.data()).ok());
  auto depth = ReadDepthPng(path, 5000.0);
  ASSERT_TRUE(depth.ok()) << depth.status().message();
  ASSERT_EQ(depth->data.size(), 6u);
  EXPECT_EQ(depth->at(0, 0), 0.f);  // 0 stays invalid
  EXPECT_FLOAT_EQ(depth->at(1, 0), 1.f / 5000.f);
  EXPECT_FLOAT_EQ(depth->at(2, 0), 1.f);
  EXPECT_FLOAT_EQ(depth->at(0, 1), 65535.f / 5000.f);
  EXPECT_FLOAT_EQ(depth->at(2, 1), 0.5f);
  ExpectErrorNames(ReadDepthPng(path, 0.0).status(), path);
}

TEST(ImageIo, DepthRoundTrip) {
  test::TempDir dir("image_io");
  DepthImage depth(7, 5);
  for (size_t i = 0; i < depth.data.size(); ++i) depth.data[i] = 0.25f + 0.1f * float(i);
  depth.at(0, 0) = 0.f;
  depth.at(1, 0) = std::numeric_limits<float>::quiet_NaN();
  depth.at(2, 0) = -1.f;
  depth.at(3, 0) = std::numeric_limits<float>::infinity();
  const std::string path = (dir / "depth.png").string();
  ASSERT_TRUE(WriteDepthPng16(path, depth, 1000.0).ok());
  auto back = ReadDepthPng(path, 1000.0);
  ASSERT_TRUE(back.ok()) << back.status().message();
  ASSERT_EQ(back->width, 7);
  ASSERT_EQ(back->height, 5);
  for (int u = 0; u < 4; ++u) EXPECT_EQ(back->at(u, 0), 0.f) << u;  // invalid -> 0
  for (size_t i = 4; i < depth.data.size(); ++i)
    EXPECT_NEAR(back->data[i], depth.data[i], 0.5e-3 + 1e-6) << i;
  // Only the final file is left: the temporary was renamed.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(ImageIo, DepthWriterRefusesOverflowAndBadFolder) {
  test::TempDir dir("image_io");
  DepthImage depth(2, 2, 1.f);
  depth.at(1, 1) = 20.f;  // 100000 units at scale 5000
  const std::string path = (dir / "depth.png").string();
  ExpectErrorNames(WriteDepthPng16(path, depth, 5000.0), path);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 0);
  const std::string nowhere = (dir / "no/such/folder/d.png").string();
  ExpectErrorNames(WriteDepthPng16(nowhere, DepthImage(2, 2, 1.f), 1000.0), nowhere);
  ExpectErrorNames(WriteColorPng(path, ColorImage()), path);
}

TEST(ImageIo, ColorRoundTripAndFormats) {
  test::TempDir dir("image_io");
  ColorImage color(4, 3);
  for (size_t i = 0; i < color.data.size(); ++i)
    color.data[i] = PackRgb(uint8_t(10 * i), uint8_t(200 - i), uint8_t(7 * i + 1));
  const std::string path = (dir / "c.png").string();
  ASSERT_TRUE(WriteColorPng(path, color).ok());
  auto back = ReadColorImage(path);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->data, color.data);

  // 8-bit gray is replicated into R, G and B.
  const std::vector<uint8_t> gray = {0, 50, 100, 255};
  ASSERT_TRUE(WritePngRaw((dir / "g.png").string(), 2, 2, 1, 8, gray.data()).ok());
  auto g = ReadColorImage((dir / "g.png").string());
  ASSERT_TRUE(g.ok()) << g.status().message();
  EXPECT_EQ(g->at(1, 0), PackRgb(50, 50, 50));

  // RGBA: alpha dropped.
  const std::vector<uint8_t> rgba = {1, 2, 3, 4, 5, 6, 7, 8};
  ASSERT_TRUE(WritePngRaw((dir / "a.png").string(), 2, 1, 4, 8, rgba.data()).ok());
  auto a = ReadColorImage((dir / "a.png").string());
  ASSERT_TRUE(a.ok()) << a.status().message();
  EXPECT_EQ(a->at(1, 0), PackRgb(5, 6, 7));

  // 16-bit RGB is down-converted to 8 bits.
  const std::vector<uint16_t> rgb16 = {0xABCD, 0x1234, 0xFFFF};
  ASSERT_TRUE(WritePngRaw((dir / "c16.png").string(), 1, 1, 3, 16, rgb16.data()).ok());
  auto c16 = ReadColorImage((dir / "c16.png").string());
  ASSERT_TRUE(c16.ok()) << c16.status().message();
  EXPECT_NEAR(Red(c16->data[0]), 0xAB, 1);
  EXPECT_NEAR(Green(c16->data[0]), 0x12, 1);
  EXPECT_EQ(Blue(c16->data[0]), 0xFF);
}

TEST(ImageIo, ReadsRealJpegAndPng) {
  for (const char* rel :
       {"iclnuim_office_traj0/rgb/1.jpg", "3dmatch_sun3d5/seq-01/frame-000000.color.png",
        "7scenes_redkitchen/frame-000000.color.jpg"}) {
    testing::internal::CaptureStderr();
    auto color = ReadColorImage((Rgbd() / rel).string());
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    ASSERT_TRUE(color.ok()) << color.status().message();
    EXPECT_EQ(color->width, 640) << rel;
    EXPECT_EQ(color->height, 480) << rel;
    // A real photo: many distinct colours and no X byte set.
    std::vector<uint32_t> sorted(color->data.begin(), color->data.end());
    std::sort(sorted.begin(), sorted.end());
    EXPECT_GT(std::unique(sorted.begin(), sorted.end()) - sorted.begin(), 1000) << rel;
    EXPECT_EQ(sorted.back() >> 24, 0u);
  }
}

TEST(ImageIo, RefusesWrongDepthKinds) {
  test::TempDir dir("image_io");
  const std::vector<uint8_t> gray8(16, 7);
  const std::string p8 = (dir / "gray8.png").string();
  ASSERT_TRUE(WritePngRaw(p8, 4, 4, 1, 8, gray8.data()).ok());
  auto r8 = ReadDepthPng(p8, 1000.0);
  ExpectErrorNames(r8.status(), p8);
  EXPECT_NE(r8.status().message().find("8-bit"), std::string::npos) << r8.status().message();

  const std::vector<uint16_t> rgb16(4 * 4 * 3, 1000);
  const std::string p3 = (dir / "rgb16.png").string();
  ASSERT_TRUE(WritePngRaw(p3, 4, 4, 3, 16, rgb16.data()).ok());
  auto r3 = ReadDepthPng(p3, 1000.0);
  ExpectErrorNames(r3.status(), p3);
  EXPECT_NE(r3.status().message().find("RGB"), std::string::npos) << r3.status().message();

  // A colour image passed as depth.
  const std::string color = (Rgbd() / "3dmatch_sun3d5/seq-01/frame-000000.color.png").string();
  ExpectErrorNames(ReadDepthPng(color, 1000.0).status(), color);
  const std::string jpeg = (Rgbd() / "iclnuim_office_traj0/rgb/1.jpg").string();
  ExpectErrorNames(ReadDepthPng(jpeg, 1000.0).status(), jpeg);
}

TEST(ImageIo, RefusesAbsurdSizes) {
  test::TempDir dir("image_io");
  const std::vector<uint8_t> row(20000, 1);  // wider than any camera
  const std::string path = (dir / "wide.png").string();
  ASSERT_TRUE(WritePngRaw(path, 20000, 1, 1, 8, row.data()).ok());
  ExpectErrorNames(ReadColorImage(path).status(), path);
}

TEST(ImageIo, RefusesMissingCorruptAndTruncatedFiles) {
  test::TempDir dir("image_io");
  const std::string missing = (dir / "missing.png").string();
  auto m = ReadDepthPng(missing, 1000.0);
  ExpectErrorNames(m.status(), missing);
  EXPECT_EQ(m.status().code(), StatusCode::kNotFound);
  ExpectErrorNames(ReadColorImage(missing).status(), missing);
  ExpectErrorNames(ReadPngHeader(missing).status(), missing);

  const std::string empty = (dir / "empty.png").string();
  WriteBytes(empty, "");
  ExpectErrorNames(ReadDepthPng(empty, 1000.0).status(), empty);
  ExpectErrorNames(ReadColorImage(empty).status(), empty);

  const std::string garbage = (dir / "garbage.png").string();
  WriteBytes(garbage, "this is not an image at all, just text");
  ExpectErrorNames(ReadDepthPng(garbage, 1000.0).status(), garbage);
  ExpectErrorNames(ReadColorImage(garbage).status(), garbage);

  const std::string depth_bytes = ReadBytes(Rgbd() / "iclnuim_office_traj0/depth/1.png");
  const std::string jpeg_bytes = ReadBytes(Rgbd() / "iclnuim_office_traj0/rgb/1.jpg");
  ASSERT_GT(depth_bytes.size(), 1000u);
  ASSERT_GT(jpeg_bytes.size(), 1000u);

  testing::internal::CaptureStderr();
  // Truncated at several points: inside the header, the first IDAT, the middle, before IEND.
  for (size_t cut : {size_t(20), size_t(60), depth_bytes.size() / 2, depth_bytes.size() - 6}) {
    const std::string path = (dir / ("trunc" + std::to_string(cut) + ".png")).string();
    WriteBytes(path, depth_bytes.substr(0, cut));
    ExpectErrorNames(ReadDepthPng(path, 5000.0).status(), path);
  }
  // Flipped bytes inside the compressed data: CRC (or zlib) error.
  std::string flipped = depth_bytes;
  for (size_t i = flipped.size() / 2; i < flipped.size() / 2 + 16; ++i)
    flipped[i] = char(~flipped[i]);
  const std::string corrupt = (dir / "corrupt.png").string();
  WriteBytes(corrupt, flipped);
  ExpectErrorNames(ReadDepthPng(corrupt, 5000.0).status(), corrupt);

  for (size_t cut : {size_t(10), size_t(400), jpeg_bytes.size() / 2}) {
    const std::string path = (dir / ("trunc" + std::to_string(cut) + ".jpg")).string();
    WriteBytes(path, jpeg_bytes.substr(0, cut));
    ExpectErrorNames(ReadColorImage(path).status(), path);
  }
  // Neither libpng nor libjpeg may print.
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace voxplan
