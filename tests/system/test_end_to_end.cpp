// End to end on real data: fuse ICL-NUIM with its ground-truth poses, then look at the model from
// fused frames' poses (Embree on the extracted mesh, and the TSDF raycaster) and compare with those
// frames' measured depth. Wrong poses,
// intrinsics (ICL's fy = -480) or frame conventions would move the surface by centimetres.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "core/raycast.h"
#include "fusion/integrate.h"
#include "fusion/mesh_extract.h"
#include "io/dataset.h"
#include "pipeline/fuse_dataset.h"
#include "sim/raycaster.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

// The fused surface agrees with each input depth map to a quarter of a voxel (median).
constexpr float kMaxMedianDepthErrorM = 0.005f;
constexpr float kMinAgreeingFraction = 0.9f;  // of pixels valid in both within 3 cm

struct FusedIcl {
  PinholeCamera camera;
  std::unique_ptr<TsdfVolume> volume;
  std::vector<Frame> checked;  // frames 10, 35 and 59
};

// The first 60 ICL-NUIM frames fused at 2 cm with ground-truth poses, once for all tests here.
const FusedIcl& FuseIcl() {
  static const FusedIcl fused = [] {
    FusedIcl f;
    auto dataset = OpenDataset((test::SharedDataDir() / "rgbd/iclnuim_office_traj0").string());
    EXPECT_TRUE(dataset.ok()) << dataset.status().message();
    if (!dataset.ok()) return f;
    f.camera = (*dataset)->info().camera;
    f.volume = std::make_unique<TsdfVolume>(VolumeParams{0.02f, 0.08f});
    std::vector<size_t> indices(60);
    for (size_t i = 0; i < indices.size(); ++i) indices[i] = i;
    FuseObserver observer;
    observer.integrated = [&](const Frame& frame, const Pose3f&, TsdfVolume&) {
      if (frame.index == 10 || frame.index == 35 || frame.index == 59) f.checked.push_back(frame);
      return Status::Ok();
    };
    Result<FuseReport> report = FuseDataset(**dataset, indices, {}, *f.volume, observer);
    EXPECT_TRUE(report.ok()) << report.status().message();
    EXPECT_EQ(f.checked.size(), 3u);
    return f;
  }();
  return fused;
}

// A depth image of the fused model at `frame`'s pose against what the frame measured.
void ExpectMatchesInputDepth(const DepthImage& fused_depth, const Frame& frame) {
  std::vector<float> errors;
  size_t agreeing = 0, in_range = 0;
  for (size_t p = 0; p < fused_depth.data.size(); ++p) {
    const float measured = frame.depth.data[p], fused = fused_depth.data[p];
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

// Mesh extraction, then Embree renders the mesh at each checked frame's pose.
TEST(EndToEnd, IclNuimFusedMeshMatchesTheInputDepth) {
  const FusedIcl& icl = FuseIcl();
  ASSERT_LT(icl.camera.fy, 0.f) << "ICL-NUIM needs its flipped y axis";
  ASSERT_EQ(icl.checked.size(), 3u);
  const Mesh mesh = ExtractMesh(*icl.volume);
  ASSERT_GT(mesh.num_triangles(), 10000u);
  auto raycaster = MeshRaycaster::Create(mesh);
  ASSERT_TRUE(raycaster.ok()) << raycaster.status().message();
  for (const Frame& frame : icl.checked)
    ExpectMatchesInputDepth((*raycaster)->Render(icl.camera, frame.T_W_C->cast<float>()).depth,
                            frame);
}

// The TSDF raycaster (what tracking and `render` use) at each checked frame's pose.
TEST(EndToEnd, IclNuimFusedMapRaycastMatchesTheInputDepth) {
  const FusedIcl& icl = FuseIcl();
  ASSERT_EQ(icl.checked.size(), 3u);
  for (const Frame& frame : icl.checked)
    ExpectMatchesInputDepth(Raycast(*icl.volume, icl.camera, frame.T_W_C->cast<float>()).depth,
                            frame);
}

// The AVX2 packet march against the scalar reference march on real, noisy data (crossings whose
// interpolant has no zero, back faces, unobserved gaps, restarts): the same bytes. Views from
// the checked poses and from between them, looking past the fused region too.
TEST(EndToEnd, IclNuimRaycastPacketsMatchTheScalarMarchExactly) {
  if (!RaycastSimdAvailable()) GTEST_SKIP() << "no AVX2 packets here: only the scalar march runs";
  const FusedIcl& icl = FuseIcl();
  ASSERT_EQ(icl.checked.size(), 3u);
  std::vector<Pose3f> poses;
  for (const Frame& frame : icl.checked) {
    const Pose3f T_W_C = frame.T_W_C->cast<float>();
    poses.push_back(T_W_C);
    Pose3f turned = T_W_C;  // a quarter turn about the camera's y axis
    turned.linear() = T_W_C.linear() * Eigen::AngleAxisf(1.5f, Eigen::Vector3f::UnitY()).matrix();
    poses.push_back(turned);
  }
  size_t hits = 0;
  for (const Pose3f& T_W_C : poses)
    for (const bool stop_at_back_faces : {true, false}) {
      RaycastParams packet_params;
      packet_params.stop_at_back_faces = stop_at_back_faces;
      RaycastParams scalar_params = packet_params;
      scalar_params.simd = false;
      const RaycastImages scalar = Raycast(*icl.volume, icl.camera, T_W_C, scalar_params);
      const RaycastImages packets = Raycast(*icl.volume, icl.camera, T_W_C, packet_params);
      test::ExpectSameImages(scalar, packets);
      hits += size_t(std::count(scalar.status.data.begin(), scalar.status.data.end(),
                                uint8_t(RayStatus::kHit)));
    }
  EXPECT_GT(hits, 600000u);  // the views see the model
}

}  // namespace
}  // namespace voxplan
