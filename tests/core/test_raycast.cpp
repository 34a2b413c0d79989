// Raycasting against volumes filled with exact analytic signed distances: depth, normals,
// colour and status per pixel, negative fy, unobserved gaps, depth limits and thread parity.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "core/raycast.h"
#include "core/raycast/raycast_kernels.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

using test::Box;
using test::Plane;
using test::Sphere;
using test::TestCamera;

constexpr float kVoxel = 0.01f;
constexpr float kTrunc = 4 * kVoxel;
constexpr uint8_t kR = test::kExactRgb[0], kG = test::kExactRgb[1], kB = test::kExactRgb[2];

using Sdf = std::function<float(const Eigen::Vector3f&)>;

TsdfVolume FillExact(const Sdf& sdf, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                     bool all_blocks = false) {
  return test::FillExactSdf(sdf, {kVoxel, kTrunc}, lo, hi, all_blocks);
}

// True when every pixel within `radius` has an analytic hit: away from silhouettes.
bool Interior(const DepthImage& truth, int u, int v, int radius) {
  for (int dv = -radius; dv <= radius; ++dv)
    for (int du = -radius; du <= radius; ++du) {
      const int uu = u + du, vv = v + dv;
      if (uu < 0 || vv < 0 || uu >= truth.width || vv >= truth.height) return false;
      if (truth.at(uu, vv) <= 0.f) return false;
    }
  return true;
}

float Median(std::vector<float> v) {
  if (v.empty()) return 0.f;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

size_t Count(const RaycastImages& images, RayStatus status) {
  return size_t(std::count(images.status.data.begin(), images.status.data.end(), uint8_t(status)));
}

// Depth against the analytic depth (in voxels) and normals against the analytic normals,
// away from silhouettes.
struct Errors {
  float median_vox = 0.f, max_vox = 0.f, max_normal_deg = 0.f;
  size_t checked = 0, missed = 0;
};
Errors Compare(const RaycastImages& images, const DepthImage& truth, const PinholeCamera& cam,
               const Pose3f& T_W_C,
               const std::function<Eigen::Vector3f(const Eigen::Vector3f&)>& normal_at) {
  Errors e;
  std::vector<float> errors;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      if (!Interior(truth, u, v, 2)) continue;
      ++e.checked;
      if (images.status.at(u, v) != uint8_t(RayStatus::kHit)) {
        ++e.missed;
        continue;
      }
      const float err = std::abs(images.depth.at(u, v) - truth.at(u, v)) / kVoxel;
      errors.push_back(err);
      e.max_vox = std::max(e.max_vox, err);
      const Eigen::Vector3f p_W = T_W_C * cam.Unproject(float(u), float(v), truth.at(u, v));
      const float cos_angle = images.normal_W.at(u, v).dot(normal_at(p_W));
      e.max_normal_deg =
          std::max(e.max_normal_deg, float(std::acos(std::min(1.f, cos_angle)) * 180.0 / M_PI));
    }
  e.median_vox = Median(errors);
  return e;
}

// Named tolerances: trilinear interpolation of an exact SDF sampled at 1 cm.
constexpr float kMedianDepthVox = 0.05f;
constexpr float kMaxDepthVox = 0.2f;
constexpr float kMaxNormalDeg = 3.0f;

TEST(Raycast, SphereDepthNormalsColourAndVertices) {
  const Sphere sphere{Eigen::Vector3f(0.02f, -0.03f, 0.01f), 0.3f};
  const TsdfVolume volume = FillExact([&](const Eigen::Vector3f& p) { return sphere.Sdf(p); },
                                      sphere.c - Eigen::Vector3f::Constant(0.45f),
                                      sphere.c + Eigen::Vector3f::Constant(0.45f));
  // Also a size that is not a multiple of the 16-pixel tiles: partial tile rows and columns.
  for (const auto& [width, height] : {std::pair{160, 120}, std::pair{157, 117}}) {
    SCOPED_TRACE(std::to_string(width) + "x" + std::to_string(height));
    const PinholeCamera cam = TestCamera(width, height);
    const Pose3f T_W_C = LookAt(sphere.c + Eigen::Vector3f(0.9f, -0.5f, 0.3f), sphere.c);
    const RaycastImages images = Raycast(volume, cam, T_W_C);
    ASSERT_EQ(images.depth.width, cam.width);
    ASSERT_EQ(images.status.height, cam.height);

    const DepthImage truth = test::RenderDepth(sphere, cam, T_W_C);
    const Errors e = Compare(images, truth, cam, T_W_C, [&](const Eigen::Vector3f& p) {
      return Eigen::Vector3f((p - sphere.c).normalized());
    });
    std::printf("sphere: depth error median %.4f max %.4f voxel, normals max %.3f deg, %zu px\n",
                e.median_vox, e.max_vox, e.max_normal_deg, e.checked);
    ASSERT_GT(e.checked, 3000u);
    EXPECT_EQ(e.missed, 0u);
    EXPECT_LE(e.median_vox, kMedianDepthVox);
    EXPECT_LE(e.max_vox, kMaxDepthVox);
    EXPECT_LE(e.max_normal_deg, kMaxNormalDeg);

    size_t hits = 0;
    for (size_t i = 0; i < images.status.data.size(); ++i) {
      const int u = int(i % size_t(cam.width)), v = int(i / size_t(cam.width));
      if (images.status.data[i] != uint8_t(RayStatus::kHit)) {
        EXPECT_EQ(images.depth.data[i], 0.f);
        EXPECT_TRUE(images.vertex_W.data[i].array().isNaN().all());
        EXPECT_TRUE(images.normal_W.data[i].array().isNaN().all());
        EXPECT_EQ(images.color.data[i], 0u);
        continue;
      }
      ++hits;
      EXPECT_EQ(images.color.data[i], PackRgb(kR, kG, kB));
      EXPECT_NEAR(images.normal_W.data[i].norm(), 1.f, 1e-4f);
      // The vertex lies on the pixel's ray at the reported depth.
      const Eigen::Vector3f expected =
          T_W_C * cam.Unproject(float(u), float(v), images.depth.data[i]);
      EXPECT_LT((images.vertex_W.data[i] - expected).norm(), 1e-5f);
      EXPECT_LT(std::abs(sphere.Sdf(images.vertex_W.data[i])), 0.25f * kVoxel);
    }
    // Rays past the silhouette cross allocated free space or nothing at all.
    EXPECT_GT(Count(images, RayStatus::kFree) + Count(images, RayStatus::kUnobserved), 0u);
    EXPECT_EQ(hits + Count(images, RayStatus::kFree) + Count(images, RayStatus::kUnobserved),
              images.status.data.size());
  }
}

