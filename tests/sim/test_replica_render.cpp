// Reality check: rendering Replica office0's mesh at the dataset's poses reproduces the
// dataset's own depth frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "io/image_io.h"
#include "io/mesh_io.h"
#include "sim/raycaster.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

constexpr double kDepthScale = 6553.5;      // PNG units per metre
constexpr double kMaxMedianError_m = 0.01;  // the data README measured 4.9 mm by back-projection
constexpr double kMinOverlap = 0.8;         // share of pixels valid in both

PinholeCamera ReplicaCamera() {
  PinholeCamera camera;
  camera.width = 1200;
  camera.height = 680;
  camera.fx = camera.fy = 600.f;
  camera.cx = 599.5f;
  camera.cy = 339.5f;
  return camera;
}

std::vector<Pose3f> ReadTrajectory(const fs::path& path, int max_frames) {
  std::vector<Pose3f> poses;
  std::ifstream in(path);
  std::string line;
  while (int(poses.size()) < max_frames && std::getline(in, line)) {
    std::istringstream fields(line);
    Eigen::Matrix4f m;
    for (int i = 0; i < 16; ++i) fields >> m(i / 4, i % 4);  // row-major
    if (!fields) break;
    Pose3f T_W_C;
    T_W_C.matrix() = m;
    poses.push_back(T_W_C);
  }
  return poses;
}

TEST(ReplicaRender, MeshDepthMatchesDatasetDepth) {
  const fs::path scene = test::SharedDataDir() / "scenes/replica_office0/office0_mesh.ply";
  const fs::path sequence = test::SharedDataDir() / "rgbd/replica_office0/office0";
  if (!fs::exists(scene) || !fs::exists(sequence)) GTEST_SKIP() << "shared data not found";

  auto mesh = ReadMesh(scene.string());
  ASSERT_TRUE(mesh.ok()) << mesh.status().message();
  EXPECT_EQ(mesh->num_triangles(), 50000u);
  auto raycaster = MeshRaycaster::Create(*mesh);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();

  const auto poses = ReadTrajectory(sequence / "traj.txt", 4);
  ASSERT_EQ(poses.size(), 4u);
  const PinholeCamera camera = ReplicaCamera();
  for (int frame = 0; frame < 4; ++frame) {
    char name[32];
    std::snprintf(name, sizeof(name), "depth%06d.png", frame);
    auto measured_or = ReadDepthPng((sequence / "results" / name).string(), kDepthScale);
    ASSERT_TRUE(measured_or.ok()) << measured_or.status().message();
    const DepthImage& measured = *measured_or;
    ASSERT_EQ(measured.width, camera.width) << name;
    ASSERT_EQ(measured.height, camera.height) << name;

    const RenderOutput rendered = (*raycaster)->Render(camera, poses[frame]);
    std::vector<double> errors;
    for (size_t i = 0; i < measured.data.size(); ++i)
      if (measured.data[i] > 0.f && rendered.depth.data[i] > 0.f)
        errors.push_back(std::abs(double(measured.data[i]) - double(rendered.depth.data[i])));
    ASSERT_GT(double(errors.size()), kMinOverlap * double(measured.data.size())) << name;
    const size_t mid = errors.size() / 2;
    std::nth_element(errors.begin(), errors.begin() + mid, errors.end());
    const double median = errors[mid];
    std::cout << "[ replica ] frame " << frame << ": median |depth error| " << median * 1e3
              << " mm over " << errors.size() << " pixels\n";
    RecordProperty("median_error_mm_frame" + std::to_string(frame), std::to_string(median * 1e3));
    EXPECT_LE(median, kMaxMedianError_m) << name;
  }
}

}  // namespace
}  // namespace voxplan
