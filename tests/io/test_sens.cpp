// ScanNet .sens files (io/sens_file.h) and the dataset over them: a file written by the test's
// writer reads back value for value, the -inf pose frame is kept without a pose and counted,
// colour is registered to depth, and truncated or corrupt files are refused naming the file and
// the frame.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "io/color_registration.h"
#include "io/dataset.h"
#include "io/sens_file.h"
#include "tests/io/dataset_checks.h"
#include "tests/io/sens_fixture.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

bool Contains(const std::string& s, const std::string& what) {
  return s.find(what) != std::string::npos;
}

void ExpectError(const Status& s, std::initializer_list<std::string> what) {
  ASSERT_FALSE(s.ok()) << "expected an error";
  for (const std::string& w : what) EXPECT_TRUE(Contains(s.message(), w)) << s.message();
}

fs::path WriteScan(const test::TempDir& dir, const test::SensScan& scan,
                   const std::string& name = "scene0000_00.sens") {
  const fs::path path = dir / name;
  test::WriteBytes(path, test::EncodeSens(scan.header, scan.frames));
  return path;
}

TEST(Sens, IndexReadsBackTheHeaderAndFrames) {
  const test::TempDir dir("voxplan-sens");
  const test::SensScan scan = test::MakeWallScan();
  const fs::path path = WriteScan(dir, scan);
  Result<SensIndex> index = ReadSensIndex(path.string());
  ASSERT_TRUE(index.ok()) << index.status().message();
  const SensHeader& h = index->header;
  EXPECT_EQ(h.sensor_name, "StructureSensor");
  EXPECT_EQ(h.depth_width, 32);
  EXPECT_EQ(h.color_height, 48);
  EXPECT_FLOAT_EQ(h.depth_intrinsic(0, 2), 15.5f);
  EXPECT_FLOAT_EQ(h.color_intrinsic(0, 0), 48.f);
  EXPECT_FLOAT_EQ(h.depth_shift, 1000.f);
  EXPECT_EQ(h.color_compression, SensColorCompression::kJpeg);
  ASSERT_EQ(index->frames.size(), 4u);
  EXPECT_FLOAT_EQ(index->frames[1].camera_to_world(0, 3), 0.05f);
  EXPECT_EQ(index->frames[3].depth_timestamp_us, 1000000u + 3 * 33333u);
  EXPECT_EQ(index->frames[0].depth_bytes, scan.frames[0].depth_bytes.size());

  Result<DepthImage> depth = ReadSensDepth(*index, 1, 1000.0);
  ASSERT_TRUE(depth.ok()) << depth.status().message();
  EXPECT_EQ(depth->width, 32);
  for (float d : depth->data) EXPECT_FLOAT_EQ(d, 2.0f);  // 2000 mm
  Result<ColorImage> color = ReadSensColor(*index, 1);
  ASSERT_TRUE(color.ok()) << color.status().message();
  EXPECT_EQ(color->width, 64);
  EXPECT_NEAR(Red(color->at(63, 0)), 255, 6);
  EXPECT_NEAR(Green(color->at(0, 47)), 255, 6);
}