TEST(Raycast, BoxWithNegativeFy) {
  // ICL-NUIM's cameras flip the image y axis; the raycast must agree with the analytic render.
  const Box box{Eigen::Vector3f(-0.2f, -0.15f, -0.1f), Eigen::Vector3f(0.25f, 0.2f, 0.15f)};
  const TsdfVolume volume = FillExact([&](const Eigen::Vector3f& p) { return box.Sdf(p); },
                                      box.lo - Eigen::Vector3f::Constant(0.15f),
                                      box.hi + Eigen::Vector3f::Constant(0.15f));
  PinholeCamera cam = TestCamera(160, 120);
  cam.fy = -cam.fy;
  const Pose3f T_W_C =
      LookAt(Eigen::Vector3f(0.8f, 0.6f, 0.7f), Eigen::Vector3f(0.02f, 0.02f, 0.f));
  const RaycastImages images = Raycast(volume, cam, T_W_C);
  const DepthImage truth = test::RenderDepth(box, cam, T_W_C);
  // Normals are checked below, away from the edges where the SDF bends within a voxel.
  const Errors e = Compare(images, truth, cam, T_W_C,
                           [](const Eigen::Vector3f&) { return Eigen::Vector3f::UnitX(); });
  std::printf("box: depth error median %.4f max %.4f voxel, %zu px\n", e.median_vox, e.max_vox,
              e.checked);
  ASSERT_GT(e.checked, 1500u);
  EXPECT_EQ(e.missed, 0u);
  EXPECT_LE(e.median_vox, kMedianDepthVox);
  // Edges of the box: the SDF is not linear within a voxel of them.
  size_t far_from_edges = 0, bad_normals = 0;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      if (!Interior(truth, u, v, 2) || images.status.at(u, v) != uint8_t(RayStatus::kHit)) continue;
      const Eigen::Vector3f p = T_W_C * cam.Unproject(float(u), float(v), truth.at(u, v));
      int near_faces = 0;
      for (int a = 0; a < 3; ++a)
        near_faces +=
            std::min(std::abs(p[a] - box.lo[a]), std::abs(p[a] - box.hi[a])) < 2.5f * kVoxel;
      if (near_faces > 1) continue;
      ++far_from_edges;
      EXPECT_LE(std::abs(images.depth.at(u, v) - truth.at(u, v)) / kVoxel, kMaxDepthVox);
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      for (int a = 0; a < 3; ++a) {
        if (std::abs(p[a] - box.lo[a]) < 1e-3f) n[a] = -1.f;
        if (std::abs(p[a] - box.hi[a]) < 1e-3f) n[a] = 1.f;
      }
      bad_normals += images.normal_W.at(u, v).dot(n) < std::cos(kMaxNormalDeg * M_PI / 180.0);
    }
  EXPECT_GT(far_from_edges, 1000u);
  EXPECT_EQ(bad_normals, 0u);
}

