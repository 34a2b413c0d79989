// Free-space carving: blocks in front of the band are allocated and carved, the touched-block
// list, the coverage of the subsampled carving rays, clearing by readings beyond the range, and
// scalar vs SIMD parity with carving on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "core/parallel.h"
#include "core/voxel_state.h"
#include "fusion/integrate.h"
#include "tests/fusion/box_room.h"

namespace voxplan {
namespace {

constexpr float kVoxel = 0.05f;
constexpr float kTrunc = 0.15f;
const test::BoxRoom kRoom{Eigen::Vector3f(-1.49f, -1.29f, -0.99f),
                          Eigen::Vector3f(1.49f, 1.29f, 0.99f)};
const Eigen::Vector3f kEye(0.02f, 0.03f, 0.01f);

IntegrateParams CarveParams() {
  IntegrateParams p;
  p.max_depth_m = 4.0f;
  p.carve_free_space = true;
  return p;
}

// A Kinect-like 640x480 camera: carving rays then go one per 13x13-pixel tile at 5 cm voxels.
PinholeCamera Vga() {
  PinholeCamera cam;
  cam.width = 640;
  cam.height = 480;
  cam.fx = cam.fy = 525.f;
  cam.cx = 319.5f;
  cam.cy = 239.5f;
  return cam;
}

bool Observed(const TsdfVolume& v, GlobalVoxelIndex g) {
  const TsdfBlock* b = v.FindBlock(BlockOf(g));
  return b && b->weight[LinearIndex(LocalOf(g))] > 0;
}

TEST(Carving, CarvesTheInteriorOnlyWhenAsked) {
  const PinholeCamera cam = test::RoomCamera();
  const Pose3f pose = test::AxisViews(kEye)[0];
  const DepthImage depth = test::RenderRoomDepth(kRoom, cam, pose);
  const GlobalVoxelIndex middle = VoxelAt(Eigen::Vector3f(0.7f, 0.1f, 0.05f), kVoxel);
  for (bool carve : {false, true}) {
    TsdfVolume volume({kVoxel, kTrunc});
    IntegrateParams params = CarveParams();
    params.carve_free_space = carve;
    auto stats = IntegrateFrame(depth, {}, cam, pose, params, volume);
    ASSERT_TRUE(stats.ok());
    EXPECT_EQ(Observed(volume, middle), carve);
    if (carve) {
      const TsdfBlock* b = volume.FindBlock(BlockOf(middle));
      const int i = LinearIndex(LocalOf(middle));
      EXPECT_EQ(b->tsdf[i], int16_t(kTsdfScale));  // truncated +1
      EXPECT_EQ(ClassifyVoxel(b->tsdf[i], b->weight[i], kTrunc / kVoxel, {}), VoxelState::kFree);
    }
    // The frame's touched blocks are what it allocated: sorted, unique, all in the volume.
    EXPECT_EQ(stats->touched_blocks, volume.SortedBlockIndices());
    EXPECT_EQ(stats->blocks_in_band, stats->touched_blocks.size());
  }
}

TEST(Carving, TouchedBlocksOfALaterFrameIncludeTheBand) {
  const PinholeCamera cam = test::RoomCamera();
  const std::vector<Pose3f> views = test::AxisViews(kEye);
  TsdfVolume volume({kVoxel, kTrunc});
  const IntegrateParams params = CarveParams();
  ASSERT_TRUE(
      IntegrateFrame(test::RenderRoomDepth(kRoom, cam, views[0]), {}, cam, views[0], params, volume)
          .ok());
  const DepthImage depth = test::RenderRoomDepth(kRoom, cam, views[2]);
  auto stats = IntegrateFrame(depth, {}, cam, views[2], params, volume);
  ASSERT_TRUE(stats.ok());
  const auto& touched = stats->touched_blocks;
  EXPECT_TRUE(std::is_sorted(touched.begin(), touched.end()));
  EXPECT_EQ(std::adjacent_find(touched.begin(), touched.end()), touched.end());
  const auto band = BlocksInTruncationBand(depth, cam, views[2], params, volume.params());
  EXPECT_TRUE(std::includes(touched.begin(), touched.end(), band.begin(), band.end()));
  EXPECT_GT(touched.size(), band.size());
  EXPECT_EQ(touched, BlocksToUpdate(depth, cam, views[2], params, volume.params()));
}

// Subsampled carving rays against every block of the room allocated up front: the carved map
// misses few of the voxels the frames observe.
TEST(Carving, TileRaysReachNearlyEveryVoxelTheFrameObserves) {
  const PinholeCamera cam = Vga();
  const IntegrateParams params = CarveParams();
  TsdfVolume carved({kVoxel, kTrunc}), full({kVoxel, kTrunc});
  const float block = kVoxel * kBlockSide;
  const BlockIndex lo = BlockAt(kRoom.lo - Eigen::Vector3f::Constant(0.3f), block);
  const BlockIndex hi = BlockAt(kRoom.hi + Eigen::Vector3f::Constant(0.3f), block);
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) full.FindOrAllocate({x, y, z});
  // Tilted views so tile rays cross block faces at odd angles.
  for (const Eigen::Vector3f& target :
       {Eigen::Vector3f(1.f, 0.3f, -0.2f), Eigen::Vector3f(-0.4f, 1.f, 0.3f)}) {
    const Pose3f pose = LookAt(kEye, target);
    const DepthImage depth = test::RenderRoomDepth(kRoom, cam, pose);
    ASSERT_TRUE(IntegrateFrame(depth, {}, cam, pose, params, carved).ok());
    IntegrateParams no_alloc = params;
    no_alloc.carve_free_space = false;  // `full` has every block already
    ASSERT_TRUE(IntegrateFrame(depth, {}, cam, pose, no_alloc, full).ok());
  }
  // A voxel is missed when the carved map lacks its block, or lacks it for one of the frames
  // (then its bytes differ).
  size_t observed = 0, missed = 0;
  full.ForEachBlock([&](BlockIndex b, const TsdfBlock& fb) {
    const TsdfBlock* cb = carved.FindBlock(b);
    for (int i = 0; i < kBlockVoxels; ++i) {
      if (fb.weight[i] == 0) continue;
      ++observed;
      missed += !cb || cb->tsdf[i] != fb.tsdf[i] || cb->weight[i] != fb.weight[i];
    }
  });
  EXPECT_GT(observed, 15000u);
  // Only voxels of blocks that the frustum grazes between two tile rays are lost.
  EXPECT_LE(double(missed), 0.002 * double(observed)) << missed << " of " << observed;
}

TEST(Carving, ScalarAndSimdKernelsAgreeBitForBit) {
  if (!SimdKernelAvailable()) GTEST_SKIP() << "no AVX2 on this CPU";
  const PinholeCamera cam = test::RoomCamera(120);
  // The last case cuts the room with its range: readings on both sides of it, the far ones
  // clearing.
  for (int c = 0; c < 3; ++c) {
    const Weighting weighting = c == 1 ? Weighting::kDepthDependent : Weighting::kConstant;
    TsdfVolume scalar({kVoxel, kTrunc}), simd({kVoxel, kTrunc});
    IntegrateParams params = CarveParams();
    params.weighting = weighting;
    if (c == 2) {
      params.max_depth_m = 1.3f;
      params.clear_beyond_max_depth = true;
    }
    for (const Pose3f& pose : test::AxisViews(kEye)) {
      DepthImage depth = test::RenderRoomDepth(kRoom, cam, pose);
      for (size_t i = 0; i < depth.data.size(); i += 37) depth.data[i] = 0.f;  // dropouts
      ColorImage color(cam.width, cam.height);
      for (size_t i = 0; i < color.data.size(); ++i) color.data[i] = uint32_t(i * 2654435761u);
      params.kernel = Kernel::kScalar;
      ASSERT_TRUE(IntegrateFrame(depth, color, cam, pose, params, scalar).ok());
      params.kernel = Kernel::kSimd;
      ASSERT_TRUE(IntegrateFrame(depth, color, cam, pose, params, simd).ok());
    }
    ASSERT_EQ(scalar.SortedBlockIndices(), simd.SortedBlockIndices());
    scalar.ForEachBlock([&](BlockIndex b, const TsdfBlock& sb) {
      EXPECT_EQ(std::memcmp(&sb, simd.FindBlock(b), sizeof(TsdfBlock)), 0);
    });
  }
}

// Every wall of kRoom lies at least 0.89 m (z-depth) from kEye: with a 0.8 m range a frame sees
// nothing to fuse, only free space in front of the range, and only when readings beyond the range
// clear.
TEST(Carving, ReadingsBeyondMaxDepthClearFreeSpaceInFrontOfIt) {
  const PinholeCamera cam = test::RoomCamera();
  const Pose3f pose = test::AxisViews(kEye)[0];  // along +x
  const DepthImage depth = test::RenderRoomDepth(kRoom, cam, pose);
  ColorImage color(cam.width, cam.height, 0x00ffffffu);
  const GlobalVoxelIndex ahead = VoxelAt(Eigen::Vector3f(0.5f, 0.03f, 0.01f), kVoxel);
  for (bool clear : {false, true}) {
    TsdfVolume volume({kVoxel, kTrunc});
    IntegrateParams params = CarveParams();
    params.max_depth_m = 0.8f;
    params.clear_beyond_max_depth = clear;
    ASSERT_TRUE(IntegrateFrame(depth, color, cam, pose, params, volume).ok());
    EXPECT_EQ(Observed(volume, ahead), clear);
    size_t observed = 0;
    const Pose3f T_C_W = pose.inverse();
    volume.ForEachBlock([&](BlockIndex b, const TsdfBlock& block) {
      for (int i = 0; i < kBlockVoxels; ++i) {
        if (block.weight[i] == 0) continue;
        ++observed;
        // Free and colourless: a reading beyond the range is no surface, and nothing beyond
        // the range is touched.
        EXPECT_EQ(block.tsdf[i], int16_t(kTsdfScale));
        EXPECT_EQ(block.r[i] | block.g[i] | block.b[i], 0);
        const VoxelIndex local{i & kBlockMask, (i >> kBlockShift) & kBlockMask,
                               i >> (2 * kBlockShift)};
        const Eigen::Vector3f p_W = VoxelCenter(GlobalOf(b, local), kVoxel);
        EXPECT_LE((T_C_W * p_W).z(), params.max_depth_m + 1e-4f);
      }
    });
    EXPECT_EQ(observed > 0, clear);
  }
  // Readings that are not finite distances clear nothing.
  for (float bad : {std::numeric_limits<float>::infinity(), std::nanf("")}) {
    TsdfVolume volume({kVoxel, kTrunc});
    IntegrateParams params = CarveParams();
    params.max_depth_m = 0.8f;
    params.clear_beyond_max_depth = true;
    const DepthImage bad_depth(cam.width, cam.height, bad);
    ASSERT_TRUE(IntegrateFrame(bad_depth, {}, cam, pose, params, volume).ok());
    EXPECT_FALSE(Observed(volume, ahead));
  }
}

// Far returns add free space; they never erase a surface that readings in range put there (a
// thin leg seen up close would otherwise fade under the rays that pass it to a far wall).
TEST(Carving, ClearingLeavesFusedSurfacesAlone) {
  const PinholeCamera cam = test::RoomCamera();
  const Pose3f pose =
      LookAt(Eigen::Vector3f(1.0f, 0.03f, 0.01f), Eigen::Vector3f(2.f, 0.03f, 0.01f));
  TsdfVolume volume({kVoxel, kTrunc}), before({kVoxel, kTrunc});
  IntegrateParams params = CarveParams();
  const DepthImage near_depth = test::RenderRoomDepth(kRoom, cam, pose);
  for (TsdfVolume* v : {&volume, &before})
    ASSERT_TRUE(IntegrateFrame(near_depth, {}, cam, pose, params, *v).ok());
  // The wall 0.49 m ahead, then a frame whose returns all lie beyond a 2 m range (a room with
  // its walls 3 m off or more): it clears through where the wall was fused.
  const test::BoxRoom far_room{Eigen::Vector3f::Constant(-4.f), Eigen::Vector3f::Constant(4.f)};
  params.max_depth_m = 2.f;
  params.clear_beyond_max_depth = true;
  ASSERT_TRUE(
      IntegrateFrame(test::RenderRoomDepth(far_room, cam, pose), {}, cam, pose, params, volume)
          .ok());
  size_t surface = 0, cleared = 0;
  before.ForEachBlock([&](BlockIndex b, const TsdfBlock& old) {
    const TsdfBlock& now = *volume.FindBlock(b);
    for (int i = 0; i < kBlockVoxels; ++i) {
      if (old.weight[i] == 0) continue;
      if (old.tsdf[i] != int16_t(kTsdfScale)) {
        ++surface;  // near or behind the wall: untouched
        EXPECT_EQ(now.tsdf[i], old.tsdf[i]);
        EXPECT_EQ(now.weight[i], old.weight[i]);
      } else {
        cleared += now.weight[i] > old.weight[i];
      }
    }
  });
  EXPECT_GT(surface, 100u);
  EXPECT_GT(cleared, 100u);
}

TEST(Carving, RefusesANonPositiveRaySpacing) {
  const PinholeCamera cam = test::RoomCamera();
  const Pose3f pose = test::AxisViews(kEye)[0];
  TsdfVolume volume({kVoxel, kTrunc});
  IntegrateParams params = CarveParams();
  params.carve_ray_spacing_blocks = 0.f;
  const auto result =
      IntegrateFrame(test::RenderRoomDepth(kRoom, cam, pose), {}, cam, pose, params, volume);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("spacing"), std::string::npos);
}

}  // namespace
}  // namespace voxplan
