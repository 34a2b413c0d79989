// WriteFuseOutputs round trips: what it writes reads back as the run's mesh, map, poses, frames
// and surface points; empty paths write nothing; a failed write names its file.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
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

// The surface points are the mesh's vertices: on the sphere, with its colour and unit normals.
TEST(FuseOutputs, PointsAreTheSurfaceAsAPlyPointCloud) {
  const SphereRun run;
  const test::TempDir dir("voxplan-fuse-points");
  FuseOutputPaths paths;
  paths.points = (dir / "p.ply").string();
  Result<FuseOutputs> out = WriteFuseOutputs(paths, run.volume, run.report, {}, {});
  ASSERT_TRUE(out.ok()) << out.status().message();
  const size_t n = out->mesh.num_vertices();
  ASSERT_GT(n, 100u);
  std::ifstream in(paths.points, std::ios::binary);
  const std::string bytes(std::istreambuf_iterator<char>(in), {});
  const size_t end = bytes.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = bytes.substr(0, end);
  EXPECT_NE(header.find("element vertex " + std::to_string(n) + "\n"), std::string::npos);
  EXPECT_EQ(header.find("element face"), std::string::npos);
  const size_t body = end + 11, stride = 12 + 12 + 3;
  ASSERT_EQ(bytes.size(), body + n * stride);
  for (size_t i = 0; i < n; i += 37) {
    float p[6];
    std::memcpy(p, bytes.data() + body + i * stride, 24);
    EXPECT_NEAR(Eigen::Vector3f(p[0], p[1], p[2] - 1.f).norm(), 0.3f, 0.01f) << i;
    EXPECT_NEAR(Eigen::Vector3f(p[3], p[4], p[5]).norm(), 1.f, 1e-3f) << i;
    EXPECT_EQ(uint8_t(bytes[body + i * stride + 24]), test::kExactRgb[0]);
  }
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