TEST(Raycast, ThinSheetInFrontOfAFloorHidesIt) {
  // Rays skip ahead to just in front of the nearest negative voxel the range image knows of;
  // were that bound ever past the sheet (2.5 voxels thick), the floor 15 cm behind it would be
  // reported instead. Seen head-on, obliquely and near grazing.
  const Box sheet{Eigen::Vector3f(-0.25f, -0.25f, 0.f), Eigen::Vector3f(0.25f, 0.25f, 0.025f)};
  const Plane floor{Eigen::Vector3f::UnitZ(), -0.15f};
  const TsdfVolume volume =
      FillExact([&](const Eigen::Vector3f& p) { return std::min(sheet.Sdf(p), floor.Sdf(p)); },
                Eigen::Vector3f(-0.6f, -0.6f, -0.2f), Eigen::Vector3f(0.6f, 0.6f, 0.1f));
  const PinholeCamera cam = TestCamera(160, 120);
  for (const float tilt_deg : {0.f, 35.f, 60.f, 72.f}) {
    const float tilt = tilt_deg * float(M_PI) / 180.f, azimuth = 0.4f + tilt;
    const Eigen::Vector3f eye =
        0.8f * Eigen::Vector3f(std::sin(tilt) * std::cos(azimuth),
                               std::sin(tilt) * std::sin(azimuth), std::cos(tilt));
    const Pose3f T_W_C = LookAt(eye, Eigen::Vector3f(0.01f, 0.02f, 0.f));
    const RaycastImages images = Raycast(volume, cam, T_W_C);
    const DepthImage on_sheet = test::RenderDepth(sheet, cam, T_W_C);
    // Behind: a hit past the sheet (the floor). Off: no hit or not on the sheet, allowed at a
    // few pixels where the interpolant bends around the sheet's edges.
    size_t checked = 0, behind = 0, off = 0;
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        if (!Interior(on_sheet, u, v, 2)) continue;
        ++checked;
        const bool hit = images.status.at(u, v) == uint8_t(RayStatus::kHit);
        const float error_m = images.depth.at(u, v) - on_sheet.at(u, v);
        behind += hit && error_m > kVoxel;
        off += !hit || std::abs(error_m) > kVoxel;
      }
    SCOPED_TRACE(tilt_deg);
    EXPECT_GT(checked, 500u);
    EXPECT_EQ(behind, 0u);
    EXPECT_LE(double(off), 0.01 * double(checked));
  }
}

TEST(Raycast, DeepNegativeBandsKeepTheirFrontSurface) {
  // A solid box whose negative band is 12 voxels deep: the range image leaves out the bricks
  // behind others on the camera's side. Were that test on the wrong side (or across block
  // faces), rays would start behind the front surface and miss it. Seen from its faces, edges
  // and corners, from far and from near (inside a face's slab). Each face's first negative
  // voxels are the first or last layer of their blocks (8 cm), so the neighbours that face the
  // camera lie in the next block.
  const Box box{Eigen::Vector3f(-0.158f, -0.157f, -0.077f),
                Eigen::Vector3f(0.158f, 0.157f, 0.158f)};
  const TsdfVolume volume = test::FillExactSdf(
      [&](const Eigen::Vector3f& p) { return box.Sdf(p); }, {kVoxel, 12 * kVoxel},
      box.lo - Eigen::Vector3f::Constant(0.2f), box.hi + Eigen::Vector3f::Constant(0.2f));
  const PinholeCamera cam = TestCamera(160, 120);
  const Eigen::Vector3f centre = 0.5f * (box.lo + box.hi);
  size_t views = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy && !dz) continue;
        const Eigen::Vector3f dir = Eigen::Vector3f(float(dx), float(dy), float(dz)).normalized();
        for (const float distance_m : {0.36f, 0.75f}) {
          // Off-centre, so that the near views look along a face rather than at the centre.
          const Eigen::Vector3f eye =
              centre + distance_m * dir + Eigen::Vector3f(0.013f, 0.021f, -0.017f);
          const Pose3f T_W_C = LookAt(eye, centre + Eigen::Vector3f(0.03f, -0.02f, 0.01f));
          const RaycastImages images = Raycast(volume, cam, T_W_C);
          const DepthImage truth = test::RenderDepth(box, cam, T_W_C);
          size_t checked = 0, off = 0;
          for (int v = 0; v < cam.height; ++v)
            for (int u = 0; u < cam.width; ++u) {
              // Nearer than min_depth_m (and a margin): not reported.
              if (!Interior(truth, u, v, 2) || truth.at(u, v) < 0.12f) continue;
              // Rays grazing a face (beyond 75 degrees) may pass it: the march cannot tell
              // such a crossing from noise.
              const Eigen::Vector3f ray_W =
                  T_W_C.linear() * cam.Unproject(float(u), float(v), 1.f).normalized();
              const Eigen::Vector3f p = T_W_C * cam.Unproject(float(u), float(v), truth.at(u, v));
              float cos_incidence = 1.f;
              for (int a = 0; a < 3; ++a)
                if (std::min(std::abs(p[a] - box.lo[a]), std::abs(p[a] - box.hi[a])) < 1e-3f)
                  cos_incidence = std::min(cos_incidence, std::abs(ray_W[a]));
              if (cos_incidence < std::cos(75.f * float(M_PI) / 180.f)) continue;
              ++checked;
              off += images.status.at(u, v) != uint8_t(RayStatus::kHit) ||
                     std::abs(images.depth.at(u, v) - truth.at(u, v)) > kVoxel;
            }
          SCOPED_TRACE(testing::Message()
                       << "view " << dx << " " << dy << " " << dz << " at " << distance_m << " m");
          EXPECT_GT(checked, 1500u);
          // A pixel or two where two faces meet; a bound behind the front face misses regions.
          EXPECT_LE(off, checked / 500);
          ++views;
        }
      }
  EXPECT_EQ(views, 52u);
}

