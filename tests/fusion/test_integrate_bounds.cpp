// IntegrateFrame's entry checks and the memory budget: invalid params, volumes and intrinsics
// are refused with the range in the message; past the volume's budget a frame allocates no new
// block, counts the refused ones and updates only blocks that exist.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>

#include "fusion/integrate.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A wall 1 m in front of the camera, filling the image.
DepthImage Wall(const PinholeCamera& camera) {
  return test::RenderDepth(test::Plane{Eigen::Vector3f(0.f, 0.f, -1.f), -1.f}, camera,
                           Pose3f::Identity());
}

bool Mentions(const Status& s, const std::string& text) {
  return s.message().find(text) != std::string::npos;
}

TEST(IntegrateBounds, ParamsValidate) {
  EXPECT_TRUE(IntegrateParams{}.Validate().ok());
  IntegrateParams p;
  p.max_depth_m = 1e9f;
  EXPECT_TRUE(Mentions(p.Validate(), "max depth must be in [0, 100] m")) << p.Validate().message();
  p = {};
  p.min_depth_m = kNaN;
  EXPECT_TRUE(Mentions(p.Validate(), "min depth must be in [0, 100] m"));
  p = {};
  p.min_depth_m = 2.f;
  p.max_depth_m = 1.f;
  EXPECT_TRUE(Mentions(p.Validate(), "min < max"));
  p = {};
  p.max_weight = kNaN;
  EXPECT_TRUE(Mentions(p.Validate(), "max weight"));
  p.max_weight = 0.f;
  EXPECT_FALSE(p.Validate().ok());
}

TEST(IntegrateBounds, RefusesOutOfRangeVolumesAndIntrinsics) {
  const PinholeCamera camera = test::TestCamera();
  const DepthImage depth = Wall(camera);
  TsdfVolume fine(VolumeParams{0.0001f, 0.0004f});  // the constructor takes it; fusion must not
  Result<IntegrateStats> r =
      IntegrateFrame(depth, {}, camera, Pose3f::Identity(), IntegrateParams{}, fine);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(Mentions(r.status(), "voxel size must be in [0.001, 1] m")) << r.status().message();
  EXPECT_EQ(fine.num_blocks(), 0u);

  TsdfVolume deep(VolumeParams{0.01f, 1000.f});
  r = IntegrateFrame(depth, {}, camera, Pose3f::Identity(), IntegrateParams{}, deep);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(Mentions(r.status(), "[1, 64] voxels")) << r.status().message();

  PinholeCamera wide = camera;
  wide.fx = wide.fy = 1.f;
  TsdfVolume volume(VolumeParams{0.01f, 0.04f});
  r = IntegrateFrame(Wall(wide), {}, wide, Pose3f::Identity(), IntegrateParams{}, volume);
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(Mentions(r.status(), "|fx|")) << r.status().message();
  EXPECT_EQ(volume.num_blocks(), 0u);
}

TEST(IntegrateBounds, PastTheBudgetBlocksAreRefusedAndCounted) {
  const PinholeCamera camera = test::TestCamera();
  const DepthImage depth = Wall(camera);
  const VolumeParams unlimited{0.005f, 0.02f};
  TsdfVolume all(unlimited);
  Result<IntegrateStats> full =
      IntegrateFrame(depth, {}, camera, Pose3f::Identity(), IntegrateParams{}, all);
  ASSERT_TRUE(full.ok());
  ASSERT_GT(full->blocks_allocated, 256u);  // more than one pool chunk

  VolumeParams tight = unlimited;
  tight.max_memory_bytes = uint64_t(1) << 20;  // one chunk of 256 blocks
  TsdfVolume volume(tight);
  Result<IntegrateStats> r =
      IntegrateFrame(depth, {}, camera, Pose3f::Identity(), IntegrateParams{}, volume);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->blocks_allocated, 256u);
  EXPECT_EQ(r->blocks_refused, full->blocks_allocated - 256u);
  EXPECT_EQ(volume.num_blocks(), 256u);
  EXPECT_LE(volume.MemoryBytes(), tight.max_memory_bytes);
  // Only blocks that exist were updated, each exactly as without the budget.
  EXPECT_EQ(r->touched_blocks.size(), 256u);
  for (const BlockIndex& b : r->touched_blocks) {
    ASSERT_NE(volume.FindBlock(b), nullptr);
    EXPECT_EQ(std::memcmp(volume.FindBlock(b), all.FindBlock(b), sizeof(TsdfBlock)), 0);
  }
  // A second frame allocates nothing more and still updates the kept blocks.
  r = IntegrateFrame(depth, {}, camera, Pose3f::Identity(), IntegrateParams{}, volume);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->blocks_allocated, 0u);
  EXPECT_EQ(r->blocks_in_band, 256u);
  EXPECT_EQ(volume.num_blocks(), 256u);
}

}  // namespace
}  // namespace voxplan
