#include <gtest/gtest.h>

#include <stdexcept>

#include "core/queries.h"
#include "core/volume.h"

namespace voxplan {
namespace {

TEST(Volume, RefusesInvalidParameters) {
  EXPECT_THROW(TsdfVolume({0.0f, 0.04f}), std::invalid_argument);
  EXPECT_THROW(TsdfVolume({0.01f, 0.005f}), std::invalid_argument);
  EXPECT_NO_THROW(TsdfVolume({0.01f, 0.04f}));
}

TEST(Volume, CompactEncodingResolution) {
  // 16-bit TSDF: the worst rounding error is half a step of 1/32767 of the truncation.
  for (float t = -1.0f; t <= 1.0f; t += 0.001f)
    EXPECT_NEAR(DecodeTsdf(EncodeTsdf(t)), t, 0.5f / kTsdfScale + 1e-7f);
  for (float w = 0.0f; w <= 64.0f; w += 0.37f)
    EXPECT_NEAR(DecodeWeight(EncodeWeight(w)), w, 0.5f / kWeightScale + 1e-6f);
  EXPECT_EQ(TsdfVolume::BytesPerVoxel(), 7.0);
}

// Fills voxels with a linear field f(p) = a . p + c (in metres) and checks that trilinear
// interpolation and the gradient reproduce it exactly (up to the 16-bit step).
TEST(Queries, InterpolationAndGradientAreExactOnALinearField) {
  TsdfVolume volume({0.02f, 0.5f});
  const Eigen::Vector3f a(0.3f, -0.2f, 0.6f);
  const float c = 0.01f;
  for (int bz = -1; bz <= 0; ++bz)
    for (int by = -1; by <= 0; ++by)
      for (int bx = -1; bx <= 0; ++bx) {
        const BlockIndex b{bx, by, bz};
        TsdfBlock& block = volume.FindOrAllocate(b);
        for (int i = 0; i < kBlockVoxels; ++i) {
          const Eigen::Vector3f p = VoxelCenter(GlobalOf(b, VoxelOfLinear(i)), 0.02f);
          block.tsdf[i] = EncodeTsdf((a.dot(p) + c) / volume.trunc_m());
          block.weight[i] = EncodeWeight(2.0f);
          block.r[i] = 200;
        }
      }
  for (const Eigen::Vector3f& p :
       {Eigen::Vector3f(0.013f, -0.021f, 0.0f), Eigen::Vector3f(-0.1f, 0.05f, -0.033f)}) {
    const auto v = Interpolate(volume, p);
    ASSERT_TRUE(v.has_value());
    EXPECT_NEAR(v->tsdf_m, a.dot(p) + c, 1e-4f);
    EXPECT_NEAR(v->weight, 2.0f, 1e-5f);
    EXPECT_NEAR(v->rgb.x(), 200.0f, 1e-3f);
    const auto g = Gradient(volume, p);
    ASSERT_TRUE(g.has_value());
    EXPECT_LT((*g - a).norm(), 2e-3f);
  }
  // Outside the allocated blocks: no value, unobserved.
  EXPECT_FALSE(Interpolate(volume, Eigen::Vector3f(0.5f, 0.5f, 0.5f)).has_value());
  EXPECT_EQ(StateAt(volume, Eigen::Vector3f(0.5f, 0.5f, 0.5f)), VoxelState::kUnobserved);
  // Behind the surface (f = -2 cm, so every point of its voxel has f < 0): occupied; far in
  // front (f = +5 cm, over a voxel even at its corners): free.
  EXPECT_EQ(StateAt(volume, (-c - 0.02f) * a / a.squaredNorm()), VoxelState::kOccupied);
  EXPECT_EQ(StateAt(volume, (-c + 0.05f) * a / a.squaredNorm()), VoxelState::kFree);
}

TEST(Queries, StateDistinguishesFreeFromUnobserved) {
  TsdfVolume volume({0.05f, 0.2f});
  TsdfBlock& block = volume.FindOrAllocate({0, 0, 0});
  block.weight[0] = EncodeWeight(1.0f);  // tsdf stays +1: observed free space
  EXPECT_EQ(StateAt(volume, Eigen::Vector3f(0.01f, 0.01f, 0.01f)), VoxelState::kFree);
  EXPECT_EQ(StateAt(volume, Eigen::Vector3f(0.06f, 0.01f, 0.01f)), VoxelState::kUnobserved);
}

}  // namespace
}  // namespace voxplan
