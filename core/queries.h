#pragma once
// Point queries the rest of the engine needs: interpolated TSDF, weight, colour and gradient,
// and the discrete state of a voxel. All in world metres.
#include <Eigen/Core>
#include <optional>

#include "core/volume.h"
#include "core/voxel_state.h"

namespace voxplan {

struct VoxelValue {
  float tsdf_m = 0.f;  // signed distance, metres (truncated)
  float weight = 0.f;
  Eigen::Vector3f rgb = Eigen::Vector3f::Zero();  // 0..255
};

// The stored voxel containing p_W; nullopt when its block is not allocated.
std::optional<VoxelValue> VoxelAtPoint(const TsdfVolume& volume, const Eigen::Vector3f& p_W);
std::optional<VoxelValue> VoxelAtIndex(const TsdfVolume& volume, GlobalVoxelIndex g);

// The state of the voxel containing p_W by the one rule of core/voxel_state.h; unobserved
// where its block is not allocated.
VoxelState StateAt(const TsdfVolume& volume, const Eigen::Vector3f& p_W,
                   const VoxelStateParams& params = {});

// Trilinear interpolation over the 8 surrounding voxel centres; nullopt unless all 8 are
// observed with weight >= min_weight.
std::optional<VoxelValue> Interpolate(const TsdfVolume& volume, const Eigen::Vector3f& p_W,
                                      float min_weight = 1e-3f);
// Gradient of the interpolated TSDF by central differences (one voxel apart); points away
// from surfaces, so its normalisation is the outward surface normal.
std::optional<Eigen::Vector3f> Gradient(const TsdfVolume& volume, const Eigen::Vector3f& p_W);

}  // namespace voxplan