TEST(Sens, DatasetSkipsAndCountsTheLostPoseAndRegistersColour) {
  const test::TempDir dir("voxplan-sens-ds");
  const fs::path path = WriteScan(dir, test::MakeWallScan());
  for (const fs::path& open : {path, dir.path()}) {  // the file, or its scene folder
    auto ds = OpenDataset(open.string());
    ASSERT_TRUE(ds.ok()) << ds.status().message();
    const DatasetInfo& info = (*ds)->info();
    EXPECT_EQ(info.format, DatasetFormat::kScanNet);
    EXPECT_EQ(info.num_frames, 4u);
    EXPECT_EQ(info.camera.width, 32);
    EXPECT_FLOAT_EQ(info.camera.fx, 24.f);
    EXPECT_DOUBLE_EQ(info.depth_scale, 1000.0);
    EXPECT_TRUE(info.has_color);
    EXPECT_EQ(info.frames_bad_pose, 1u);
    EXPECT_EQ(info.pose_source, path.string());
    EXPECT_EQ((*ds)->InputFiles(), std::vector<std::string>{path.string()});
    bool warned = false;
    for (const std::string& w : info.warnings)
      warned |= Contains(w, "1 pose is not a rigid transform") && Contains(w, "frame 2");
    EXPECT_TRUE(warned);
  }
  auto ds = OpenDataset(path.string());
  ASSERT_TRUE(ds.ok());
  Result<Frame> lost = (*ds)->Load(2);
  ASSERT_TRUE(lost.ok()) << lost.status().message();
  EXPECT_FALSE(lost->T_W_C.has_value());
  EXPECT_EQ(lost->pose_rejected, PoseRejection::kBadValues);
  Result<Frame> frame = (*ds)->Load(3);
  ASSERT_TRUE(frame.ok()) << frame.status().message();
  ASSERT_TRUE(frame->T_W_C.has_value());
  EXPECT_NEAR(frame->T_W_C->translation().x(), 0.15, 1e-6);
  EXPECT_NEAR(frame->timestamp, 1.0 + 3 * 0.033333, 1e-9);
  EXPECT_EQ(frame->depth_path, path.string() + ": frame 3");
  // Colour 64x48 resampled to the 32x24 depth camera: depth pixel u sees colour u' = 2u + 0.5.
  ASSERT_EQ(frame->color.width, 32);
  ASSERT_EQ(frame->color.height, 24);
  for (int u : {0, 10, 31})
    EXPECT_NEAR(Red(frame->color.at(u, 12)), (2 * u + 0.5) * 255 / 63, 6) << u;
  for (int v : {0, 11, 23})
    EXPECT_NEAR(Green(frame->color.at(16, v)), (2 * v + 0.5) * 255 / 47, 6) << v;
}

TEST(Sens, RegistrationMovesColourByTheExtrinsics) {
  // A colour camera equal to the depth camera but 0.1 m to the right (T_color_depth translates
  // x by -0.1): at 2 m depth with fx 24 a point moves 1.2 colour pixels to the left.
  const PinholeCamera cam{32, 24, 24.f, 24.f, 15.5f, 11.5f};
  const ColorImage color = test::GradientColor(32, 24);
  const DepthImage depth(32, 24, 2.0f);
  Pose3d T = Pose3d::Identity();
  T.translation().x() = -0.1;
  const ColorImage out = RegisterColorToDepth(color, cam, depth, cam, T);
  EXPECT_NEAR(Red(out.at(10, 5)), (10 - 1.2) * 255 / 31, 1.0);
  EXPECT_EQ(out.at(0, 5), 0u);  // lands left of the colour image: black
  EXPECT_EQ(RegisterColorToDepth(color, cam, depth, cam, Pose3d::Identity()).data, color.data);
}

TEST(Sens, TruncatedFilesAreRefusedNamingTheFrame) {
  const test::TempDir dir("voxplan-sens-trunc");
  const test::SensScan scan = test::MakeWallScan();
  const std::string bytes = test::EncodeSens(scan.header, scan.frames);
  // Cut inside the header; so early that 4 frames cannot fit; inside frame 2's record; inside
  // frame 3's depth.
  const size_t header = 4 + 8 + 15 + 4 * 64 + 4 * 7;
  const size_t frame_bytes =
      96 + scan.frames[0].color_bytes.size() + scan.frames[0].depth_bytes.size();
  const size_t cuts[] = {20, header + 8 + 40, header + 8 + 2 * frame_bytes + 40, bytes.size() - 10};
  const char* expect[] = {"truncated", "states 4 frames", "frame 2: truncated", "frame 3: depth"};
  for (int i = 0; i < 4; ++i) {
    const fs::path path = dir / ("cut" + std::to_string(i) + ".sens");
    test::WriteBytes(path, bytes.substr(0, cuts[i]));
    ExpectError(OpenDataset(path.string()).status(), {path.string(), expect[i]});
  }
}