// A wall at x = 0.5 seen head-on from the origin, its whole neighbourhood allocated.
struct Wall {
  Plane plane{Eigen::Vector3f(-1.f, 0.f, 0.f), -0.5f};  // free space at x < 0.5
  Pose3f T_W_C = LookAt(Eigen::Vector3f(0.f, 0.01f, 0.02f), Eigen::Vector3f(1.f, 0.01f, 0.02f));
  PinholeCamera cam = TestCamera(80, 60);
  TsdfVolume volume = FillExact([this](const Eigen::Vector3f& p) { return plane.Sdf(p); },
                                Eigen::Vector3f(0.2f, -0.4f, -0.4f),
                                Eigen::Vector3f(0.6f, 0.4f, 0.4f), /*all_blocks=*/true);
};

TEST(Raycast, UnobservedGapInFrontOfTheSurfaceStopsNothing) {
  Wall wall;
  const RaycastImages before = Raycast(wall.volume, wall.cam, wall.T_W_C);
  // Unobserve a slab from 20 cm to 6 voxels in front of the wall, and drop one whole block
  // column in front of it, so rays cross both unobserved voxels and unallocated blocks.
  wall.volume.ForEachBlock([&](BlockIndex b, const TsdfBlock&) {
    TsdfBlock& data = *wall.volume.FindBlock(b);
    for (int i = 0; i < kBlockVoxels; ++i) {
      const float x = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), kVoxel).x();
      if (x > 0.2f && x < 0.5f - 6 * kVoxel) data.weight[i] = 0;
    }
  });
  const float block = kVoxel * kBlockSide;
  for (int by = -4; by <= 4; ++by)
    for (int bz = -4; bz <= 4; ++bz) wall.volume.EraseBlock(BlockIndex{int(0.45f / block), by, bz});
  const RaycastImages after = Raycast(wall.volume, wall.cam, wall.T_W_C);
  const DepthImage truth = test::RenderDepth(wall.plane, wall.cam, wall.T_W_C);
  for (int v = 0; v < wall.cam.height; ++v)
    for (int u = 0; u < wall.cam.width; ++u) {
      ASSERT_EQ(after.status.at(u, v), uint8_t(RayStatus::kHit)) << u << " " << v;
      EXPECT_NEAR(after.depth.at(u, v), truth.at(u, v), kMaxDepthVox * kVoxel);
      EXPECT_NEAR(after.depth.at(u, v), before.depth.at(u, v), 1e-5f);
    }
}

TEST(Raycast, FreeAndUnobservedStatus) {
  // Observed free space only: a cube of +1 voxels in front of the camera, nothing elsewhere.
  TsdfVolume volume({kVoxel, kTrunc});
  for (int x = 2; x <= 5; ++x)
    for (int y = -1; y <= 0; ++y)
      for (int z = -1; z <= 0; ++z) {
        TsdfBlock& data = volume.FindOrAllocate(BlockIndex{x, y, z});
        for (int i = 0; i < kBlockVoxels; ++i) data.weight[i] = EncodeWeight(1.f);
      }
  const PinholeCamera cam = TestCamera(80, 60);
  const Pose3f T_W_C = LookAt(Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitX());
  const RaycastImages images = Raycast(volume, cam, T_W_C);
  EXPECT_EQ(Count(images, RayStatus::kHit), 0u);
  EXPECT_EQ(images.status.at(cam.width / 2, cam.height / 2), uint8_t(RayStatus::kFree));
  EXPECT_EQ(images.status.at(0, 0), uint8_t(RayStatus::kUnobserved));
  EXPECT_GT(Count(images, RayStatus::kFree), 100u);
  EXPECT_GT(Count(images, RayStatus::kUnobserved), 100u);

  // The same blocks left unobserved (weight below min_weight) are unobserved space.
  RaycastParams params;
  params.min_weight = 2.f;
  EXPECT_EQ(Count(Raycast(volume, cam, T_W_C, params), RayStatus::kUnobserved),
            size_t(cam.width) * size_t(cam.height));
  // An empty volume: nothing observed anywhere.
  EXPECT_EQ(Count(Raycast(TsdfVolume({kVoxel, kTrunc}), cam, T_W_C), RayStatus::kUnobserved),
            size_t(cam.width) * size_t(cam.height));
}

