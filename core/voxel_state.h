#pragma once
// What a planner may know of a voxel, read off the TSDF: never observed, observed free, or
// occupied (at or behind a surface). Free space away from surfaces is carved into the TSDF by
// integration along each ray, so one rule here classifies every allocated voxel.
#include <cstdint>

#include "core/block.h"

namespace voxplan {

enum class VoxelState : uint8_t { kUnobserved = 0, kFree = 1, kOccupied = 2 };

struct VoxelStateParams {
  float min_weight = 0.5f;  // less fused weight than this counts as unobserved
  // Occupied when the signed distance is at most this many voxels: the voxel nearest a surface
  // on its free side, and everything observed behind it.
  float occupied_max_sdf_vox = 0.5f;
};

// trunc_vox = truncation distance / voxel size of the volume the voxel comes from.
inline VoxelState ClassifyVoxel(int16_t tsdf, uint16_t weight, float trunc_vox,
                                const VoxelStateParams& params) {
  if (DecodeWeight(weight) < params.min_weight) return VoxelState::kUnobserved;
  return DecodeTsdf(tsdf) * trunc_vox <= params.occupied_max_sdf_vox ? VoxelState::kOccupied
                                                                     : VoxelState::kFree;
}

}  // namespace voxplan
