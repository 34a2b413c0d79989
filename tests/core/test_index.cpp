#include <gtest/gtest.h>

#include "core/index.h"

namespace voxplan {
namespace {

TEST(Index, FloorDivisionHandlesNegativeCoordinates) {
  EXPECT_EQ(BlockOf({-1, -8, -9}), (BlockIndex{-1, -1, -2}));
  EXPECT_EQ(BlockOf({0, 7, 8}), (BlockIndex{0, 0, 1}));
  EXPECT_EQ(LocalOf({-1, -8, -9}), (VoxelIndex{7, 0, 7}));
  EXPECT_EQ(VoxelAt(Eigen::Vector3f(-0.001f, 0.0f, 0.0199f), 0.01f), (GlobalVoxelIndex{-1, 0, 1}));
  EXPECT_EQ(BlockAt(Eigen::Vector3f(-0.001f, 0.079f, 0.081f), 0.08f), (BlockIndex{-1, 0, 1}));
}

TEST(Index, GlobalLocalRoundTrip) {
  for (int x = -20; x <= 20; x += 3)
    for (int y = -17; y <= 17; y += 5)
      for (int z = -9; z <= 9; ++z) {
        const GlobalVoxelIndex g{x, y, z};
        EXPECT_EQ(GlobalOf(BlockOf(g), LocalOf(g)), g);
      }
}

TEST(Index, LinearIndexRoundTripAndRowsAreContiguous) {
  for (int i = 0; i < kBlockVoxels; ++i) EXPECT_EQ(LinearIndex(VoxelOfLinear(i)), i);
  EXPECT_EQ(LinearIndex(1, 0, 0) - LinearIndex(0, 0, 0), 1);
}

TEST(Index, PackUnpackRoundTripIncludingExtremes) {
  const int32_t m = kMaxBlockCoord;
  for (BlockIndex b :
       {BlockIndex{0, 0, 0}, BlockIndex{-1, 2, -3}, BlockIndex{m, -m, m}, BlockIndex{-m, m, -1}}) {
    EXPECT_TRUE(InPackRange(b));
    EXPECT_EQ(UnpackBlockIndex(PackBlockIndex(b)), b);
  }
  EXPECT_FALSE(InPackRange(BlockIndex{m + 1, 0, 0}));
  EXPECT_NE(PackBlockIndex({-1, 0, 0}), PackBlockIndex({0, -1, 0}));
}

TEST(Index, VoxelCentreIsInsideItsVoxel) {
  const GlobalVoxelIndex g{-3, 4, -5};
  EXPECT_EQ(VoxelAt(VoxelCenter(g, 0.05f), 0.05f), g);
}

}  // namespace
}  // namespace voxplan