TEST(Raycast, CameraInsideASolidSeesOnlyBackFaces) {
  const Sphere sphere{Eigen::Vector3f(0.f, 0.f, 0.f), 0.3f};
  const TsdfVolume volume =
      FillExact([&](const Eigen::Vector3f& p) { return sphere.Sdf(p); },
                Eigen::Vector3f::Constant(-0.45f), Eigen::Vector3f::Constant(0.45f));
  const RaycastImages images = Raycast(volume, TestCamera(80, 60),
                                       LookAt(Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitX()));
  EXPECT_EQ(Count(images, RayStatus::kHit), 0u);
  EXPECT_EQ(Count(images, RayStatus::kFree), images.status.data.size());
}

TEST(Raycast, DepthLimitsAreRespected) {
  const Sphere sphere{Eigen::Vector3f(1.2f, 0.f, 0.f), 0.3f};  // front at 0.9 m, back at 1.5 m
  const TsdfVolume volume = FillExact([&](const Eigen::Vector3f& p) { return sphere.Sdf(p); },
                                      sphere.c - Eigen::Vector3f::Constant(0.45f),
                                      sphere.c + Eigen::Vector3f::Constant(0.45f));
  const PinholeCamera cam = TestCamera(80, 60);
  const Pose3f T_W_C = LookAt(Eigen::Vector3f::Zero(), sphere.c);
  const size_t pixels = size_t(cam.width) * size_t(cam.height);
  RaycastParams params;
  const RaycastImages full = Raycast(volume, cam, T_W_C, params);
  const size_t all_hits = Count(full, RayStatus::kHit);
  ASSERT_GT(all_hits, 500u);

  params.max_depth_m = 0.85f;  // in front of the sphere
  EXPECT_EQ(Count(Raycast(volume, cam, T_W_C, params), RayStatus::kHit), 0u);

  params.max_depth_m = 0.95f;  // cuts through the cap: only the nearest points remain
  const RaycastImages capped = Raycast(volume, cam, T_W_C, params);
  const size_t cap_hits = Count(capped, RayStatus::kHit);
  EXPECT_GT(cap_hits, 0u);
  EXPECT_LT(cap_hits, all_hits);
  for (size_t i = 0; i < pixels; ++i)
    if (capped.status.data[i] == uint8_t(RayStatus::kHit)) {
      EXPECT_LE(capped.depth.data[i], params.max_depth_m);
      EXPECT_EQ(capped.depth.data[i], full.depth.data[i]);
    }

  params.max_depth_m = 5.f;
  params.min_depth_m = 0.95f;  // cuts the cap: rays starting inside meet only the back face
  const RaycastImages inside = Raycast(volume, cam, T_W_C, params);
  // Grazing rays may clip less than a voxel of the solid; compare away from the silhouette.
  const DepthImage truth = test::RenderDepth(sphere, cam, T_W_C);
  size_t near_cut = 0, beyond_cut = 0;
  for (size_t i = 0; i < pixels; ++i) {
    const int u = int(i % size_t(cam.width)), v = int(i / size_t(cam.width));
    if (full.status.data[i] != uint8_t(RayStatus::kHit) || !Interior(truth, u, v, 2)) continue;
    const bool hit = inside.status.data[i] == uint8_t(RayStatus::kHit);
    if (full.depth.data[i] < params.min_depth_m - kVoxel) {
      ++near_cut;
      EXPECT_FALSE(hit) << "surface in front of min_depth";
    } else if (full.depth.data[i] > params.min_depth_m + kVoxel) {
      ++beyond_cut;
      EXPECT_TRUE(hit);
      EXPECT_NEAR(inside.depth.data[i], full.depth.data[i], 0.01f * kVoxel);
    }
  }
  EXPECT_GT(near_cut, 20u);
  EXPECT_GT(beyond_cut, 20u);
}

TEST(Raycast, OneAndTwoThreadsGiveIdenticalBytes) {
  const Sphere sphere{Eigen::Vector3f(0.f, 0.f, 0.f), 0.3f};
  const Box box{Eigen::Vector3f(-0.6f, -0.6f, -0.5f), Eigen::Vector3f(0.6f, 0.6f, -0.4f)};
  const TsdfVolume volume =
      FillExact([&](const Eigen::Vector3f& p) { return std::min(sphere.Sdf(p), box.Sdf(p)); },
                Eigen::Vector3f(-0.7f, -0.7f, -0.6f), Eigen::Vector3f(0.7f, 0.7f, 0.4f));
  const PinholeCamera cam = TestCamera(320, 240);
  const Pose3f T_W_C = LookAt(Eigen::Vector3f(0.9f, 0.7f, 0.6f), Eigen::Vector3f::Zero());
  RaycastImages one, two;
  {
    ThreadLimit limit(1);
    one = Raycast(volume, cam, T_W_C);
  }
  {
    ThreadLimit limit(2);
    two = Raycast(volume, cam, T_W_C);
  }
  ASSERT_GT(Count(one, RayStatus::kHit), 10000u);
  test::ExpectSameImages(one, two);

  // Reusing images gives the same bytes again.
  RaycastImages reused = one;
  Raycast(volume, cam, T_W_C, {}, reused);
  test::ExpectSameImages(one, reused);

  // Images start on a cache line, copies too, so at this width every tile row of depth, colour,
  // vertices and normals is whole lines: the rows written with streaming stores above.
  for (const RaycastImages* images : {&one, &reused}) {
    for (const void* p : {static_cast<const void*>(images->depth.data.data()),
                          static_cast<const void*>(images->color.data.data()),
                          static_cast<const void*>(images->vertex_W.data.data()),
                          static_cast<const void*>(images->normal_W.data.data()),
                          static_cast<const void*>(images->status.data.data())})
      EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % 64, 0u);
  }
}