TEST(Sens, CorruptHeadersAndFramesAreRefused) {
  const test::TempDir dir("voxplan-sens-bad");
  const auto refused = [&](const test::SensScan& s, std::initializer_list<std::string> what,
                           uint32_t version = 4) {
    const fs::path path = dir / "bad.sens";
    test::WriteBytes(path, test::EncodeSens(s.header, s.frames, version));
    ExpectError(OpenDataset(path.string()).status(), what);
  };
  refused(test::MakeWallScan(), {"version 3"}, 3);
  test::SensScan s = test::MakeWallScan();
  s.header.depth_compression = SensDepthCompression::kOcciUshort;
  refused(s, {"occi"});
  s = test::MakeWallScan();
  s.header.depth_width = 100000;
  refused(s, {"depth image", "16384"});
  s = test::MakeWallScan();
  s.header.depth_shift = std::nanf("");
  refused(s, {"depth shift"});
  s = test::MakeWallScan();
  s.header.depth_extrinsic(0, 0) = 2.f;
  refused(s, {"depth extrinsics"});
  s = test::MakeWallScan();
  s.frames[1].color_bytes.clear();
  refused(s, {"frame 1", "no colour"});

  // A zlib stream too short to inflate to the header's image (at most 1032-fold) is refused at
  // open, before a buffer of the header's size is allocated (a file of a few KiB could make each
  // Load allocate up to 128 MiB).
  s = test::MakeWallScan();
  s.header.depth_width = s.header.depth_height = 4096;
  refused(s, {"frame 0", "cannot inflate to the header's 4096x4096"});

  // A frame count the file cannot hold is refused before anything is reserved.
  s = test::MakeWallScan();
  std::string bytes = test::EncodeSens(s.header, s.frames);
  const size_t count_at = 4 + 8 + 15 + 4 * 64 + 4 * 7;
  for (int i = 0; i < 8; ++i) bytes[count_at + size_t(i)] = char(0xff);
  test::WriteBytes(dir / "count.sens", bytes);
  ExpectError(OpenDataset((dir / "count.sens").string()).status(), {"count.sens", "frames"});

  // Corrupt zlib depth opens (only records are read) and fails on Load, naming the frame.
  s = test::MakeWallScan();
  s.frames[1].depth_bytes = std::string(40, 'x');
  test::WriteBytes(dir / "zlib.sens", test::EncodeSens(s.header, s.frames));
  auto ds = OpenDataset((dir / "zlib.sens").string());
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  EXPECT_TRUE((*ds)->Load(0).ok());
  ExpectError((*ds)->Load(1).status(), {"zlib.sens: frame 1", "zlib"});
  // Depth that inflates to another size than the header's.
  s = test::MakeWallScan();
  s.frames[0].depth_bytes = test::ZlibDepth(DepthImage(8, 8, 1.f), 1000.f);
  test::WriteBytes(dir / "size.sens", test::EncodeSens(s.header, s.frames));
  ds = OpenDataset((dir / "size.sens").string());
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  ExpectError((*ds)->Load(0).status(), {"size.sens: frame 0", "32x24"});
}

TEST(Sens, FoldersAndFormatsAreChecked) {
  const test::TempDir dir("voxplan-sens-dirs");
  WriteScan(dir, test::MakeWallScan(), "a.sens");
  WriteScan(dir, test::MakeWallScan(), "b.sens");
  ExpectError(OpenDataset(dir.path().string()).status(), {"2 .sens files", "a.sens"});
  DatasetOptions tum;
  tum.format = DatasetFormat::kTum;
  ExpectError(OpenDataset((dir / "a.sens").string(), tum).status(), {"a.sens", "scannet"});
  test::WriteBytes(dir / "x.txt", "hello");
  ExpectError(OpenDataset((dir / "x.txt").string()).status(), {"x.txt", "not a dataset file"});
  EXPECT_TRUE(IsDatasetFile("scene.SENS"));
  EXPECT_FALSE(IsDatasetFile("map.vpmap"));
}

// fuse decodes frames ahead on worker threads: loads from several threads at once give the
// frames one thread loads.
TEST(Sens, LoadsFromSeveralThreadsMatchOneThread) {
  const test::TempDir dir("voxplan-sens-threads");
  const fs::path path = WriteScan(dir, test::MakeWallScan(8, 2));
  auto ds = OpenDataset(path.string());
  ASSERT_TRUE(ds.ok()) << ds.status().message();
  test::ExpectThreadedLoadsMatchOneThread(**ds);
}

}  // namespace
}  // namespace voxplan
