// Datasets in one file, run through the CLI as a user would: a ScanNet .sens file the test
// writes is described by `info` and fused by `fuse` like any dataset folder, its lost-tracking
// frame skipped and counted, and the file itself is refused as an output; so is a ROS 1 bag
// written by rosbag, its topics found or named with --topics; a ROS 2 bag is refused saying how
// to convert it. `fuse` also writes the surface as a point cloud and the occupancy as OctoMap.
// Float depth: a TUM-style folder of 32-bit float TIFF or EXR depth (metres) fuses into the same
// map, checksum for checksum, as the same depths in 16-bit PNGs at scale 1000.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "io/image_io.h"
#include "tests/io/bag_fixture.h"
#include "tests/io/float_depth_fixture.h"
#include "tests/io/sens_fixture.h"
#include "tests/support/test_support.h"
#include "tests/system/cli_runner.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;
using test::Describe;
using test::RunCli;
using test::RunResult;

fs::path WriteWallSens(const test::TempDir& dir) {
  const test::SensScan scan = test::MakeWallScan(/*frames=*/6, /*lost=*/2);
  const fs::path path = dir / "scene0000_00" / "scene0000_00.sens";
  test::WriteBytes(path, test::EncodeSens(scan.header, scan.frames));
  return path;
}

TEST(FormatsCli, InfoDescribesASensFile) {
  const test::TempDir dir("voxplan-sens-info");
  const fs::path sens = WriteWallSens(dir);
  const RunResult r = RunCli({"info", sens.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const auto& j = r.last_json;
  EXPECT_EQ(j.at("kind"), "dataset");
  EXPECT_EQ(j.at("format"), "scannet");
  EXPECT_EQ(j.at("frames").get<int>(), 6);
  EXPECT_EQ(j.at("frames_bad_pose").get<int>(), 1);
  EXPECT_EQ(j.at("camera").at("width").get<int>(), 32);
  EXPECT_DOUBLE_EQ(j.at("depth_scale").get<double>(), 1000.0);
  EXPECT_TRUE(j.at("has_color").get<bool>());
  EXPECT_NE(r.err.find("bad poses   1 of 6 frames"), std::string::npos) << Describe(r);
  // The scene folder reads the same file.
  const RunResult folder = RunCli({"info", sens.parent_path().string()});
  ASSERT_EQ(folder.exit_code, 0) << Describe(folder);
  EXPECT_EQ(folder.last_json.at("format"), "scannet");
}

TEST(FormatsCli, FuseASensFileLikeAFolder) {
  const test::TempDir dir("voxplan-sens-fuse");
  const fs::path sens = WriteWallSens(dir), mesh = dir / "wall.ply", stats = dir / "stats.json";
  const RunResult r =
      RunCli({"fuse", sens.string(), "--voxel-size", "0.02", "--max-depth", "3", "--threads", "1",
              "--mesh", mesh.string(), "--stats", stats.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const auto& j = r.last_json;
  EXPECT_EQ(j.at("format"), "scannet");
  EXPECT_EQ(j.at("frames").get<int>(), 5);
  EXPECT_EQ(j.at("frames_skipped_bad_pose").get<int>(), 1);
  EXPECT_GT(j.at("mesh_triangles").get<int>(), 100);
  EXPECT_TRUE(fs::is_regular_file(mesh));
  EXPECT_NE(r.err.find("frame 2"), std::string::npos) << Describe(r);  // the -inf pose, warned

  // The .sens file is an input: writing over it is refused before any work.
  const RunResult clobber = RunCli({"fuse", sens.string(), "--stats", sens.string()});
  EXPECT_EQ(clobber.exit_code, 2) << Describe(clobber);
  EXPECT_NE(clobber.err.find(sens.string()), std::string::npos) << Describe(clobber);
  // A truncated file is refused naming it.
  const fs::path cut = dir / "cut.sens";
  test::WriteBytes(cut, test::ReadAll(sens).substr(0, 200));
  const RunResult truncated = RunCli({"fuse", cut.string()});
  EXPECT_EQ(truncated.exit_code, 1) << Describe(truncated);
  EXPECT_NE(truncated.err.find("cut.sens"), std::string::npos) << Describe(truncated);
}

TEST(FormatsCli, FuseWritesPointsAndOctomap) {
  const test::TempDir dir("voxplan-points-cli");
  const fs::path sens = WriteWallSens(dir), points = dir / "wall_points.ply",
                 octomap = dir / "wall.bt";
  const RunResult r = RunCli({"fuse", sens.string(), "--voxel-size", "0.02", "--threads", "1",
                              "--points", points.string(), "--octomap", octomap.string()});
  ASSERT_EQ(r.exit_code, 0) << Describe(r);
  const auto& j = r.last_json;
  EXPECT_EQ(j.at("points").get<std::string>(), points.string());
  EXPECT_GT(j.at("point_count").get<int>(), 100);
  EXPECT_EQ(j.at("point_count"), j.at("mesh_vertices"));
  EXPECT_TRUE(j.at("mesh").is_null());
  EXPECT_GT(j.at("octomap_occupied_voxels").get<int>(), 100);
  EXPECT_GT(j.at("octomap_free_voxels").get<int>(), 100);
  const std::string ply = test::ReadAll(points);
  EXPECT_EQ(ply.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(ply.find("element vertex " + std::to_string(j.at("point_count").get<int>())),
            std::string::npos);
  EXPECT_EQ(ply.find("element face"), std::string::npos);
  EXPECT_EQ(test::ReadAll(octomap).rfind("# Octomap OcTree binary file\n", 0), 0u);

  // Wrong extensions and an output written twice are refused before any work.
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--points", (dir / "p.xyz").string()},
        std::vector<std::string>{"--octomap", (dir / "o.ot").string()},
        std::vector<std::string>{"--points", points.string(), "--mesh", points.string()}}) {
    std::vector<std::string> args = {"fuse", sens.string()};
    args.insert(args.end(), bad.begin(), bad.end());
    const RunResult refused = RunCli(args);
    EXPECT_EQ(refused.exit_code, 2) << Describe(refused);
  }
}

TEST(FormatsCli, InfoAndFuseARosBag) {
  const test::TempDir dir("voxplan-bag-cli");
  const fs::path bag = dir / "run.bag", mesh = dir / "run.ply";
  test::WriteBag(bag.string(), test::BagScene{});
  const RunResult info = RunCli({"info", bag.string()});
  ASSERT_EQ(info.exit_code, 0) << Describe(info);
  EXPECT_EQ(info.last_json.at("format"), "rosbag");
  EXPECT_EQ(info.last_json.at("frames").get<int>(), 6);
  EXPECT_NE(info.err.find("topics      depth /camera/depth/image (32FC1)"), std::string::npos)
      << Describe(info);
  EXPECT_NE(info.last_json.at("pose_source").get<std::string>().find("/tf"), std::string::npos);

  const RunResult fuse = RunCli(
      {"fuse", bag.string(), "--voxel-size", "0.02", "--threads", "1", "--mesh", mesh.string()});
  ASSERT_EQ(fuse.exit_code, 0) << Describe(fuse);
  EXPECT_EQ(fuse.last_json.at("format"), "rosbag");
  EXPECT_EQ(fuse.last_json.at("frames").get<int>(), 6);
  EXPECT_GT(fuse.last_json.at("mesh_triangles").get<int>(), 100);
  EXPECT_TRUE(fs::is_regular_file(mesh));

  // --topics: named topics are used, a malformed option is a usage error, a missing topic an error.
  const RunResult named =
      RunCli({"info", bag.string(), "--topics", "depth=/camera/depth/image,pose=/tf"});
  EXPECT_EQ(named.exit_code, 0) << Describe(named);
  const RunResult malformed = RunCli({"fuse", bag.string(), "--topics", "depth"});
  EXPECT_EQ(malformed.exit_code, 2) << Describe(malformed);
  EXPECT_NE(malformed.err.find("key=topic"), std::string::npos) << Describe(malformed);
  const RunResult missing = RunCli({"fuse", bag.string(), "--topics", "depth=/nope"});
  EXPECT_EQ(missing.exit_code, 1) << Describe(missing);
  EXPECT_NE(missing.err.find("no topic /nope"), std::string::npos) << Describe(missing);
  // The bag is an input: writing over it is refused before any work.
  const RunResult clobber = RunCli({"fuse", bag.string(), "--stats", bag.string()});
  EXPECT_EQ(clobber.exit_code, 2) << Describe(clobber);
}

TEST(FormatsCli, Ros2BagRefusedWithHowToConvert) {
  const test::TempDir dir("voxplan-ros2-cli");
  const fs::path db3 = dir / "rec" / "rec_0.db3";
  test::WriteBytes(db3, "SQLite format 3");
  for (const char* command : {"info", "fuse"}) {
    const RunResult r = RunCli({command, db3.string()});
    EXPECT_EQ(r.exit_code, 1) << Describe(r);
    EXPECT_NE(r.err.find("rosbags-convert"), std::string::npos) << Describe(r);
    EXPECT_NE(r.err.find(db3.string()), std::string::npos) << Describe(r);
  }
}

// A TUM-style folder of `frames` views of a tilted wall, every depth a whole number of
// millimetres (so that 16-bit PNG at scale 1000 and float metres hold the same values), a few
// pixels invalid: ext ".png" writes the millimetres, ".tif" / ".exr" float metres (invalid
// pixels as NaN, -1 and 0, which read as 0 like the PNG's 0).
fs::path WriteWallFolder(const fs::path& root, const std::string& ext, int frames) {
  const int w = 48, h = 36;
  std::string list, gt;
  for (int k = 0; k < frames; ++k) {
    std::vector<uint16_t> mm(size_t(w * h));
    DepthImage metres(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y * w + x);
        mm[i] = uint16_t(1200 + 7 * x + 3 * y + 11 * k);
        if ((x * 13 + y * 7 + k) % 29 == 0) mm[i] = 0;
        // As ReadDepthPng converts units (io/image_io.cpp).
        metres.data[i] = float(double(mm[i]) * (1.0 / 1000.0));
        if (mm[i] == 0) {
          const float invalid[3] = {std::numeric_limits<float>::quiet_NaN(), -1.f, 0.f};
          metres.data[i] = invalid[(x + y) % 3];
        }
      }
    const std::string name = "depth/" + std::to_string(k) + ext;
    if (ext == ".png") {
      fs::create_directories(root / "depth");
      EXPECT_TRUE(WritePngRaw((root / name).string(), w, h, 1, 16, mm.data()).ok());
    } else {
      test::WriteFloatDepth(root / name, metres);
    }
    const std::string t = std::to_string(10.0 + 0.1 * k);
    list += t + " " + name + "\n";
    gt += t + " " + std::to_string(0.02 * k) + " 0 " + std::to_string(-0.01 * k) + " 0 0 0 1\n";
  }
  test::WriteBytes(root / "depth.txt", list);
  test::WriteBytes(root / "groundtruth.txt", gt);
  test::WriteBytes(root / "camera.txt", "40 40 23.5 17.5\n");
  return root;
}

// `voxplan fuse` of `dataset` into a map, then its checksum as `voxplan info` gives it.
std::string FusedChecksum(const fs::path& dataset, const fs::path& map,
                          const std::vector<std::string>& extra, nlohmann::json* stats) {
  std::vector<std::string> args = {
      "fuse", dataset.string(), "--voxel-size", "0.01", "--max-depth", "3", "--threads",
      "2",    "--map",          map.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const RunResult fused = RunCli(args);
  EXPECT_EQ(fused.exit_code, 0) << Describe(fused);
  if (stats) *stats = fused.last_json;
  const RunResult info = RunCli({"info", map.string()});
  EXPECT_EQ(info.exit_code, 0) << Describe(info);
  return info.last_json.is_object() ? info.last_json.value("checksum", "") : "";
}

TEST(FormatsCli, FloatDepthFusesLikeSixteenBitPng) {
  const test::TempDir dir("voxplan-float-depth");
  const fs::path png = WriteWallFolder(dir / "png", ".png", 3);
  nlohmann::json png_stats;
  const std::string reference =
      FusedChecksum(png, dir / "png.vpmap", {"--depth-scale", "1000"}, &png_stats);
  ASSERT_FALSE(reference.empty());
  EXPECT_EQ(png_stats.at("depth_encoding"), "16-bit PNG");
  EXPECT_TRUE(png_stats.at("depth_scale_applies").get<bool>());
  EXPECT_GT(png_stats.at("blocks").get<int>(), 0);
  for (const char* ext : {".tif", ".exr"}) {
    SCOPED_TRACE(ext);
    const fs::path folder = WriteWallFolder(dir / (std::string("float") + ext), ext, 3);
    const RunResult info = RunCli({"info", folder.string()});
    ASSERT_EQ(info.exit_code, 0) << Describe(info);
    const std::string encoding =
        std::string("32-bit float ") + (std::string(ext) == ".exr" ? "EXR" : "TIFF");
    EXPECT_EQ(info.last_json.at("depth_encoding"), encoding);
    EXPECT_FALSE(info.last_json.at("depth_scale_applies").get<bool>());
    EXPECT_NE(info.err.find(encoding + ", metres (the depth scale does not apply)"),
              std::string::npos)
        << Describe(info);
    nlohmann::json stats;
    // No depth scale given (TUM's 5000 is in force, and ignored: the files are metres).
    EXPECT_EQ(FusedChecksum(folder, dir / (std::string("float") + ext + ".vpmap"), {}, &stats),
              reference);
    EXPECT_EQ(stats.at("depth_encoding"), encoding);
    EXPECT_FALSE(stats.at("depth_scale_applies").get<bool>());
    EXPECT_EQ(stats.at("frames").get<int>(), 3);
  }
}

}  // namespace
}  // namespace voxplan