// The AVX2 packet march (crossings refined eight at a time in AVX2 lanes) against the scalar
// reference march on a noisy volume (random TSDF noise, unobserved voxels, varied colour), from
// outside and from inside a solid, with and without stopping at back faces, under a raised
// minimum weight and without colour and normals: the same bytes.
TEST(Raycast, PacketMarchMatchesTheScalarMarchExactly) {
  if (!RaycastSimdAvailable()) GTEST_SKIP() << "no AVX2 packets here: only the scalar march runs";
  const Sphere sphere{Eigen::Vector3f(0.f, 0.f, 0.f), 0.3f};
  const Box box{Eigen::Vector3f(-0.6f, -0.6f, -0.5f), Eigen::Vector3f(0.6f, 0.6f, -0.4f)};
  TsdfVolume volume =
      FillExact([&](const Eigen::Vector3f& p) { return std::min(sphere.Sdf(p), box.Sdf(p)); },
                Eigen::Vector3f(-0.7f, -0.7f, -0.6f), Eigen::Vector3f(0.7f, 0.7f, 0.4f));
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, 0.15f);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<BlockIndex> blocks;
  volume.ForEachBlock([&](BlockIndex b, const TsdfBlock&) { blocks.push_back(b); });
  std::sort(blocks.begin(), blocks.end(), [](BlockIndex a, BlockIndex b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  for (BlockIndex b : blocks) {
    TsdfBlock& block = *volume.FindBlock(b);
    for (int i = 0; i < kBlockVoxels; ++i) {
      block.tsdf[i] = EncodeTsdf(DecodeTsdf(block.tsdf[i]) + noise(rng));
      if (byte(rng) < 13)
        block.weight[i] = 0;  // about 5 % unobserved
      else if (byte(rng) < 13)
        block.weight[i] = EncodeWeight(1.f);  // below a raised minimum
      block.r[i] = uint8_t(byte(rng)), block.g[i] = uint8_t(byte(rng)),
      block.b[i] = uint8_t(byte(rng));
    }
  }
  const PinholeCamera cam = TestCamera(160, 120);
  size_t hits = 0, misses = 0;
  for (const Eigen::Vector3f& eye :
       {Eigen::Vector3f(0.9f, 0.7f, 0.6f), Eigen::Vector3f(0.05f, 0.f, 0.f)})
    for (const int variant : {0, 1, 2, 3}) {
      const Pose3f T_W_C = LookAt(eye, Eigen::Vector3f(0.f, 0.f, -0.3f));
      RaycastParams packet_params;
      packet_params.stop_at_back_faces = variant != 1;
      if (variant == 2) packet_params.min_weight = 1.5f;
      if (variant == 3) packet_params.with_color = packet_params.with_normals = false;
      RaycastParams scalar_params = packet_params;
      scalar_params.simd = false;
      const RaycastImages scalar = Raycast(volume, cam, T_W_C, scalar_params);
      const RaycastImages packets = Raycast(volume, cam, T_W_C, packet_params);
      test::ExpectSameImages(scalar, packets);
      hits += Count(scalar, RayStatus::kHit);
      misses += Count(scalar, RayStatus::kFree) + Count(scalar, RayStatus::kUnobserved);
    }
  EXPECT_GT(hits, 20000u);
  EXPECT_GT(misses, 5000u);
}

TEST(Raycast, ColourAndNormalsCanBeSkipped) {
  const Sphere sphere{Eigen::Vector3f(0.f, 0.f, 0.f), 0.3f};
  const TsdfVolume volume =
      FillExact([&](const Eigen::Vector3f& p) { return sphere.Sdf(p); },
                Eigen::Vector3f::Constant(-0.45f), Eigen::Vector3f::Constant(0.45f));
  const PinholeCamera cam = TestCamera(80, 60);
  const Pose3f T_W_C = LookAt(Eigen::Vector3f(0.9f, 0.3f, 0.2f), Eigen::Vector3f::Zero());
  const RaycastImages full = Raycast(volume, cam, T_W_C);
  RaycastParams params;
  params.with_color = false;
  params.with_normals = false;
  const RaycastImages bare = Raycast(volume, cam, T_W_C, params);
  ASSERT_GT(Count(full, RayStatus::kHit), 1000u);
  for (size_t i = 0; i < full.status.data.size(); ++i) {
    EXPECT_EQ(bare.status.data[i], full.status.data[i]);
    EXPECT_EQ(bare.depth.data[i], full.depth.data[i]);
    EXPECT_EQ(bare.color.data[i], 0u);
    EXPECT_TRUE(bare.normal_W.data[i].array().isNaN().all());
  }
}

TEST(Raycast, InvalidInputsGiveEmptyOrUnobservedImages) {
  const Sphere sphere{Eigen::Vector3f(0.f, 0.f, 0.f), 0.3f};
  const TsdfVolume volume =
      FillExact([&](const Eigen::Vector3f& p) { return sphere.Sdf(p); },
                Eigen::Vector3f::Constant(-0.45f), Eigen::Vector3f::Constant(0.45f));
  PinholeCamera bad = TestCamera(80, 60);
  bad.fx = 0.f;
  EXPECT_TRUE(Raycast(volume, bad, Pose3f::Identity()).status.empty());
  Pose3f nan_pose = LookAt(Eigen::Vector3f(1.f, 0.f, 0.f), Eigen::Vector3f::Zero());
  nan_pose.translation().x() = std::numeric_limits<float>::quiet_NaN();
  const RaycastImages images = Raycast(volume, TestCamera(80, 60), nan_pose);
  EXPECT_EQ(Count(images, RayStatus::kUnobserved), images.status.data.size());
}

// The caster's SSE2 kernels against their scalar references (core/raycast/raycast_kernels.h).
namespace kernels = raycast_detail;

TsdfBlock RandomBlock(std::mt19937& rng) {
  TsdfBlock block;
  std::uniform_int_distribution<int> tsdf(-32767, 32767), weight(0, 65535), colour(0, 255);
  for (int i = 0; i < kBlockVoxels; ++i) {
    block.tsdf[i] = int16_t(tsdf(rng));
    block.weight[i] = uint16_t(i % 7 == 0 ? 0 : weight(rng));  // some never observed
    block.r[i] = uint8_t(colour(rng));
    block.g[i] = uint8_t(colour(rng));
    block.b[i] = uint8_t(colour(rng));
  }
  return block;
}

// Every cell base inside a block (local coordinates < 7 on each axis).
std::vector<int> InnerCellBases() {
  std::vector<int> bases;
  for (int z = 0; z < kBlockMask; ++z)
    for (int y = 0; y < kBlockMask; ++y)
      for (int x = 0; x < kBlockMask; ++x) bases.push_back(LinearIndex(x, y, z));
  return bases;
}

TEST(RaycastKernels, CornerLoadsMatchTheScalarReferenceExactly) {
#if !VOXPLAN_RAYCAST_SSE2
  GTEST_SKIP() << "no SSE2 kernels in this build";
#else
  std::mt19937 rng(7);
  const TsdfBlock block = RandomBlock(rng);
  for (const uint32_t min_weight : {1u, 64u, 32768u, 65535u, 65536u})
    for (const int i0 : InnerCellBases()) {
      float scalar[8], simd[8];
      const uint8_t observed = kernels::LoadCornersScalar(block, i0, min_weight, scalar);
      ASSERT_EQ(kernels::LoadCornersSse2(block, i0, min_weight, simd), observed) << i0;
      for (int k = 0; k < 8; ++k) {
        ASSERT_EQ(simd[k], scalar[k]) << i0 << " corner " << k;
        // Corner k is voxel base + (k & 1, (k >> 1) & 1, k >> 2).
        const int i =
            i0 + (k & 1) + ((k >> 1) & 1) * kBlockSide + (k >> 2) * kBlockSide * kBlockSide;
        EXPECT_EQ(scalar[k], DecodeTsdf(block.tsdf[i]));
        EXPECT_EQ(bool(observed & (1 << k)), block.weight[i] >= min_weight);
      }
    }
#endif
}

TEST(RaycastKernels, CornerLoadsAcrossBlocksMatchTheScalarReferenceExactly) {
#if !VOXPLAN_RAYCAST_SSE2
  GTEST_SKIP() << "no SSE2 kernels in this build";
#else
  std::mt19937 rng(11);
  const TsdfBlock blocks[3] = {RandomBlock(rng), RandomBlock(rng), RandomBlock(rng)};
  std::uniform_int_distribution<int> which(0, 2), voxel(0, kBlockVoxels - 1);
  for (const uint32_t min_weight : {1u, 64u, 32768u, 65535u, 65536u})
    for (int trial = 0; trial < 500; ++trial) {
      const TsdfBlock* block[8];
      int index[8];
      for (int k = 0; k < 8; ++k) block[k] = &blocks[which(rng)], index[k] = voxel(rng);
      float scalar[8], simd[8];
      const uint8_t observed = kernels::LoadCornersAcrossScalar(block, index, min_weight, scalar);
      ASSERT_EQ(kernels::LoadCornersAcrossSse2(block, index, min_weight, simd), observed);
      for (int k = 0; k < 8; ++k) {
        ASSERT_EQ(simd[k], scalar[k]) << "corner " << k;
        EXPECT_EQ(scalar[k], DecodeTsdf(block[k]->tsdf[index[k]]));
        EXPECT_EQ(bool(observed & (1 << k)), block[k]->weight[index[k]] >= min_weight);
      }
    }
#endif
}

// Rounding of 4-term sums of values in [-1, 1] taken in another order.
constexpr float kSumRounding = 1e-6f;

TEST(RaycastKernels, TrilinearValueAndGradientAreExactOnALinearFunction) {
  // f = a + g . (corner offset): the interpolant is f itself and its gradient g everywhere.
  const float a = 0.125f;
  const Eigen::Vector3f g(0.25f, -0.375f, 0.0625f);
  float t[8];
  for (int k = 0; k < 8; ++k)
    t[k] = a + g.x() * float(k & 1) + g.y() * float((k >> 1) & 1) + g.z() * float(k >> 2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (int n = 0; n < 200; ++n) {
    const float frac[4] = {unit(rng), unit(rng), unit(rng), 0.f};
    const float expected = a + g.x() * frac[0] + g.y() * frac[1] + g.z() * frac[2];
    float gradient[3];
    EXPECT_NEAR(kernels::ValueAndGradientScalar(t, frac, gradient), expected, kSumRounding);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(gradient[i], g[i], kSumRounding);
#if VOXPLAN_RAYCAST_SSE2
    EXPECT_NEAR(kernels::ValueAndGradientSse2(t, frac, gradient), expected, kSumRounding);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(gradient[i], g[i], kSumRounding);
#endif
  }
}

TEST(RaycastKernels, ValueAndGradientMatchTheScalarReference) {
#if !VOXPLAN_RAYCAST_SSE2
  GTEST_SKIP() << "no SSE2 kernels in this build";
#else
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.f, 1.f), value(-1.f, 1.f);
  for (int n = 0; n < 2000; ++n) {
    float t[8];
    for (float& v : t) v = value(rng);
    // Corners and faces too: frac exactly 0 or 1.
    const float frac[4] = {n % 5 == 0 ? 0.f : unit(rng), n % 7 == 0 ? 1.f : unit(rng), unit(rng),
                           0.f};
    float scalar_gradient[3], simd_gradient[3];
    const float scalar = kernels::ValueAndGradientScalar(t, frac, scalar_gradient);
    EXPECT_NEAR(kernels::ValueAndGradientSse2(t, frac, simd_gradient), scalar, kSumRounding);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(simd_gradient[i], scalar_gradient[i], kSumRounding);
  }
#endif
}

// Colour channels are rounded to integers after a weighted mean summed in another order.
constexpr int kColourRoundingLevels = 1;

TEST(RaycastKernels, ColourBlendsMatchTheScalarReference) {
#if !VOXPLAN_RAYCAST_SSE2
  GTEST_SKIP() << "no SSE2 kernels in this build";
#else
  std::mt19937 rng(11);
  const TsdfBlock block = RandomBlock(rng);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  size_t checked = 0, identical = 0;
  auto near = [](uint32_t a, uint32_t b) {
    for (int shift = 0; shift < 24; shift += 8)
      if (std::abs(int((a >> shift) & 255) - int((b >> shift) & 255)) > kColourRoundingLevels)
        return false;
    return (a >> 24) == 0 && (b >> 24) == 0;
  };
  for (const int i0 : InnerCellBases())
    for (int n = 0; n < 4; ++n) {
      const float frac[4] = {unit(rng), unit(rng), unit(rng), 0.f};
      const uint32_t scalar = kernels::BlendColorScalar(block, i0, frac);
      const uint32_t simd = kernels::BlendColorSse2(block, i0, frac);
      EXPECT_TRUE(near(simd, scalar)) << i0 << ": " << simd << " vs " << scalar;
      // The same corners given as arrays.
      uint8_t r[8], g[8], b[8];
      for (int k = 0; k < 8; ++k) {
        r[k] = block.r[i0 + kernels::kCornerOffset[k]];
        g[k] = block.g[i0 + kernels::kCornerOffset[k]];
        b[k] = block.b[i0 + kernels::kCornerOffset[k]];
      }
      EXPECT_EQ(kernels::BlendCornerColorsScalar(r, g, b, frac), scalar);
      EXPECT_EQ(kernels::BlendCornerColorsSse2(r, g, b, frac), simd);
      ++checked;
      identical += simd == scalar;
    }
  // Off by one only where a channel's mean lies within rounding of a half.
  EXPECT_GT(identical, checked * 95 / 100);
  // A uniform colour blends to itself at any position.
  TsdfBlock uniform = block;
  std::fill(std::begin(uniform.r), std::end(uniform.r), uint8_t(200));
  std::fill(std::begin(uniform.g), std::end(uniform.g), uint8_t(13));
  std::fill(std::begin(uniform.b), std::end(uniform.b), uint8_t(255));
  const float frac[4] = {0.3f, 0.9f, 0.5f, 0.f};
  EXPECT_EQ(kernels::BlendColorSse2(uniform, LinearIndex(2, 3, 4), frac), PackRgb(200, 13, 255));
  EXPECT_EQ(kernels::BlendColorScalar(uniform, LinearIndex(2, 3, 4), frac), PackRgb(200, 13, 255));
#endif
}

}  // namespace
}  // namespace voxplan
