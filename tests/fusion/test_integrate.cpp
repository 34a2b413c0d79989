// Integration against analytic scenes whose signed distance is known exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/queries.h"
#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

using test::TestCamera;

constexpr float kVoxel = 0.02f;
constexpr float kTrunc = 0.08f;
// Head-on, the projective TSDF is the exact SDF up to 16-bit rounding.
constexpr float kMaxHeadOnSdfErrorVox = 0.01f;
// Seen obliquely it overestimates distances by 1/cos(angle): looser bounds for curved scenes.
constexpr float kMaxObliqueSdfErrorVox = 0.75f;
// Fused mesh vertices lie this close to the true surface.
constexpr float kMaxMeshErrorVox = 0.2f;

template <typename Scene>
TsdfVolume FuseViews(const Scene& scene, const std::vector<Pose3f>& poses,
                     const IntegrateParams& params = {}) {
  TsdfVolume volume({kVoxel, kTrunc});
  const PinholeCamera cam = TestCamera(320, 240);
  for (const Pose3f& T_W_C : poses) {
    const DepthImage depth = test::RenderDepth(scene, cam, T_W_C);
    auto stats = IntegrateFrame(depth, ColorImage{}, cam, T_W_C, params, volume);
    EXPECT_TRUE(stats.ok()) << stats.status().message();
  }
  return volume;
}

// Projective distances are exact for surfaces seen head-on and overestimate at grazing angles
// and silhouettes, so the bounds are on the median and the 95th percentile.
std::pair<float, float> MedianAndP95(std::vector<float> v) {
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v[v.size() * 95 / 100]};
}

template <typename Scene>
void ExpectTsdfMatchesSdf(const TsdfVolume& volume, const Scene& scene, size_t min_checked,
                          float max_median_vox) {
  std::vector<float> errors;
  volume.ForEachBlock([&](BlockIndex b, const TsdfBlock& block) {
    for (int i = 0; i < kBlockVoxels; ++i) {
      if (block.weight[i] == 0) continue;
      const Eigen::Vector3f p = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), kVoxel);
      const float sdf = scene.Sdf(p);
      if (std::abs(sdf) > 1.0f * kVoxel) continue;
      errors.push_back(std::abs(DecodeTsdf(block.tsdf[i]) * kTrunc - sdf) / kVoxel);
    }
  });
  ASSERT_GE(errors.size(), min_checked);
  const auto [median, p95] = MedianAndP95(errors);
  std::printf("tsdf error (voxels): median %.4f p95 %.4f over %zu voxels\n", median, p95,
              errors.size());
  EXPECT_LT(median, max_median_vox);
  EXPECT_LT(p95, 3 * max_median_vox);
}

template <typename Scene>
void ExpectMeshOnSurface(const TsdfVolume& volume, const Scene& scene) {
  const Mesh mesh = ExtractMesh(volume);
  ASSERT_GT(mesh.num_triangles(), 100u);
  std::vector<float> errors;
  for (const auto& p : mesh.positions) errors.push_back(std::abs(scene.Sdf(p)) / kVoxel);
  const auto [median, p95] = MedianAndP95(errors);
  std::printf("mesh error (voxels): median %.4f p95 %.4f\n", median, p95);
  EXPECT_LT(median, kMaxMeshErrorVox);
  EXPECT_LT(p95, 2 * kMaxMeshErrorVox);
}

TEST(Integrate, FrontoParallelPlaneIsExact) {
  const test::Plane plane{Eigen::Vector3f(0, 0, -1), -1.5f};  // z = 1.5 facing the camera at 0
  const Pose3f T_W_C = Pose3f::Identity();
  const TsdfVolume volume = FuseViews(plane, {T_W_C});
  ExpectTsdfMatchesSdf(volume, plane, 1000, kMaxHeadOnSdfErrorVox);
  ExpectMeshOnSurface(volume, plane);
}

TEST(Integrate, SphereFromSixViews) {
  const test::Sphere sphere{Eigen::Vector3f(0.1f, -0.05f, 0.02f), 0.4f};
  std::vector<Pose3f> poses;
  for (int k = 0; k < 6; ++k) {
    const float a = float(k) * 2.0f * float(M_PI) / 6.0f;
    poses.push_back(
        LookAt(sphere.c + Eigen::Vector3f(1.5f * std::cos(a), 1.5f * std::sin(a), 0.3f), sphere.c));
  }
  const TsdfVolume volume = FuseViews(sphere, poses);
  ExpectTsdfMatchesSdf(volume, sphere, 2000, kMaxObliqueSdfErrorVox);
  ExpectMeshOnSurface(volume, sphere);
}

TEST(Integrate, BoxCornerView) {
  const test::Box box{Eigen::Vector3f(-0.3f, -0.2f, -0.25f), Eigen::Vector3f(0.3f, 0.2f, 0.25f)};
  const TsdfVolume volume =
      FuseViews(box, {LookAt({1.2f, 0.9f, 0.8f}, {0, 0, 0}), LookAt({-1.1f, 1.0f, 0.7f}, {0, 0, 0}),
                      LookAt({0.2f, -1.3f, 0.9f}, {0, 0, 0})});
  // Near edges the projective distance differs from the Euclidean one; check face interiors
  // (points at least two voxels from every edge of the box).
  const Mesh mesh = ExtractMesh(volume);
  ASSERT_GT(mesh.num_triangles(), 100u);
  std::vector<float> errors;
  for (const auto& p : mesh.positions) {
    int inside_extent = 0;
    for (int a = 0; a < 3; ++a)
      inside_extent += p[a] > box.lo[a] + 2 * kVoxel && p[a] < box.hi[a] - 2 * kVoxel;
    if (inside_extent == 2) errors.push_back(std::abs(box.Sdf(p)) / kVoxel);
  }
  ASSERT_GT(errors.size(), 100u);
  const auto [median, p95] = MedianAndP95(errors);
  std::printf("mesh error (voxels): median %.4f p95 %.4f\n", median, p95);
  EXPECT_LT(median, kMaxMeshErrorVox);
  EXPECT_LT(p95, 2 * kMaxMeshErrorVox);
}

