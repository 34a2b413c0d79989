// End to end on real data: fuse ICL-NUIM with its ground-truth poses, extract the mesh, render
// it back at a fused frame's pose and compare with that frame's measured depth. Wrong poses,
// intrinsics (ICL's fy = -480) or frame conventions would move the surface by centimetres.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "io/dataset.h"
#include "sim/raycaster.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

// The fused surface agrees with each input depth map to a quarter of a voxel (median).
constexpr float kMaxMedianDepthErrorM = 0.005f;
constexpr float kMinAgreeingFraction = 0.9f;  // of pixels valid in both within 3 cm

TEST(EndToEnd, IclNuimFusedWithGroundTruthPosesMatchesTheInputDepth) {
  auto dataset = OpenDataset((test::SharedDataDir() / "rgbd/iclnuim_office_traj0").string());
  ASSERT_TRUE(dataset.ok()) << dataset.status().message();
  const PinholeCamera camera = (*dataset)->info().camera;
  ASSERT_LT(camera.fy, 0.f) << "ICL-NUIM needs its flipped y axis";

  TsdfVolume volume({0.02f, 0.08f});
  std::vector<Frame> checked;
  for (size_t i = 0; i < 60; ++i) {
    auto frame = (*dataset)->Load(i);
    ASSERT_TRUE(frame.ok()) << frame.status().message();
    if (!frame->T_W_C) continue;
    auto stats =
        IntegrateFrame(frame->depth, frame->color, camera, frame->T_W_C->cast<float>(), {}, volume);
    ASSERT_TRUE(stats.ok()) << stats.status().message();
    if (i == 10 || i == 35 || i == 59) checked.push_back(std::move(*frame));
  }
  const Mesh mesh = ExtractMesh(volume);
  ASSERT_GT(mesh.num_triangles(), 10000u);
  auto raycaster = MeshRaycaster::Create(mesh);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();

  ASSERT_EQ(checked.size(), 3u);
  for (const Frame& frame : checked) {
    const RenderOutput render = (*raycaster)->Render(camera, frame.T_W_C->cast<float>());
    std::vector<float> errors;
    size_t agreeing = 0, in_range = 0;
    for (size_t p = 0; p < render.depth.data.size(); ++p) {
      const float measured = frame.depth.data[p], fused = render.depth.data[p];
      if (!(measured > 0.1f && measured < 3.0f)) continue;
      ++in_range;
      if (fused <= 0.f) continue;
      errors.push_back(std::abs(measured - fused));
      agreeing += errors.back() < 0.03f;
    }
    // The fused surface covers what the frame measured within the fusion depth range.
    ASSERT_GT(errors.size(), in_range * 8 / 10) << "frame " << frame.index;
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    const float median = errors[errors.size() / 2];
    std::printf("frame %zu: %zu of %zu pixels covered, median |depth error| %.4f m\n", frame.index,
                errors.size(), in_range, median);
    EXPECT_LT(median, kMaxMedianDepthErrorM) << "frame " << frame.index;
    EXPECT_GT(float(agreeing) / float(errors.size()), kMinAgreeingFraction)
        << "frame " << frame.index;
  }
}

}  // namespace
}  // namespace voxplan
