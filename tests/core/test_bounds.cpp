// The parameter ranges (core/bounds.h) and the volume's memory budget: out-of-range and NaN
// values are refused with the range in the message; past its budget the volume allocates no new
// block and its memory stays within the budget.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/bounds.h"
#include "core/volume.h"

namespace voxplan {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool Mentions(const Status& s, const std::string& text) {
  return s.message().find(text) != std::string::npos;
}

TEST(Bounds, CheckRangeRefusesNaNAndGivesTheRange) {
  EXPECT_TRUE(bounds::CheckRange("x", 0.5, 0.0, 1.0).ok());
  EXPECT_TRUE(bounds::CheckRange("x", 1.0, 0.0, 1.0).ok());
  const Status nan = bounds::CheckRange("x", kNaN, 0.0, 1.0, "m");
  EXPECT_FALSE(nan.ok());
  EXPECT_EQ(nan.message(), "x must be in [0, 1] m, got nan");
  EXPECT_FALSE(bounds::CheckRange("x", INFINITY, 0.0, 1.0).ok());
  EXPECT_FALSE(bounds::CheckRange("x", -1e-9, 0.0, 1.0).ok());
}

TEST(Bounds, VolumeParamsValidate) {
  EXPECT_TRUE((VolumeParams{0.01f, 0.04f}).Validate().ok());
  EXPECT_TRUE((VolumeParams{0.001f, 0.064f}).Validate().ok());
  for (float voxel : {1e-9f, 1e-4f, 2.f, kNaN, -0.01f}) {
    const Status s = VolumeParams{voxel, 0.04f}.Validate();
    EXPECT_FALSE(s.ok()) << voxel;
    EXPECT_TRUE(Mentions(s, "voxel size must be in [0.001, 1] m")) << s.message();
  }
  // 1000 m at 1 cm is 100000 voxels; half a voxel is less than one.
  for (float trunc : {1000.f, 0.005f, 0.65f, kNaN}) {
    const Status s = VolumeParams{0.01f, trunc}.Validate();
    EXPECT_FALSE(s.ok()) << trunc;
    EXPECT_TRUE(Mentions(s, "truncation must be in [1, 64] voxels")) << s.message();
  }
  EXPECT_TRUE((VolumeParams{0.01f, 0.04f, 1 << 20}).Validate().ok());
  const Status tiny = VolumeParams{0.01f, 0.04f, 4096}.Validate();
  EXPECT_TRUE(Mentions(tiny, "memory budget")) << tiny.message();
}

TEST(Bounds, IntrinsicsAgainstTheImageSize) {
  PinholeCamera c{640, 480, 525.f, 525.f, 319.5f, 239.5f};
  EXPECT_TRUE(bounds::CheckIntrinsics(c).ok());
  c.fy = -480.f;  // ICL-NUIM's flipped y axis is a valid camera
  EXPECT_TRUE(bounds::CheckIntrinsics(c).ok());
  PinholeCamera fx1 = c;
  fx1.fx = 1.f;  // a 179.6 degree field of view
  const Status s = bounds::CheckIntrinsics(fx1);
  EXPECT_TRUE(Mentions(s, "|fx| (image width 640) must be in [64, 64000] pixels")) << s.message();
  PinholeCamera off = c;
  off.cx = 5000.f;
  EXPECT_TRUE(Mentions(bounds::CheckIntrinsics(off), "cx must be in [0, 640]"));
  PinholeCamera nan = c;
  nan.cy = kNaN;
  EXPECT_FALSE(bounds::CheckIntrinsics(nan).ok());
  PinholeCamera huge = c;
  huge.width = 100000;
  EXPECT_TRUE(Mentions(bounds::CheckIntrinsics(huge), "[1, 16384]"));
  EXPECT_FALSE(bounds::CheckImageSize("size", 16384, 16384).ok());  // 2^28 pixels
  EXPECT_TRUE(bounds::CheckImageSize("size", 8192, 8192).ok());
}

// Blocks along a line, each new one within the budget until the budget refuses.
TEST(VolumeBudget, PastTheBudgetNoNewBlockAndMemoryStaysWithin) {
  const uint64_t budget = uint64_t(2) << 20;  // two pool chunks and a bit
  TsdfVolume volume(VolumeParams{0.01f, 0.04f, budget});
  size_t allocated = 0;
  for (int x = 0; x < 2000; ++x) {
    if (volume.AllocateWithinBudget(BlockIndex{x, 0, 0})) ++allocated;
    EXPECT_LE(volume.MemoryBytes(), budget);
  }
  EXPECT_EQ(allocated, volume.num_blocks());
  EXPECT_EQ(allocated, 512u);  // 2 chunks of 256 blocks: a third would pass 2 MiB
  EXPECT_EQ(volume.blocks_refused(), 2000u - allocated);
  // Existing blocks are still handed out past the budget.
  EXPECT_NE(volume.AllocateWithinBudget(BlockIndex{3, 0, 0}), nullptr);
  EXPECT_EQ(volume.blocks_refused(), 2000u - allocated);
  // The estimate covers what the volume holds: every block's voxels.
  EXPECT_GE(volume.MemoryBytes(), volume.num_blocks() * sizeof(TsdfBlock));
}

TEST(VolumeBudget, NoBudgetMeansNoLimit) {
  TsdfVolume volume(VolumeParams{0.01f, 0.04f});
  for (int x = 0; x < 600; ++x)
    ASSERT_NE(volume.AllocateWithinBudget(BlockIndex{x, 0, 0}), nullptr);
  EXPECT_EQ(volume.blocks_refused(), 0u);
}

}  // namespace
}  // namespace voxplan
