// Datasets in one file, run through the CLI as a user would: a ScanNet .sens file the test
// writes is described by `info` and fused by `fuse` like any dataset folder, its lost-tracking
// frame skipped and counted, and the file itself is refused as an output; so is a ROS 1 bag
// written by rosbag, its topics found or named with --topics; a ROS 2 bag is refused saying how
// to convert it. `fuse` also writes the surface as a point cloud and the occupancy as OctoMap.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/io/bag_fixture.h"
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

}  // namespace
}  // namespace voxplan