TEST(Integrate, DepthRangeAndInvalidPixelsAreSkipped) {
  const PinholeCamera cam = TestCamera(64, 48);
  DepthImage depth(cam.width, cam.height, 0.0f);
  for (int u = 0; u < 32; ++u)
    for (int v = 0; v < cam.height; ++v) depth.at(u, v) = 1.0f;  // valid
  for (int v = 0; v < cam.height; ++v) depth.at(40, v) = 5.0f;   // too far
  for (int v = 0; v < cam.height; ++v) depth.at(50, v) = std::numeric_limits<float>::quiet_NaN();
  IntegrateParams params;
  params.max_depth_m = 3.0f;
  TsdfVolume volume({kVoxel, kTrunc});
  auto stats = IntegrateFrame(depth, ColorImage{}, cam, Pose3f::Identity(), params, volume);
  ASSERT_TRUE(stats.ok());
  EXPECT_EQ(stats->valid_pixels, size_t(32 * cam.height));
  // Nothing is allocated near the far or NaN columns' depth.
  const Eigen::Vector3f far_point = cam.Unproject(40, 24, 5.0f);
  EXPECT_EQ(StateAt(volume, far_point), VoxelState::kUnobserved);
  // All-invalid frame: no blocks, no error.
  TsdfVolume empty({kVoxel, kTrunc});
  ASSERT_TRUE(
      IntegrateFrame(DepthImage(64, 48, 0.f), ColorImage{}, cam, Pose3f::Identity(), params, empty)
          .ok());
  EXPECT_EQ(empty.num_blocks(), 0u);
}

TEST(Integrate, WeightIsCappedAndWeightingModesDiffer) {
  const PinholeCamera cam = TestCamera(32, 24);
  const DepthImage depth(cam.width, cam.height, 2.0f);
  IntegrateParams params;
  params.max_weight = 5.0f;
  TsdfVolume volume({kVoxel, kTrunc});
  for (int i = 0; i < 12; ++i)
    ASSERT_TRUE(IntegrateFrame(depth, ColorImage{}, cam, Pose3f::Identity(), params, volume).ok());
  const auto on_axis = VoxelAtPoint(volume, Eigen::Vector3f(0.005f, 0.005f, 2.0f - 0.5f * kVoxel));
  ASSERT_TRUE(on_axis.has_value());
  EXPECT_FLOAT_EQ(on_axis->weight, 5.0f);

  params.weighting = Weighting::kDepthDependent;
  TsdfVolume weighted({kVoxel, kTrunc});
  ASSERT_TRUE(IntegrateFrame(depth, ColorImage{}, cam, Pose3f::Identity(), params, weighted).ok());
  const auto w = VoxelAtPoint(weighted, Eigen::Vector3f(0.005f, 0.005f, 2.0f - 0.5f * kVoxel));
  ASSERT_TRUE(w.has_value());
  EXPECT_NEAR(w->weight, 1.0f / (2.0f * 2.0f), 1.0f / kWeightScale);
}

TEST(Integrate, ColourIsFusedNearTheSurface) {
  const PinholeCamera cam = TestCamera(32, 24);
  const DepthImage depth(cam.width, cam.height, 1.0f);
  ColorImage color(cam.width, cam.height, PackRgb(200, 100, 50));
  TsdfVolume volume({kVoxel, kTrunc});
  ASSERT_TRUE(IntegrateFrame(depth, color, cam, Pose3f::Identity(), {}, volume).ok());
  color = ColorImage(cam.width, cam.height, PackRgb(100, 0, 150));
  ASSERT_TRUE(IntegrateFrame(depth, color, cam, Pose3f::Identity(), {}, volume).ok());
  const auto v = VoxelAtPoint(volume, Eigen::Vector3f(0.005f, 0.005f, 1.0f - 0.5f * kVoxel));
  ASSERT_TRUE(v.has_value());
  EXPECT_NEAR(v->rgb.x(), 150.f, 0.5f);
  EXPECT_NEAR(v->rgb.y(), 50.f, 0.5f);
  EXPECT_NEAR(v->rgb.z(), 100.f, 0.5f);
}

TEST(Integrate, RefusesMismatchedInputs) {
  const PinholeCamera cam = TestCamera(32, 24);
  TsdfVolume volume({kVoxel, kTrunc});
  EXPECT_FALSE(
      IntegrateFrame(DepthImage(31, 24, 1.f), ColorImage{}, cam, Pose3f::Identity(), {}, volume)
          .ok());
  EXPECT_FALSE(IntegrateFrame(DepthImage(32, 24, 1.f), ColorImage(16, 12), cam, Pose3f::Identity(),
                              {}, volume)
                   .ok());
  Pose3f bad = Pose3f::Identity();
  bad.translation().x() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(IntegrateFrame(DepthImage(32, 24, 1.f), ColorImage{}, cam, bad, {}, volume).ok());
  IntegrateParams params;
  params.max_weight = 1000.f;
  EXPECT_FALSE(
      IntegrateFrame(DepthImage(32, 24, 1.f), ColorImage{}, cam, Pose3f::Identity(), params, volume)
          .ok());
}

}  // namespace
}  // namespace voxplan
