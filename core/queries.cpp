#include "core/queries.h"

#include <cmath>

namespace voxplan {

std::optional<VoxelValue> VoxelAtIndex(const TsdfVolume& volume, GlobalVoxelIndex g) {
  const TsdfBlock* block = volume.FindBlock(BlockOf(g));
  if (!block) return std::nullopt;
  const int i = LinearIndex(LocalOf(g));
  return VoxelValue{DecodeTsdf(block->tsdf[i]) * volume.trunc_m(), DecodeWeight(block->weight[i]),
                    Eigen::Vector3f(block->r[i], block->g[i], block->b[i])};
}

std::optional<VoxelValue> VoxelAtPoint(const TsdfVolume& volume, const Eigen::Vector3f& p_W) {
  return VoxelAtIndex(volume, VoxelAt(p_W, volume.voxel_size_m()));
}

VoxelState StateAt(const TsdfVolume& volume, const Eigen::Vector3f& p_W,
                   const VoxelStateParams& params) {
  const GlobalVoxelIndex g = VoxelAt(p_W, volume.voxel_size_m());
  const TsdfBlock* block = volume.FindBlock(BlockOf(g));
  if (!block) return VoxelState::kUnobserved;
  const int i = LinearIndex(LocalOf(g));
  return ClassifyVoxel(block->tsdf[i], block->weight[i], volume.trunc_m() / volume.voxel_size_m(),
                       params);
}

std::optional<VoxelValue> Interpolate(const TsdfVolume& volume, const Eigen::Vector3f& p_W,
                                      float min_weight) {
  const float s = volume.voxel_size_m();
  // Continuous voxel coordinates with voxel centres at integers.
  const Eigen::Vector3f q = p_W / s - Eigen::Vector3f::Constant(0.5f);
  const GlobalVoxelIndex base{FloorToInt(q.x()), FloorToInt(q.y()), FloorToInt(q.z())};
  const Eigen::Vector3f f = q - Eigen::Vector3f(float(base.x), float(base.y), float(base.z));
  VoxelValue out;
  const TsdfBlock* cached = nullptr;
  BlockIndex cached_index{};
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = c >> 2;
    const GlobalVoxelIndex g{base.x + dx, base.y + dy, base.z + dz};
    const BlockIndex b = BlockOf(g);
    if (!cached || !(b == cached_index)) {
      cached = volume.FindBlock(b);
      cached_index = b;
    }
    if (!cached) return std::nullopt;
    const int i = LinearIndex(LocalOf(g));
    const float w = DecodeWeight(cached->weight[i]);
    if (w < min_weight || w == 0.f) return std::nullopt;
    const float t =
        (dx ? f.x() : 1.f - f.x()) * (dy ? f.y() : 1.f - f.y()) * (dz ? f.z() : 1.f - f.z());
    out.tsdf_m += t * DecodeTsdf(cached->tsdf[i]);
    out.weight += t * w;
    out.rgb += t * Eigen::Vector3f(cached->r[i], cached->g[i], cached->b[i]);
  }
  out.tsdf_m *= volume.trunc_m();
  return out;
}

std::optional<Eigen::Vector3f> Gradient(const TsdfVolume& volume, const Eigen::Vector3f& p_W) {
  const float h = volume.voxel_size_m();
  Eigen::Vector3f grad;
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::Vector3f d = Eigen::Vector3f::Zero();
    d[axis] = h;
    const auto plus = Interpolate(volume, p_W + d);
    const auto minus = Interpolate(volume, p_W - d);
    if (!plus || !minus) return std::nullopt;
    grad[axis] = (plus->tsdf_m - minus->tsdf_m) / (2.f * h);
  }
  return grad;
}

}  // namespace voxplan
