// WriteFuseOutputs round trips: what it writes reads back as the run's mesh, map, poses and
// frames; empty paths write nothing; a failed write names its file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/map_io.h"
#include "io/mesh_io.h"
#include "io/tum_trajectory.h"
#include "pipeline/fuse_outputs.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

// A fused sphere and a report of two frames with known poses.
struct SphereRun {
  TsdfVolume volume = test::FillExactSdf(
      [](const Eigen::Vector3f& p) {
        return test::Sphere{Eigen::Vector3f(0.f, 0.f, 1.f), 0.3f}.Sdf(p);
      },
      VolumeParams{0.02f, 0.08f}, Eigen::Vector3f(-0.5f, -0.5f, 0.5f),
      Eigen::Vector3f(0.5f, 0.5f, 1.5f));
  FuseReport report;
  SphereRun() {
    for (int k = 0; k < 2; ++k) {
      FusedFrame f;
      f.index = size_t(k);
      f.timestamp_s = 1.0 + k;
      f.T_W_C.translation() = Eigen::Vector3f(0.1f * float(k), 0.f, 0.f);
      f.depth_path = k == 0 ? "d0.png" : "d1.png";
      report.frames.push_back(f);
    }
  }
};

TEST(FuseOutputs, WhatIsWrittenReadsBackAsTheRun) {
  const SphereRun run;
  const test::TempDir dir("voxplan-fuse-outputs");
  const FuseOutputPaths paths{(dir / "m.ply").string(), (dir / "m.vpmap").string(),
                              (dir / "t.txt").string(), (dir / "f.json").string()};
  FrameListParams list;
  list.camera = test::TestCamera();
  list.voxel_size_m = 0.02;
  Result<FuseOutputs> out = WriteFuseOutputs(paths, run.volume, run.report, {}, list);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_GT(out->mesh.num_triangles(), 100u);

  Result<Mesh> mesh = ReadMesh(paths.mesh);
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->num_triangles(), out->mesh.num_triangles());
  Result<TsdfVolume> map = LoadMap(paths.map);
  ASSERT_TRUE(map.ok()) << map.status().message();
  EXPECT_EQ(map->SortedBlockIndices(), run.volume.SortedBlockIndices());
  Result<TumTrajectory> trajectory = ReadTumTrajectory(paths.trajectory);
  ASSERT_TRUE(trajectory.ok()) << trajectory.status().message();
  ASSERT_EQ(trajectory->T_W_C.size(), 2u);
  EXPECT_DOUBLE_EQ(trajectory->timestamps_s[1], 2.0);
  EXPECT_NEAR(trajectory->T_W_C[1].translation().x(), 0.1, 1e-7);
  const nlohmann::json frames = nlohmann::json::parse(std::ifstream(paths.frame_list));
  ASSERT_EQ(frames["frames"].size(), 2u);
  EXPECT_EQ(frames["frames"][1]["depth"], "d1.png");
  EXPECT_EQ(frames["width"], list.camera.width);
}

TEST(FuseOutputs, EmptyPathsWriteNothingAndAFailureNamesTheFile) {
  const SphereRun run;
  const test::TempDir dir("voxplan-fuse-outputs");
  Result<FuseOutputs> none = WriteFuseOutputs({}, run.volume, run.report, {}, {});
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->mesh.num_triangles(), 0u);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));

  const std::string missing = (dir / "no_such_folder" / "t.txt").string();
  FuseOutputPaths paths;
  paths.trajectory = missing;
  Result<FuseOutputs> failed = WriteFuseOutputs(paths, run.volume, run.report, {}, {});
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.status().message().find(missing), std::string::npos)
      << failed.status().message();
}

}  // namespace
}  // namespace voxplan
