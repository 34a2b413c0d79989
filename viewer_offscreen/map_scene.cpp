// MapScene: bounds from the allocated blocks, surface samples from the zero crossings, one
// core ray cast per view.
#include "viewer_offscreen/map_scene.h"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <utility>

#include "core/block.h"
#include "core/index.h"
#include "core/parallel.h"

namespace voxplan {

std::vector<Eigen::Vector3f> SurfaceCrossings(const TsdfVolume& volume, float min_weight,
                                              size_t max_samples) {
  const std::vector<BlockIndex> blocks = volume.SortedBlockIndices();
  // The ray caster's test (core/raycast/sampler.h): weight 0 is never observed.
  const uint32_t w_min = uint32_t(std::clamp(std::ceil(min_weight * kWeightScale), 1.f, 65536.f));
  const auto observed = [w_min](const TsdfBlock& block, int i) {
    return uint32_t(block.weight[i]) >= w_min;
  };
  // Which voxels of each block are crossings; the blocks are independent, so any split gives
  // the same bits.
  std::vector<std::bitset<kBlockVoxels>> crossing(blocks.size());
  ParallelFor(blocks.size(), 64, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const BlockIndex b = blocks[k];
      const TsdfBlock& block = *volume.FindBlock(b);
      const TsdfBlock* next[3] = {volume.FindBlock({b.x + 1, b.y, b.z}),
                                  volume.FindBlock({b.x, b.y + 1, b.z}),
                                  volume.FindBlock({b.x, b.y, b.z + 1})};
      for (int i = 0; i < kBlockVoxels; ++i) {
        if (!observed(block, i)) continue;
        const VoxelIndex v = VoxelOfLinear(i);
        const bool negative = block.tsdf[i] < 0;
        for (int axis = 0; axis < 3; ++axis) {
          int c[3] = {v.x, v.y, v.z};
          const TsdfBlock* other = &block;
          if (++c[axis] == kBlockSide) c[axis] = 0, other = next[axis];
          const int j = LinearIndex(c[0], c[1], c[2]);
          if (other && observed(*other, j) && (other->tsdf[j] < 0) != negative) {
            crossing[k].set(size_t(i));
            break;
          }
        }
      }
    }
  });
  size_t total = 0;
  for (const auto& bits : crossing) total += bits.count();
  const size_t stride =
      max_samples == 0 ? 1 : std::max<size_t>(1, (total + max_samples - 1) / max_samples);
  std::vector<Eigen::Vector3f> samples;
  samples.reserve(total / stride + 1);
  size_t n = 0;
  for (size_t k = 0; k < blocks.size(); ++k) {
    if (crossing[k].none()) continue;
    for (int i = 0; i < kBlockVoxels; ++i)
      if (crossing[k].test(size_t(i)) && n++ % stride == 0)
        samples.push_back(
            VoxelCenter(GlobalOf(blocks[k], VoxelOfLinear(i)), volume.voxel_size_m()));
  }
  return samples;
}

MapScene::MapScene(TsdfVolume volume, const MapSceneParams& params) : volume_(std::move(volume)) {
  params_.min_weight = params.min_weight;
  params_.simd = params.simd;
  params_.min_depth_m = params.near_m > 0.0f ? params.near_m : 0.01f;
  // From outside a room the walls' backs come first: look through them at the inside.
  params_.stop_at_back_faces = false;
  const float block_m = volume_.block_size_m();
  volume_.ForEachBlock([&](BlockIndex b, const TsdfBlock&) {
    const Eigen::Vector3f lo = BlockOrigin(b, block_m);
    bounds_.extend(lo);
    bounds_.extend(Eigen::Vector3f(lo + Eigen::Vector3f::Constant(block_m)));
  });
}

std::vector<Eigen::Vector3f> MapScene::SurfaceSamples() const {
  return SurfaceCrossings(volume_, params_.min_weight);
}

SurfaceImages MapScene::Render(const PinholeCamera& camera, const Pose3f& T_W_C) const {
  RaycastParams params = params_;
  // Far enough to reach every allocated block from this camera.
  float farthest_m = 0.0f;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3f corner = bounds_.corner(static_cast<Eigen::AlignedBox3f::CornerType>(c));
    farthest_m = std::max(farthest_m, (corner - T_W_C.translation()).norm());
  }
  params.max_depth_m = std::max(farthest_m, params.min_depth_m + 0.1f);
  RaycastImages r = Raycast(volume_, camera, T_W_C, params);
  SurfaceImages s;
  s.depth = std::move(r.depth);
  s.vertex_W = std::move(r.vertex_W);
  s.normal_W = std::move(r.normal_W);
  // A map fused without colour stores black: shade it neutral grey instead.
  bool any_colour = false;
  for (size_t i = 0; i < s.depth.data.size() && !any_colour; ++i)
    any_colour = s.depth.data[i] > 0.0f && (r.color.data[i] & 0xffffffu) != 0;
  if (any_colour) s.color = std::move(r.color);
  return s;
}

}  // namespace voxplan
