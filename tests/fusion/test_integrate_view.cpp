// IntegrateFrame over borrowed pixels (fusion/integrate_view.h) is the same integration as over
// owned images: the same blocks, bit for bit, and the same refusals.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "fusion/integrate.h"
#include "fusion/integrate_view.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

TEST(IntegrateView, ViewsFuseTheSameBitsAsImages) {
  const PinholeCamera cam = test::TestCamera(160, 120);
  const test::Sphere sphere{{0.1f, -0.05f, 1.2f}, 0.4f};
  for (bool carve : {false, true}) {
    IntegrateParams params;
    params.carve_free_space = carve;
    TsdfVolume owned({0.02f, 0.08f}), viewed({0.02f, 0.08f});
    for (float x : {-0.1f, 0.0f, 0.12f}) {
      const Pose3f T_W_C = LookAt({x, 0.05f, 0.0f}, sphere.c, -Eigen::Vector3f::UnitY());
      const DepthImage depth = test::RenderDepth(sphere, cam, T_W_C);
      ColorImage color(cam.width, cam.height);
      for (size_t i = 0; i < color.data.size(); ++i) color.data[i] = PackRgb(uint8_t(i), 80, 200);
      // Another owner's memory, as a numpy array would be: plain vectors, no alignment.
      const std::vector<float> depth_pixels(depth.data.begin(), depth.data.end());
      const std::vector<uint32_t> color_pixels(color.data.begin(), color.data.end());
      auto a = IntegrateFrame(depth, color, cam, T_W_C, params, owned);
      auto b = IntegrateFrame(ImageView<float>{depth_pixels.data(), cam.width, cam.height},
                              ImageView<uint32_t>{color_pixels.data(), cam.width, cam.height}, cam,
                              T_W_C, params, viewed);
      ASSERT_TRUE(a.ok() && b.ok());
      EXPECT_EQ(a->valid_pixels, b->valid_pixels);
      EXPECT_EQ(a->touched_blocks, b->touched_blocks);
    }
    const auto blocks = owned.SortedBlockIndices();
    ASSERT_EQ(blocks, viewed.SortedBlockIndices());
    ASSERT_GT(blocks.size(), 20u);
    size_t differing = 0;
    for (const BlockIndex& b : blocks)
      differing += std::memcmp(owned.FindBlock(b), viewed.FindBlock(b), sizeof(TsdfBlock)) != 0;
    EXPECT_EQ(differing, 0u) << "carve " << carve;
  }
}

TEST(IntegrateView, RefusesWhatImagesAreRefusedFor) {
  const PinholeCamera cam = test::TestCamera(160, 120);
  TsdfVolume volume({0.02f, 0.08f});
  const std::vector<float> depth(size_t(cam.width) * size_t(cam.height), 1.0f);
  const Pose3f T_W_C = Pose3f::Identity();
  auto small = IntegrateFrame(ImageView<float>{depth.data(), cam.width - 1, cam.height}, {}, cam,
                              T_W_C, {}, volume);
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.status().message().find("but the camera is 160x120"), std::string::npos);
  auto no_pixels =
      IntegrateFrame(ImageView<float>{nullptr, cam.width, cam.height}, {}, cam, T_W_C, {}, volume);
  ASSERT_FALSE(no_pixels.ok());
  EXPECT_EQ(no_pixels.status().message(), "depth image has no pixels");
  auto depth_only = IntegrateFrame(ImageView<float>{depth.data(), cam.width, cam.height},
                                   ImageView<uint32_t>{}, cam, T_W_C, {}, volume);
  EXPECT_TRUE(depth_only.ok());  // an empty colour view: depth only
  EXPECT_GT(volume.num_blocks(), 0u);
}

}  // namespace
}  // namespace voxplan
